#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "stereo_fabmap_slam/io/option_reader.h"
#include "stereo_fabmap_slam/place_recognition/place_recognition_options.h"

namespace stereo_fabmap_slam::place_recognition {

// Visual words: the leaves of a tree of cluster centres, learnt by clustering training descriptors
// level by level (hierarchical k-majority in Hamming space for binary descriptors, hierarchical
// k-means for float ones). Quantising a descriptor walks down the tree, comparing it with the
// `branching` centres of one node per level: branching x depth distances, not one per word.
class Vocabulary {
 public:
  // `descriptors`: one training descriptor per row, CV_8U (binary) or CV_32F (float).
  static Vocabulary Train(const cv::Mat& descriptors, const VocabularyOptions& options);

  int Quantize(const cv::Mat& descriptors, int row) const;      // word of one descriptor
  std::vector<int> Quantize(const cv::Mat& descriptors) const;  // word of every row
  // The image as FAB-MAP sees it: the sorted set of words that occur in it.
  std::vector<int> WordSet(const cv::Mat& descriptors) const;

  int size() const { return word_count_; }
  bool binary() const { return centres_.type() == CV_8U; }
  int descriptor_bytes() const { return static_cast<int>(centres_.cols * centres_.elemSize()); }

  // Versioned binary file with magic number and checksum; Load refuses bad files with a message.
  void Save(const std::string& path) const;
  static Vocabulary Load(const std::string& path);
  bool operator==(const Vocabulary& other) const;
  // A hash of the whole tree: two vocabularies with the same fingerprint quantise alike, so a map
  // saved with one can be used with the other.
  std::uint64_t Fingerprint() const;

 private:
  struct Node {
    std::int32_t first_child = -1;  // children are consecutive nodes
    std::int32_t child_count = 0;
    std::int32_t word = -1;  // leaves only
  };

  double Distance(const cv::Mat& descriptors, int row, int node) const;
  void Split(const cv::Mat& descriptors, const std::vector<int>& members, int node, int level,
             const VocabularyOptions& options, std::uint64_t seed);

  cv::Mat centres_;  // one row per node; the root's row is unused
  std::vector<Node> nodes_;
  int word_count_ = 0;
};

}  // namespace stereo_fabmap_slam::place_recognition
