// Speed and memory figures of place recognition for docs/benchmarks.md (make bench): Chow-Liu
// training at 10,000 words, quantisation, FAB-MAP 2.0 query time against map size, memory per
// place. Synthetic word data with fixed seeds: the figures depend on sizes, not on content.
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <numeric>
#include <random>
#include <set>
#include <stdexcept>
#include <vector>

#include "command_line.h"
#include "stereo_fabmap_slam/place_recognition/fab_map.h"
#include "stereo_fabmap_slam/place_recognition/sequence_score.h"
#include "stereo_fabmap_slam/place_recognition/vocabulary.h"

namespace {

using namespace stereo_fabmap_slam::place_recognition;  // NOLINT: a tool's main file
using Clock = std::chrono::steady_clock;

double Seconds(Clock::time_point since) {
  return std::chrono::duration<double>(Clock::now() - since).count();
}

double PeakResidentMegabytes() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_maxrss / 1024.0;
}

class RandomWords {
 public:
  RandomWords(int vocabulary, std::uint64_t seed) : random_(seed), word_(0, vocabulary - 1) {}
  std::vector<int> Set(int size) {
    std::set<int> words;
    while (static_cast<int>(words.size()) < size) words.insert(word_(random_));
    return {words.begin(), words.end()};
  }

 private:
  std::mt19937_64 random_;
  std::uniform_int_distribution<int> word_;
};

}  // namespace

constexpr char kUsage[] =
    "usage: benchmark_fabmap\n"
    "Times place recognition on synthetic words with fixed seeds (a few minutes): Chow-Liu\n"
    "training at 10,000 words, quantisation, FAB-MAP 2.0 queries against maps of 1,000 and\n"
    "100,000 places, memory per place. Prints the table of docs/benchmarks.md.\n";

