#pragma once

#include <string>
#include <vector>

#include "stereo_fabmap_slam/io/option_reader.h"
#include "stereo_fabmap_slam/place_recognition/place_recognition_options.h"

namespace stereo_fabmap_slam::place_recognition {

// FAB-MAP's detector model: p(z | e), how often a word of the scene is seen in a view of it, and
// p(z | not e), how often a view shows a word the scene does not have (a false detection, or a
// descriptor quantised to a neighbouring word).
struct DetectorModel {
  static constexpr char kSection[] = "detector_model";

  double p_z_given_e = 0;
  double p_z_given_not_e = 0;
  int triples = 0;  // triples of views it was estimated from

  void Visit(io::OptionVisitor& visitor);
  void Validate() const;  // throws std::invalid_argument unless 0 <= not_e < e < 1
};

// Estimates the detector model from sequences of views (per sequence: each view's sorted
// distinct words, views in order, neighbours showing one place) by the method of moments. Over
// triples of neighbouring views (A, B, C), with V words and E of them in the scene:
//   m0 = V,  m1 = mean |A| = a E + b (V - E),  m2 = mean |A n B| = a^2 E + b^2 (V - E),
//   m3 = mean |A n B n C| = a^3 E + b^3 (V - E),
// a two-point measure whose points a = p(z | e) and b = p(z | not e) are the roots of
// t^2 + c1 t + c0 with m2 + c1 m1 + c0 m0 = 0 and m3 + c1 m2 + c0 m1 = 0. No word's rate is
// fixed by hand: the training views say how repeatable the words are.
// Throws std::invalid_argument when there are no triples or the moments admit no model with
// 0 <= b < a < 1 (views that share nothing, or as many words as the vocabulary).
DetectorModel EstimateDetectorModel(const std::vector<std::vector<std::vector<int>>>& sequences,
                                    int vocabulary_size);

// detector_model.yaml beside a vocabulary (train_fabmap writes it). Load throws io::InputError
// for a missing or malformed file.
void SaveDetectorModel(const DetectorModel& model, const std::string& path);
DetectorModel LoadDetectorModel(const std::string& path);

// `options` with the detector model in force: with detector_model trained, p_z_given_e and
// p_z_given_not_e from `vocabulary_directory`/detector_model.yaml (io::InputError if it is
// missing: train the vocabulary again, or choose fixed); with fixed, unchanged.
FabMapOptions ResolveDetectorModel(FabMapOptions options, const std::string& vocabulary_directory);

}  // namespace stereo_fabmap_slam::place_recognition
