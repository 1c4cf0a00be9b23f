#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace stereo_fabmap_slam::place_recognition {

// The Chow-Liu tree of word occurrences (Chow & Liu 1968): the tree-shaped distribution closest
// (in KL divergence) to the joint distribution of the training images' binary word vectors. It
// is the maximum spanning tree of the pairwise mutual information; each word keeps its marginal
// and its conditional table given its parent.
class ChowLiuTree {
 public:
  // `word_sets`: per training image, its sorted distinct words (< vocabulary_size). Memory: one
  // 32-bit co-occurrence count per word pair (vocabulary_size^2 / 2); time: one mutual
  // information per pair (Prim's algorithm on the complete graph, computed on the fly).
  static ChowLiuTree Train(const std::vector<std::vector<int>>& word_sets, int vocabulary_size);

  int size() const { return static_cast<int>(parent_.size()); }
  int root() const { return root_; }
  int parent(int word) const { return parent_[static_cast<std::size_t>(word)]; }  // -1 for the root
  const std::vector<int>& children(int word) const {
    return children_[static_cast<std::size_t>(word)];
  }
  // p(z_word = 1): the probability that an image shows the word.
  double Marginal(int word) const { return marginal_[static_cast<std::size_t>(word)]; }
  // p(z_word = z | z_parent = z_parent); the root's is its marginal.
  double Conditional(int word, bool z, bool z_parent) const;
  int training_images() const { return training_images_; }

  void Save(const std::string& path) const;
  static ChowLiuTree Load(const std::string& path);
  bool operator==(const ChowLiuTree& other) const;

 private:
  void LinkChildren();

  int root_ = 0;
  int training_images_ = 0;
  std::vector<std::int32_t> parent_;
  std::vector<double> marginal_;
  std::vector<std::array<double, 2>> one_given_parent_;  // p(z = 1 | z_parent = 0 / 1)
  std::vector<std::vector<int>> children_;
};

}  // namespace stereo_fabmap_slam::place_recognition