int main(int argc, char** argv) {
  try {
    const stereo_fabmap_slam::tools::CommandLine args(argc, argv, {}, {"help"});
    if (args.Flag("help")) {
      std::fputs(kUsage, stdout);
      return 0;
    }
    if (!args.positional().empty()) throw std::invalid_argument("takes no arguments");
  } catch (const std::invalid_argument& error) {
    std::fprintf(stderr, "benchmark_fabmap: %s\n%s", error.what(), kUsage);
    return 2;
  }
  constexpr int kVocabulary = 10000;
  std::printf("| measurement | figure |\n| --- | --- |\n");

  // Chow-Liu tree: 10,000 words, 5,000 training images of 300 words each.
  RandomWords words(kVocabulary, 1);
  std::vector<std::vector<int>> training;
  for (int i = 0; i < 5000; ++i) training.push_back(words.Set(300));
  const double memory_before = PeakResidentMegabytes();
  auto start = Clock::now();
  const ChowLiuTree tree = ChowLiuTree::Train(training, kVocabulary);
  std::printf("| Chow-Liu tree, 10,000 words, 5,000 images of 300 words: time | %.1f s |\n",
              Seconds(start));
  std::printf("| Chow-Liu tree: peak memory added | %.0f MB |\n",
              PeakResidentMegabytes() - memory_before);

  // Quantisation: 1,000 BRISK-sized (64-byte) descriptors into a 10,000-word vocabulary.
  cv::Mat training_descriptors(100000, 64, CV_8U);
  cv::randu(training_descriptors, 0, 256);
  start = Clock::now();
  const Vocabulary vocabulary = Vocabulary::Train(training_descriptors, VocabularyOptions{});
  const double vocabulary_seconds = Seconds(start);
  cv::Mat query_descriptors(1000, 64, CV_8U);
  cv::randu(query_descriptors, 0, 256);
  start = Clock::now();
  constexpr int kRepeats = 50;
  for (int r = 0; r < kRepeats; ++r) vocabulary.WordSet(query_descriptors);
  std::printf("| vocabulary training, 100,000 descriptors -> %d words | %.1f s |\n",
              vocabulary.size(), vocabulary_seconds);
  std::printf("| quantising 1,000 binary descriptors into %d words | %.3f ms |\n",
              vocabulary.size(), Seconds(start) * 1000.0 / kRepeats);

  // FAB-MAP 2.0 queries: 1,000 words seen per image; maps of 1,000 and 100,000 places of 1,000
  // words each.
  // A share of the places is then observed a second time (as a revisit updates its place):
  // the query scores those apart from the rest, so their share costs time too.
  RandomWords query_words(kVocabulary, 3);
  std::vector<std::vector<int>> queries;
  for (int q = 0; q < 20; ++q) queries.push_back(query_words.Set(1000));
  const auto time_queries = [&](const PlaceDatabase& map, const char* what) {
    FabMap fabmap(tree, FabMapOptions{});
    fabmap.SetPlaces(map);
    fabmap.Compare(queries[0]);  // warm caches
    // Each query timed on its own: the mean and the slowest of them, as a table row.
    const auto time_each = [&](const char* label, const auto& run) {
      std::vector<double> times;
      for (const auto& query : queries) {
        const auto query_start = Clock::now();
        run(query);
        times.push_back(Seconds(query_start) * 1000.0);
      }
      std::printf(
          "| %s, %d places%s: mean (slowest of %zu) | %.2f ms (%.2f) |\n", label, map.size(), what,
          times.size(),
          std::accumulate(times.begin(), times.end(), 0.0) / static_cast<double>(times.size()),
          *std::max_element(times.begin(), times.end()));
    };
    time_each("FAB-MAP 2.0 query, 1,000 words seen",
              [&](const std::vector<int>& query) { fabmap.Compare(query); });
    // What the loop detector does per keyframe (loop_detection.sequence_length 5): the query,
    // each place's log odds and their chains over the last 5 queries.
    SequenceScore sequence({5, 3});
    time_each("the same with the sequence score of 5 queries", [&](const std::vector<int>& query) {
      const FabMapResult result = fabmap.Compare(query);
      std::vector<double> log_odds(result.log_likelihoods.size());
      for (std::size_t p = 0; p < log_odds.size(); ++p)
        log_odds[p] = result.CandidateLogOdds(static_cast<int>(p));
      sequence.Push(log_odds);
    });
  };
  for (const int places : {1000, 100000}) {
    PlaceDatabase map(kVocabulary);
    RandomWords place_words(kVocabulary, 2);
    for (int p = 0; p < places; ++p) map.AddPlace(place_words.Set(1000));
    time_queries(map, "");
    std::printf("| memory per place (1,000 words), %d places | %.0f bytes |\n", places,
                static_cast<double>(map.MemoryBytes()) / places);
    if (places != 100000) continue;
    for (const int percent : {1, 10}) {
      PlaceDatabase revisited = map;
      std::vector<std::vector<int>> views;
      for (int p = 0; p < places; p += 100 / percent) views.push_back(place_words.Set(1000));
      const auto update_start = Clock::now();
      for (std::size_t v = 0; v < views.size(); ++v)
        revisited.UpdatePlace(static_cast<int>(v) * (100 / percent), views[v]);
      std::printf(
          "| updating a place with a second view of 1,000 words, %d places, %d %% "
          "observed twice | %.2f ms |\n",
          places, percent, Seconds(update_start) * 1000.0 / views.size());
      char what[64];
      std::snprintf(what, sizeof(what), ", %d %% of them observed twice", percent);
      time_queries(revisited, what);
    }
  }
  // Memory per place follows the words it holds, not the vocabulary: what places 2,001 to
  // 4,000 add, index included. The empty index costs a fixed amount per vocabulary word.
  for (const int vocabulary_size : {10000, 100000}) {
    std::printf(
        "| empty index, per vocabulary word | %.0f bytes |\n",
        static_cast<double>(PlaceDatabase(vocabulary_size).MemoryBytes()) / vocabulary_size);
    for (const int place_size : {100, 1000}) {
      PlaceDatabase map(vocabulary_size);
      RandomWords place_words(vocabulary_size, 4);
      for (int p = 0; p < 2000; ++p) map.AddPlace(place_words.Set(place_size));
      const std::size_t before = map.MemoryBytes();
      for (int p = 0; p < 2000; ++p) map.AddPlace(place_words.Set(place_size));
      std::printf("| memory per place, %d words, vocabulary %d (index included) | %.0f bytes |\n",
                  place_size, vocabulary_size,
                  static_cast<double>(map.MemoryBytes() - before) / 2000);
    }
  }
  return 0;
}
