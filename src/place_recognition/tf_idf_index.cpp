#include "stereo_fabmap_slam/place_recognition/tf_idf_index.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>
#include <string>

namespace stereo_fabmap_slam::place_recognition {

std::vector<double> TfIdfIndex::InverseDocumentFrequency(
    const std::vector<std::vector<int>>& training_word_sets, int vocabulary_size) {
  if (vocabulary_size <= 0) throw std::invalid_argument("tf-idf: empty vocabulary");
  std::vector<int> documents_with(static_cast<std::size_t>(vocabulary_size), 0);
  for (const std::vector<int>& words : training_word_sets) {
    std::vector<int> unique(words);
    std::sort(unique.begin(), unique.end());
    unique.erase(std::unique(unique.begin(), unique.end()), unique.end());
    for (const int w : unique) {
      if (w < 0 || w >= vocabulary_size) {
        throw std::invalid_argument("tf-idf: training word " + std::to_string(w) +
                                    " outside the vocabulary");
      }
      ++documents_with[static_cast<std::size_t>(w)];
    }
  }
  const double documents = static_cast<double>(training_word_sets.size());
  std::vector<double> idf(static_cast<std::size_t>(vocabulary_size));
  for (std::size_t w = 0; w < idf.size(); ++w)
    idf[w] = std::log((documents + 1.0) / (documents_with[w] + 1.0));
  return idf;
}

TfIdfIndex::TfIdfIndex(std::vector<double> idf) : idf_(std::move(idf)), inverted_(idf_.size()) {
  if (idf_.empty()) throw std::invalid_argument("tf-idf: empty vocabulary");
  for (const double weight : idf_) {
    if (!(weight >= 0.0)) throw std::invalid_argument("tf-idf: idf must be >= 0");
  }
}

std::vector<std::pair<int, double>> TfIdfIndex::Weigh(const std::vector<int>& words) const {
  std::map<int, int> counts;
  for (const int w : words) {
    if (w < 0 || w >= vocabulary_size()) {
      throw std::invalid_argument("tf-idf: word " + std::to_string(w) + " outside the vocabulary");
    }
    ++counts[w];
  }
  std::vector<std::pair<int, double>> vector;
  double squared_norm = 0;
  for (const auto& [word, count] : counts) {
    // tf = count / features; the 1 / features factor cancels in the normalisation below.
    const double weight = count * idf_[static_cast<std::size_t>(word)];
    if (weight <= 0.0) continue;
    vector.emplace_back(word, weight);
    squared_norm += weight * weight;
  }
  const double norm = std::sqrt(squared_norm);
  for (auto& entry : vector) entry.second /= norm;
  return vector;
}

int TfIdfIndex::Add(const std::vector<int>& words) {
  const int image = images_++;
  for (const auto& [word, weight] : Weigh(words))
    inverted_[static_cast<std::size_t>(word)].emplace_back(image, static_cast<float>(weight));
  return image;
}

std::vector<double> TfIdfIndex::Score(const std::vector<int>& words) const {
  std::vector<double> scores(static_cast<std::size_t>(images_), 0.0);
  // Through the inverted index: only images sharing a word with the query are touched.
  for (const auto& [word, weight] : Weigh(words)) {
    for (const auto& [image, image_weight] : inverted_[static_cast<std::size_t>(word)])
      scores[static_cast<std::size_t>(image)] += weight * static_cast<double>(image_weight);
  }
  return scores;
}

}  // namespace stereo_fabmap_slam::place_recognition
