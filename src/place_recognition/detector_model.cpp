#include "stereo_fabmap_slam/place_recognition/detector_model.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iterator>
#include <stdexcept>

#include "stereo_fabmap_slam/io/input_error.h"
#include "stereo_fabmap_slam/io/options_file.h"

namespace stereo_fabmap_slam::place_recognition {
namespace {

int CommonWords(const std::vector<int>& a, const std::vector<int>& b) {
  int common = 0;
  auto i = a.begin(), j = b.begin();
  while (i != a.end() && j != b.end()) {
    if (*i < *j) {
      ++i;
    } else if (*j < *i) {
      ++j;
    } else {
      ++common, ++i, ++j;
    }
  }
  return common;
}

std::vector<int> Intersection(const std::vector<int>& a, const std::vector<int>& b) {
  std::vector<int> common;
  std::set_intersection(a.begin(), a.end(), b.begin(), b.end(), std::back_inserter(common));
  return common;
}

}  // namespace

void DetectorModel::Visit(io::OptionVisitor& visitor) {
  visitor.Visit("p_z_given_e", &p_z_given_e);
  visitor.Visit("p_z_given_not_e", &p_z_given_not_e);
  visitor.Visit("triples", &triples);
}

void DetectorModel::Validate() const {
  ValidateDetectorRates(p_z_given_e, p_z_given_not_e, "detector model");
}

DetectorModel EstimateDetectorModel(const std::vector<std::vector<std::vector<int>>>& sequences,
                                    int vocabulary_size) {
  double m1 = 0, m2 = 0, m3 = 0;
  int triples = 0;
  for (const std::vector<std::vector<int>>& views : sequences) {
    for (std::size_t i = 0; i + 2 < views.size(); ++i) {
      const std::vector<int>&a = views[i], &b = views[i + 1], &c = views[i + 2];
      m1 += (a.size() + b.size() + c.size()) / 3.0;
      const std::vector<int> ab = Intersection(a, b);
      m2 += (ab.size() + CommonWords(b, c) + CommonWords(a, c)) / 3.0;
      m3 += CommonWords(ab, c);
      ++triples;
    }
  }
  if (triples == 0) throw std::invalid_argument("detector model: no three views in a sequence");
  m1 /= triples, m2 /= triples, m3 /= triples;
  const double m0 = vocabulary_size;
  // [m1 m0; m2 m1] (c1, c0) = -(m2, m3), by Cramer's rule.
  const double det = m1 * m1 - m0 * m2;
  const std::string moments = " (mean words " + std::to_string(m1) + ", shared by two " +
                              std::to_string(m2) + ", by three " + std::to_string(m3) + ")";
  if (det == 0) throw std::invalid_argument("detector model: degenerate moments" + moments);
  const double c1 = (-m2 * m1 + m0 * m3) / det;
  const double c0 = (-m1 * m3 + m2 * m2) / det;
  const double discriminant = c1 * c1 - 4 * c0;
  if (!(discriminant >= 0))
    throw std::invalid_argument("detector model: moments without two rates" + moments);
  DetectorModel model;
  model.p_z_given_e = (-c1 + std::sqrt(discriminant)) / 2;
  model.p_z_given_not_e = std::max(0.0, (-c1 - std::sqrt(discriminant)) / 2);
  model.triples = triples;
  try {
    model.Validate();
  } catch (const std::invalid_argument& error) {
    throw std::invalid_argument(error.what() + moments + ": p_z_given_e " +
                                std::to_string(model.p_z_given_e) + ", p_z_given_not_e " +
                                std::to_string(model.p_z_given_not_e));
  }
  return model;
}

void SaveDetectorModel(const DetectorModel& model, const std::string& path) {
  std::ofstream file(path);
  file << "# FAB-MAP detector model estimated by train_fabmap from its training sequences\n";
  io::PrintOptions(model, file);
  if (!file) throw io::FileError(path, 0, "cannot write");
}

DetectorModel LoadDetectorModel(const std::string& path) {
  return io::OptionsFile::Load(path).Read<DetectorModel>();
}

FabMapOptions ResolveDetectorModel(FabMapOptions options, const std::string& vocabulary_directory) {
  if (options.detector_model == DetectorModelSource::kFixed) return options;
  const std::string path = vocabulary_directory + "/detector_model.yaml";
  if (!std::ifstream(path)) {
    throw io::FileError(path, 0,
                        "missing: fabmap.detector_model is trained, but this vocabulary has no "
                        "estimate (train it again with train_fabmap, or set detector_model: "
                        "fixed with p_z_given_e and p_z_given_not_e)");
  }
  const DetectorModel model = LoadDetectorModel(path);
  options.p_z_given_e = model.p_z_given_e;
  options.p_z_given_not_e = model.p_z_given_not_e;
  options.Validate();
  return options;
}

}  // namespace stereo_fabmap_slam::place_recognition
