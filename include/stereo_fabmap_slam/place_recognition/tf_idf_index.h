#pragma once

#include <utility>
#include <vector>

namespace stereo_fabmap_slam::place_recognition {

// A plain bag-of-words retrieval score, the baseline FAB-MAP is measured against: each image is
// a vector of term frequency (a word's share of the image's features) times inverse document
// frequency, normalised to unit length, and two images score the cosine of their vectors
// (0 = no word in common, 1 = the same word histogram). It knows nothing of word
// co-occurrence or of how likely a word is to be missed, which is what FAB-MAP adds.
class TfIdfIndex {
 public:
  // idf of each word from the training images' word sets: log((documents + 1) / (images with
  // the word + 1)). The +1s keep a word no training image showed finite (the largest weight)
  // and are negligible for the thousands of training images a vocabulary comes with.
  static std::vector<double> InverseDocumentFrequency(
      const std::vector<std::vector<int>>& training_word_sets, int vocabulary_size);

  // Throws std::invalid_argument for an empty vocabulary or a negative idf.
  explicit TfIdfIndex(std::vector<double> idf);

  // `words`: one word per feature of the image, repeats included (Vocabulary::Quantize).
  // Returns the image's index. Throws std::invalid_argument for a word outside the vocabulary.
  int Add(const std::vector<int>& words);
  // Cosine similarity of the query with every added image, by index.
  std::vector<double> Score(const std::vector<int>& words) const;

  int size() const { return images_; }
  int vocabulary_size() const { return static_cast<int>(idf_.size()); }

 private:
  // The unit-length tf-idf vector of an image, as (word, weight) for its non-zero weights.
  std::vector<std::pair<int, double>> Weigh(const std::vector<int>& words) const;

  std::vector<double> idf_;
  std::vector<std::vector<std::pair<int, float>>> inverted_;  // word -> (image, weight)
  int images_ = 0;
};

}  // namespace stereo_fabmap_slam::place_recognition
