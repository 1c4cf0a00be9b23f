#include "stereo_fabmap_slam/place_recognition/chow_liu_tree.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "stereo_fabmap_slam/io/binary_file.h"

namespace stereo_fabmap_slam::place_recognition {
namespace {

constexpr char kMagic[9] = "SFSCLTRE";
constexpr std::uint32_t kVersion = 1;

// Every probability estimated from counts is kept away from 0 and 1 (add-one smoothing and a
// clamp), so that no log-likelihood is ever infinite.
double Clamp(double p) { return std::clamp(p, 1e-6, 1.0 - 1e-6); }

// Mutual information of two binary variables from their counts in n samples.
double MutualInformation(double n, double count_a, double count_b, double count_ab) {
  const double p_a = Clamp((count_a + 0.5) / (n + 1)), p_b = Clamp((count_b + 0.5) / (n + 1));
  const double cells[4] = {count_ab, count_a - count_ab, count_b - count_ab,
                           n - count_a - count_b + count_ab};
  const double margins_a[4] = {p_a, p_a, 1 - p_a, 1 - p_a};
  const double margins_b[4] = {p_b, 1 - p_b, p_b, 1 - p_b};
  double information = 0;
  for (int c = 0; c < 4; ++c) {
    const double p = Clamp((cells[c] + 0.25) / (n + 1));
    information += p * std::log(p / (margins_a[c] * margins_b[c]));
  }
  return information;
}

}  // namespace

ChowLiuTree ChowLiuTree::Train(const std::vector<std::vector<int>>& word_sets,
                               int vocabulary_size) {
  if (vocabulary_size < 1) throw std::invalid_argument("Chow-Liu tree needs at least one word");
  if (word_sets.empty()) throw std::invalid_argument("Chow-Liu tree needs training images");
  const std::size_t v = static_cast<std::size_t>(vocabulary_size);
  std::vector<std::uint32_t> counts(v, 0);
  // Co-occurrences of pairs i < j, upper triangle row by row.
  const auto pair_index = [v](std::size_t i, std::size_t j) {
    return i * v - i * (i + 1) / 2 + (j - i - 1);
  };
  std::vector<std::uint32_t> together(v * (v - 1) / 2, 0);
  for (const std::vector<int>& words : word_sets) {
    for (std::size_t a = 0; a < words.size(); ++a) {
      const std::size_t i = static_cast<std::size_t>(words[a]);
      if (i >= v || (a > 0 && words[a] <= words[a - 1])) {
        throw std::invalid_argument(
            "word sets must be sorted, distinct and below the vocabulary size");
      }
      ++counts[i];
      for (std::size_t b = a + 1; b < words.size(); ++b)
        ++together[pair_index(i, static_cast<std::size_t>(words[b]))];
    }
  }
  const double n = static_cast<double>(word_sets.size());
  const auto co_count = [&](std::size_t i, std::size_t j) {
    return static_cast<double>(i < j ? together[pair_index(i, j)] : together[pair_index(j, i)]);
  };

  // Prim's maximum spanning tree, from the most frequent word.
  ChowLiuTree tree;
  tree.training_images_ = static_cast<int>(word_sets.size());
  tree.parent_.assign(v, -1);
  tree.root_ = static_cast<int>(std::max_element(counts.begin(), counts.end()) - counts.begin());
  std::vector<double> best(v, -std::numeric_limits<double>::infinity());
  std::vector<bool> in_tree(v, false);
  std::size_t added = static_cast<std::size_t>(tree.root_);
  in_tree[added] = true;
  for (std::size_t step = 1; step < v; ++step) {
    std::size_t next = v;
    for (std::size_t u = 0; u < v; ++u) {
      if (in_tree[u]) continue;
      const double information = MutualInformation(n, counts[added], counts[u], co_count(added, u));
      if (information > best[u]) {
        best[u] = information;
        tree.parent_[u] = static_cast<std::int32_t>(added);
      }
      if (next == v || best[u] > best[next]) next = u;
    }
    in_tree[next] = true;
    added = next;
  }

  tree.marginal_.resize(v);
  tree.one_given_parent_.resize(v);
  for (std::size_t i = 0; i < v; ++i) {
    tree.marginal_[i] = Clamp((counts[i] + 1.0) / (n + 2.0));
    if (tree.parent_[i] < 0) {
      tree.one_given_parent_[i] = {tree.marginal_[i], tree.marginal_[i]};
      continue;
    }
    const std::size_t p = static_cast<std::size_t>(tree.parent_[i]);
    const double both = co_count(i, p);
    tree.one_given_parent_[i] = {Clamp((counts[i] - both + 1.0) / (n - counts[p] + 2.0)),
                                 Clamp((both + 1.0) / (counts[p] + 2.0))};
  }
  tree.LinkChildren();
  return tree;
}

void ChowLiuTree::LinkChildren() {
  children_.assign(parent_.size(), {});
  for (std::size_t i = 0; i < parent_.size(); ++i) {
    if (parent_[i] >= 0)
      children_[static_cast<std::size_t>(parent_[i])].push_back(static_cast<int>(i));
  }
}

double ChowLiuTree::Conditional(int word, bool z, bool z_parent) const {
  const double one = one_given_parent_[static_cast<std::size_t>(word)][z_parent ? 1 : 0];
  return z ? one : 1.0 - one;
}

void ChowLiuTree::Save(const std::string& path) const {
  io::BinaryWriter writer;
  writer.Put<std::int32_t>(root_);
  writer.Put<std::int32_t>(training_images_);
  writer.PutVector(parent_);
  writer.PutVector(marginal_);
  writer.PutVector(one_given_parent_);
  io::WriteBinaryFile(path, kMagic, kVersion, writer.bytes());
}

ChowLiuTree ChowLiuTree::Load(const std::string& path) {
  io::BinaryReader reader = io::ReadBinaryFile(path, kMagic, kVersion);
  ChowLiuTree tree;
  tree.root_ = reader.Get<std::int32_t>();
  tree.training_images_ = reader.Get<std::int32_t>();
  tree.parent_ = reader.GetVector<std::int32_t>();
  tree.marginal_ = reader.GetVector<double>();
  tree.one_given_parent_ = reader.GetVector<std::array<double, 2>>();
  reader.ExpectEnd();
  const std::size_t v = tree.parent_.size();
  if (v == 0 || tree.marginal_.size() != v || tree.one_given_parent_.size() != v ||
      tree.root_ < 0 || static_cast<std::size_t>(tree.root_) >= v ||
      tree.parent_[static_cast<std::size_t>(tree.root_)] != -1) {
    reader.Fail("inconsistent tree");
  }
  for (std::size_t i = 0; i < v; ++i) {
    const bool root = static_cast<int>(i) == tree.root_;
    if (root != (tree.parent_[i] < 0) || tree.parent_[i] >= static_cast<std::int32_t>(v))
      reader.Fail("bad parent");
  }
  tree.LinkChildren();
  return tree;
}

bool ChowLiuTree::operator==(const ChowLiuTree& other) const {
  return root_ == other.root_ && training_images_ == other.training_images_ &&
         parent_ == other.parent_ && marginal_ == other.marginal_ &&
         one_given_parent_ == other.one_given_parent_;
}

}  // namespace stereo_fabmap_slam::place_recognition
