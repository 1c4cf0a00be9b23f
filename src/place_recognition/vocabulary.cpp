#include "stereo_fabmap_slam/place_recognition/vocabulary.h"

#include <algorithm>
#include <limits>
#include <random>
#include <stdexcept>

#include <opencv2/core/hal/hal.hpp>

#include "stereo_fabmap_slam/io/binary_file.h"

namespace stereo_fabmap_slam::place_recognition {
namespace {

constexpr char kVocabularyMagic[9] = "SFSVOCAB";
constexpr std::uint32_t kVocabularyVersion = 1;

// Clusters the rows `members` of `data` into at most k groups; returns each member's group and
// fills `centres` (one row per group). Binary rows: k-majority (Hamming distance, bitwise
// majority centres); float rows: k-means. Seeding picks far-apart rows (k-means++ style).
std::vector<int> Cluster(const cv::Mat& data, const std::vector<int>& members, int k,
                         int iterations, std::uint64_t seed, cv::Mat* centres) {
  const bool binary = data.type() == CV_8U;
  const int n = static_cast<int>(members.size());
  std::mt19937_64 random(seed);
  const auto distance = [&](const cv::Mat& a, int i, const cv::Mat& b, int j) {
    if (binary)
      return static_cast<double>(
          cv::hal::normHamming(a.ptr<std::uint8_t>(i), b.ptr<std::uint8_t>(j), a.cols));
    return cv::norm(a.row(i), b.row(j), cv::NORM_L2);
  };
  // Seeding: the first centre at random, each next one with probability ~ squared distance.
  std::vector<int> seeds = {members[std::uniform_int_distribution<int>(0, n - 1)(random)]};
  std::vector<double> nearest(static_cast<std::size_t>(n), std::numeric_limits<double>::max());
  while (static_cast<int>(seeds.size()) < k) {
    double total = 0;
    for (int m = 0; m < n; ++m) {
      nearest[m] = std::min(nearest[m], distance(data, members[m], data, seeds.back()));
      total += nearest[m] * nearest[m];
    }
    if (total == 0) break;  // fewer distinct rows than k
    double pick = std::uniform_real_distribution<double>(0, total)(random);
    int chosen = n - 1;
    for (int m = 0; m < n; ++m) {
      pick -= nearest[m] * nearest[m];
      if (pick <= 0) {
        chosen = m;
        break;
      }
    }
    seeds.push_back(members[chosen]);
  }
  k = static_cast<int>(seeds.size());
  *centres = cv::Mat(k, data.cols, data.type());
  for (int c = 0; c < k; ++c) data.row(seeds[c]).copyTo(centres->row(c));

  std::vector<int> labels(static_cast<std::size_t>(n), -1);
  for (int iteration = 0; iteration < iterations; ++iteration) {
    bool changed = false;
    for (int m = 0; m < n; ++m) {
      int best = 0;
      double best_distance = std::numeric_limits<double>::max();
      for (int c = 0; c < k; ++c) {
        const double d = distance(data, members[m], *centres, c);
        if (d < best_distance) {
          best_distance = d;
          best = c;
        }
      }
      changed |= labels[m] != best;
      labels[m] = best;
    }
    if (!changed) break;
    // New centres: bitwise majority (binary) or mean (float) of the members; an empty cluster
    // keeps its centre.
    if (binary) {
      // One pass over the members counts the set bits of every cluster.
      const int bits = data.cols * 8;
      std::vector<int> ones(static_cast<std::size_t>(k) * bits, 0),
          counts(static_cast<std::size_t>(k), 0);
      for (int m = 0; m < n; ++m) {
        int* cluster_ones = &ones[static_cast<std::size_t>(labels[m]) * bits];
        ++counts[labels[m]];
        const std::uint8_t* row = data.ptr<std::uint8_t>(members[m]);
        for (int bit = 0; bit < bits; ++bit) cluster_ones[bit] += (row[bit >> 3] >> (bit & 7)) & 1;
      }
      for (int c = 0; c < k; ++c) {
        if (counts[c] == 0) continue;
        std::uint8_t* centre = centres->ptr<std::uint8_t>(c);
        std::fill(centre, centre + data.cols, 0);
        for (int bit = 0; bit < bits; ++bit) {
          if (2 * ones[static_cast<std::size_t>(c) * bits + bit] > counts[c]) {
            centre[bit >> 3] |= static_cast<std::uint8_t>(1 << (bit & 7));
          }
        }
      }
      continue;
    }
    for (int c = 0; c < k; ++c) {
      {
        cv::Mat sum = cv::Mat::zeros(1, data.cols, CV_64F);
        int count = 0;
        for (int m = 0; m < n; ++m) {
          if (labels[m] != c) continue;
          ++count;
          cv::Mat row;
          data.row(members[m]).convertTo(row, CV_64F);
          sum += row;
        }
        if (count > 0) cv::Mat(sum / count).convertTo(centres->row(c), CV_32F);
      }
    }
  }
  return labels;
}

}  // namespace

Vocabulary Vocabulary::Train(const cv::Mat& descriptors, const VocabularyOptions& options) {
  options.Validate();
  if (descriptors.empty() || (descriptors.type() != CV_8U && descriptors.type() != CV_32F)) {
    throw std::invalid_argument(
        "vocabulary training needs CV_8U or CV_32F descriptors, one per row");
  }
  Vocabulary vocabulary;
  vocabulary.centres_ = cv::Mat(1, descriptors.cols, descriptors.type(), cv::Scalar(0));  // root
  vocabulary.nodes_.resize(1);
  std::vector<int> all(static_cast<std::size_t>(descriptors.rows));
  for (int i = 0; i < descriptors.rows; ++i) all[i] = i;
  vocabulary.Split(descriptors, all, 0, 0, options, static_cast<std::uint64_t>(options.seed));
  return vocabulary;
}

void Vocabulary::Split(const cv::Mat& descriptors, const std::vector<int>& members, int node,
                       int level, const VocabularyOptions& options, std::uint64_t seed) {
  if (level == options.depth || static_cast<int>(members.size()) <= options.branching) {
    nodes_[node].word = word_count_++;
    return;
  }
  cv::Mat centres;
  const std::vector<int> labels =
      Cluster(descriptors, members, options.branching, options.iterations,
              seed * 7919 + static_cast<std::uint64_t>(node), &centres);
  const int first = static_cast<int>(nodes_.size());
  nodes_[node].first_child = first;
  nodes_[node].child_count = centres.rows;
  nodes_.resize(nodes_.size() + static_cast<std::size_t>(centres.rows));
  centres_.push_back(centres);
  for (int c = 0; c < centres.rows; ++c) {
    std::vector<int> child_members;
    for (std::size_t m = 0; m < members.size(); ++m) {
      if (labels[m] == c) child_members.push_back(members[m]);
    }
    if (child_members.empty()) {
      nodes_[first + c].word = word_count_++;  // a centre nobody chose still is a word
    } else {
      Split(descriptors, child_members, first + c, level + 1, options, seed);
    }
  }
}

double Vocabulary::Distance(const cv::Mat& descriptors, int row, int node) const {
  if (binary()) {
    return cv::hal::normHamming(descriptors.ptr<std::uint8_t>(row),
                                centres_.ptr<std::uint8_t>(node), centres_.cols);
  }
  const float* a = descriptors.ptr<float>(row);
  const float* b = centres_.ptr<float>(node);
  double sum = 0;
  for (int i = 0; i < centres_.cols; ++i) sum += (a[i] - b[i]) * (a[i] - b[i]);
  return sum;
}

int Vocabulary::Quantize(const cv::Mat& descriptors, int row) const {
  if (descriptors.type() != centres_.type() || descriptors.cols != centres_.cols) {
    throw std::invalid_argument("descriptors do not match the vocabulary (type or length)");
  }
  int node = 0;
  while (nodes_[node].word < 0) {
    const Node& n = nodes_[node];
    int best = n.first_child;
    double best_distance = std::numeric_limits<double>::max();
    for (int c = n.first_child; c < n.first_child + n.child_count; ++c) {
      const double d = Distance(descriptors, row, c);
      if (d < best_distance) {
        best_distance = d;
        best = c;
      }
    }
    node = best;
  }
  return nodes_[node].word;
}

std::vector<int> Vocabulary::Quantize(const cv::Mat& descriptors) const {
  std::vector<int> words(static_cast<std::size_t>(descriptors.rows));
  for (int i = 0; i < descriptors.rows; ++i) words[i] = Quantize(descriptors, i);
  return words;
}

std::vector<int> Vocabulary::WordSet(const cv::Mat& descriptors) const {
  std::vector<int> words = Quantize(descriptors);
  std::sort(words.begin(), words.end());
  words.erase(std::unique(words.begin(), words.end()), words.end());
  return words;
}

std::uint64_t Vocabulary::Fingerprint() const {
  const cv::Mat continuous = centres_.isContinuous() ? centres_ : centres_.clone();
  std::vector<std::uint8_t> bytes(continuous.data,
                                  continuous.data + continuous.total() * continuous.elemSize());
  const auto* nodes = reinterpret_cast<const std::uint8_t*>(nodes_.data());
  bytes.insert(bytes.end(), nodes, nodes + nodes_.size() * sizeof(Node));
  return io::Fnv1a64(bytes.data(), bytes.size()) ^ static_cast<std::uint64_t>(word_count_);
}

void Vocabulary::Save(const std::string& path) const {
  io::BinaryWriter writer;
  writer.Put<std::int32_t>(centres_.type());
  writer.Put<std::int32_t>(centres_.rows);
  writer.Put<std::int32_t>(centres_.cols);
  const cv::Mat continuous = centres_.isContinuous() ? centres_ : centres_.clone();
  writer.PutVector(std::vector<std::uint8_t>(
      continuous.data, continuous.data + continuous.total() * continuous.elemSize()));
  writer.PutVector(nodes_);
  writer.Put<std::int32_t>(word_count_);
  io::WriteBinaryFile(path, kVocabularyMagic, kVocabularyVersion, writer.bytes());
}

Vocabulary Vocabulary::Load(const std::string& path) {
  io::BinaryReader reader = io::ReadBinaryFile(path, kVocabularyMagic, kVocabularyVersion);
  Vocabulary vocabulary;
  const auto type = reader.Get<std::int32_t>();
  const auto rows = reader.Get<std::int32_t>();
  const auto cols = reader.Get<std::int32_t>();
  if ((type != CV_8U && type != CV_32F) || rows < 1 || cols < 1)
    reader.Fail("bad centre matrix header");
  const std::vector<std::uint8_t> data = reader.GetVector<std::uint8_t>();
  // The header's size must match the data read before anything of that size is allocated: a
  // corrupt header must not ask for gigabytes.
  const std::uint64_t element_bytes = type == CV_8U ? 1 : 4;
  if (static_cast<std::uint64_t>(rows) * static_cast<std::uint64_t>(cols) * element_bytes !=
      data.size()) {
    reader.Fail("centre data size");
  }
  vocabulary.centres_ = cv::Mat(rows, cols, type);
  std::memcpy(vocabulary.centres_.data, data.data(), data.size());
  vocabulary.nodes_ = reader.GetVector<Node>();
  vocabulary.word_count_ = reader.Get<std::int32_t>();
  reader.ExpectEnd();
  // The tree must be consistent before it is used: a corrupt index must not crash a query.
  if (vocabulary.nodes_.size() != static_cast<std::size_t>(rows))
    reader.Fail("node count differs from centres");
  for (const Node& node : vocabulary.nodes_) {
    const bool leaf = node.word >= 0;
    if (leaf ? node.word >= vocabulary.word_count_
             : (node.first_child <= 0 || node.child_count <= 0 ||
                node.first_child + node.child_count > rows)) {
      reader.Fail("inconsistent tree");
    }
  }
  return vocabulary;
}

bool Vocabulary::operator==(const Vocabulary& other) const {
  if (word_count_ != other.word_count_ || nodes_.size() != other.nodes_.size() ||
      centres_.type() != other.centres_.type() || centres_.size() != other.centres_.size()) {
    return false;
  }
  for (std::size_t i = 0; i < nodes_.size(); ++i) {
    const Node &a = nodes_[i], &b = other.nodes_[i];
    if (a.first_child != b.first_child || a.child_count != b.child_count || a.word != b.word)
      return false;
  }
  return cv::norm(centres_, other.centres_, cv::NORM_INF) == 0;
}

}  // namespace stereo_fabmap_slam::place_recognition
