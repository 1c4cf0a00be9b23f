// Place recognition: Chow-Liu trees, the FAB-MAP posterior, its two formulations, real images,
// and the files.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <numeric>
#include <random>
#include <set>

#include <gtest/gtest.h>
#include <opencv2/features2d.hpp>

#include "file_mutations.h"
#include "stereo_fabmap_slam/datasets/camera_renderer.h"
#include "stereo_fabmap_slam/datasets/euroc_sequence.h"
#include "stereo_fabmap_slam/datasets/hall_scene.h"
#include "stereo_fabmap_slam/datasets/route.h"
#include "stereo_fabmap_slam/datasets/synthetic_sequence.h"
#include "stereo_fabmap_slam/datasets/texture_library.h"
#include "stereo_fabmap_slam/io/input_error.h"
#include "stereo_fabmap_slam/io/options_file.h"
#include "stereo_fabmap_slam/place_recognition/detector_model.h"
#include "stereo_fabmap_slam/place_recognition/fab_map.h"
#include "stereo_fabmap_slam/place_recognition/image_describer.h"
#include "stereo_fabmap_slam/place_recognition/place_recognition_options.h"
#include "stereo_fabmap_slam/place_recognition/vocabulary.h"
#include "test_support.h"

namespace stereo_fabmap_slam::test {
namespace {

using namespace place_recognition;  // NOLINT: the module under test

// Samples of a known tree-shaped distribution over 8 binary words: each word copies its
// parent with probability 0.9 (flips otherwise); the root is on half the time.
std::vector<std::vector<int>> SampleTree(const std::vector<int>& parents, int samples,
                                         std::uint64_t seed) {
  std::mt19937_64 random(seed);
  std::uniform_real_distribution<double> unit(0, 1);
  std::vector<std::vector<int>> sets;
  for (int s = 0; s < samples; ++s) {
    std::vector<int> value(parents.size());
    for (std::size_t w = 0; w < parents.size(); ++w) {  // parents come before children
      value[w] = parents[w] < 0 ? unit(random) < 0.5
                                : (unit(random) < 0.9 ? value[parents[w]] : 1 - value[parents[w]]);
    }
    std::vector<int> set;
    for (std::size_t w = 0; w < value.size(); ++w) {
      if (value[w]) set.push_back(static_cast<int>(w));
    }
    sets.push_back(set);
  }
  return sets;
}

// Sets of distinct random words, sorted, from a seeded generator.
class RandomWordSets {
 public:
  RandomWordSets(int vocabulary, std::uint64_t seed) : random_(seed), word_(0, vocabulary - 1) {}
  std::vector<int> Next(int size) {
    std::set<int> words;
    while (static_cast<int>(words.size()) < size) words.insert(word_(random_));
    return {words.begin(), words.end()};
  }

 private:
  std::mt19937_64 random_;
  std::uniform_int_distribution<int> word_;
};

std::set<std::pair<int, int>> Edges(const std::vector<int>& parents) {
  std::set<std::pair<int, int>> edges;
  for (std::size_t w = 0; w < parents.size(); ++w) {
    if (parents[w] >= 0) edges.insert({std::min<int>(w, parents[w]), std::max<int>(w, parents[w])});
  }
  return edges;
}

TEST(ChowLiuTree, RecoversTheTreeSamplesWereDrawnFrom) {
  const std::vector<int> parents = {-1, 0, 0, 1, 1, 2, 5, 3};
  const ChowLiuTree tree = ChowLiuTree::Train(SampleTree(parents, 4000, 11), 8);
  std::vector<int> learnt;
  for (int w = 0; w < 8; ++w) learnt.push_back(tree.parent(w));
  EXPECT_EQ(Edges(learnt), Edges(parents));
  // Conditionals: a child equals its parent 90 % of the time (4,000 samples: +-1.5 % at 3 sigma).
  for (int w = 0; w < 8; ++w) {
    if (tree.parent(w) < 0) continue;
    EXPECT_NEAR(tree.Conditional(w, true, true), 0.9, 0.03) << w;
    EXPECT_NEAR(tree.Conditional(w, true, false), 0.1, 0.03) << w;
  }
}

// A small model: 6 words, 60 training images drawn from a known tree.
ChowLiuTree ToyTree() { return ChowLiuTree::Train(SampleTree({-1, 0, 0, 1, 2, 2}, 60, 5), 6); }

// p(z_q = z | e_q = e, z_p = zp) from the model's one assumption, not from its closed form: the
// reading z of word q depends on the scene element e and on its parent word's reading z_p, and
// e and z_p are independent given z (Cummins & Newman 2008). So the joint is
// p(z, e, z_p) = p(z) p(e | z) p(z_p | z), with p(e | z) and p(z_p | z) turned around by Bayes
// from what the model gives (the detector model p(z | e), the tree's p(z | z_p)), and the
// conditional is that joint normalised over z. The priors of e and z_p this needs cancel:
// `prior_e` and `prior_parent` may be anything in (0, 1).
double ZGivenElementAndParent(const ChowLiuTree& tree, const FabMapOptions& o, int q, bool z,
                              bool e, bool zp, double prior_e, double prior_parent) {
  const auto p_z = [&](bool reading) { return reading ? tree.Marginal(q) : 1 - tree.Marginal(q); };
  const auto p_z_given_e = [&](bool reading, bool element) {
    const double seen = element ? o.p_z_given_e : o.p_z_given_not_e;
    return reading ? seen : 1 - seen;
  };
  const auto p_e_given_z = [&](bool element, bool reading) {
    return p_z_given_e(reading, element) * (element ? prior_e : 1 - prior_e) / p_z(reading);
  };
  const auto p_parent_given_z = [&](bool parent, bool reading) {
    return tree.Conditional(q, reading, parent) * (parent ? prior_parent : 1 - prior_parent) /
           p_z(reading);
  };
  const auto joint = [&](bool reading) {
    return p_z(reading) * p_e_given_z(e, reading) * p_parent_given_z(zp, reading);
  };
  return joint(z) / (joint(true) + joint(false));
}

// log p(Z | place) from the model, one word at a time: each word's reading given its parent's,
// summed over whether the place has the element (probability theta).
double HandLogLikelihood(const ChowLiuTree& tree, const FabMapOptions& o,
                         const std::vector<int>& query, const std::vector<double>& theta) {
  double log_likelihood = 0;
  for (int q = 0; q < tree.size(); ++q) {
    const bool z = std::count(query.begin(), query.end(), q) > 0;
    const bool zp =
        tree.parent(q) >= 0 && std::count(query.begin(), query.end(), tree.parent(q)) > 0;
    double p = 0;
    for (const bool e : {false, true}) {
      p += ZGivenElementAndParent(tree, o, q, z, e, zp, 0.3, 0.6) * (e ? theta[q] : 1 - theta[q]);
    }
    log_likelihood += std::log(p);
  }
  return log_likelihood;
}

// The derivation above needs priors of e and z_p that the model does not have; they must cancel.
TEST(FabMapModel, TheConditionalOfAReadingIsTheSameWhateverThePriorsThatCancel) {
  const ChowLiuTree tree = ToyTree();
  const FabMapOptions options;
  for (int q = 0; q < tree.size(); ++q) {
    for (const bool z : {false, true}) {
      for (const bool e : {false, true}) {
        for (const bool zp : {false, true}) {
          const double reference = ZGivenElementAndParent(tree, options, q, z, e, zp, 0.3, 0.6);
          EXPECT_NEAR(ZGivenElementAndParent(tree, options, q, z, e, zp, 0.9, 0.05), reference,
                      1e-12);
        }
      }
    }
  }
}

// p(e = 1 | place seen once, showing `words`), by Bayes on the detector model.
std::vector<double> HandTheta(const ChowLiuTree& tree, const FabMapOptions& o,
                              const std::vector<int>& words) {
  std::vector<double> theta;
  for (int q = 0; q < tree.size(); ++q) {
    const bool seen = std::count(words.begin(), words.end(), q) > 0;
    const double prior = tree.Marginal(q);
    const double present = prior * (seen ? o.p_z_given_e : 1 - o.p_z_given_e);
    const double absent = (1 - prior) * (seen ? o.p_z_given_not_e : 1 - o.p_z_given_not_e);
    theta.push_back(present / (present + absent));
  }
  return theta;
}

// Where the tree tells nothing about a word (the root: p(z | z_p) = p(z)), the observation model
// is the detector model itself, whatever the word's marginal; a child whose parent is shown
// becomes likelier to be seen, one whose parent is not, less. (Multiplying by p(z) instead of
// dividing by it, as this model once did, gives this root (marginal above 0.5) p(z = 1 | e) 0.55
// instead of 0.39; a real word, marginal a few per cent, was then almost never expected where
// it exists, so its absence was no evidence against a place.)
TEST(FabMapModel, ObservationModelIsTheDetectorWhereTheTreeTellsNothing) {
  const ChowLiuTree tree = ToyTree();
  const FabMapModel model(tree, 0.39, 0.01);
  const int root = tree.root();
  ASSERT_GT(tree.Marginal(root), 0.05);
  ASSERT_LT(tree.Marginal(root), 0.95);
  for (const bool zp : {false, true}) {
    EXPECT_NEAR(std::exp(model.Term(root, true, zp, 1.0)), 0.39, 1e-12);
    EXPECT_NEAR(std::exp(model.Term(root, false, zp, 1.0)), 0.61, 1e-12);
    EXPECT_NEAR(std::exp(model.Term(root, true, zp, 0.0)), 0.01, 1e-12);
    EXPECT_NEAR(std::exp(model.Term(root, false, zp, 0.0)), 0.99, 1e-12);
  }
  for (int w = 0; w < tree.size(); ++w) {
    if (w == root || tree.Conditional(w, true, true) <= tree.Conditional(w, true, false)) continue;
    EXPECT_GT(std::exp(model.Term(w, true, true, 1.0)), 0.39) << w;
    EXPECT_LT(std::exp(model.Term(w, true, false, 1.0)), 0.39) << w;
  }
}

class ToyFabMap : public ::testing::TestWithParam<std::tuple<NewPlaceModel, bool>> {};

TEST_P(ToyFabMap, PosteriorMatchesTheFormulas) {
  const ChowLiuTree tree = ToyTree();
  FabMapOptions options;
  options.new_place_model = std::get<0>(GetParam());
  options.inverted_index = std::get<1>(GetParam());
  options.exact_tree_corrections = true;  // the formulas are FAB-MAP 1.0's, to the digit
  options.p_z_given_not_e = 0.01;
  const std::vector<std::vector<int>> places = {{0, 1, 3}, {0, 2, 4, 5}, {2, 5}};
  const std::vector<std::vector<int>> training = {{0, 1}, {2, 4}, {0, 3, 5}, {}};
  PlaceDatabase samples(6), map(6);
  for (const auto& t : training) samples.AddPlace(t);
  for (const auto& p : places) map.AddPlace(p);
  FabMap fabmap(tree, options, samples);
  fabmap.SetPlaces(map);
  const std::vector<int> query = {0, 2, 5};
  const FabMapResult result = fabmap.Compare(query);

  std::vector<double> log_joint;
  for (const auto& p : places) {
    log_joint.push_back(HandLogLikelihood(tree, options, query, HandTheta(tree, options, p)) +
                        std::log((1 - options.new_place_prior) / 3));
  }
  double new_place;
  if (options.new_place_model == NewPlaceModel::kMeanField) {
    std::vector<double> prior;
    for (int q = 0; q < 6; ++q) prior.push_back(tree.Marginal(q));
    new_place = HandLogLikelihood(tree, options, query, prior);
  } else {
    double mean = 0;
    for (const auto& t : training)
      mean += std::exp(HandLogLikelihood(tree, options, query, HandTheta(tree, options, t)));
    new_place = std::log(mean / training.size());
  }
  // FAB-MAP 1.0 is exact to rounding in double precision. FAB-MAP 2.0 sums each place's
  // per-word changes in single precision (float epsilon 1.2e-7; a handful of additions here),
  // so it is held to 1e-6 of the value.
  const auto tolerance = [&](double value) {
    return (options.inverted_index ? 1e-6 : 1e-9) * std::max(1.0, std::abs(value));
  };
  EXPECT_NEAR(result.new_place_log_likelihood, new_place, tolerance(new_place));
  log_joint.push_back(new_place + std::log(options.new_place_prior));
  double total = 0;
  for (const double l : log_joint) total += std::exp(l);
  for (int i = 0; i < 3; ++i) {
    const double log_likelihood = log_joint[i] - std::log((1 - options.new_place_prior) / 3);
    EXPECT_NEAR(result.log_likelihoods[i], log_likelihood, tolerance(log_likelihood));
    EXPECT_NEAR(result.posterior[i], 0.99 * std::exp(log_joint[i]) / total + 0.01 / 4,
                tolerance(1));
  }
  EXPECT_NEAR(result.new_place, 0.99 * std::exp(log_joint[3]) / total + 0.01 / 4, tolerance(1));
  // The query shares every word with place 1: it must be the best.
  EXPECT_EQ(result.best, 1);
  // Its log odds against the new place, unsmoothed.
  EXPECT_NEAR(result.best_log_odds, log_joint[1] - log_joint[3], tolerance(log_joint[1]));
}

TEST(FabMap, LogOddsKeepTheOrderTheSmoothedPosteriorLoses) {
  // Two maps, each with one place that is the query's twin and others unrelated to it: the
  // twin's smoothed posterior sits at the ceiling 0.99 + 0.01 / (places + 1) in both, so the
  // smaller map looks the more confident. The log odds are finite, and higher where the twin
  // shares more words.
  RandomWordSets random_sets(400, 8);
  std::vector<std::vector<int>> training;
  for (int i = 0; i < 200; ++i) training.push_back(random_sets.Next(40));
  const ChowLiuTree tree = ChowLiuTree::Train(training, 400);
  FabMapOptions options;
  options.p_z_given_not_e = 0.005;
  const std::vector<int> query = random_sets.Next(40);
  const auto twin_of_query = [&](int shared) {
    std::vector<int> twin(query.begin(), query.begin() + shared);
    for (const int w : random_sets.Next(40 - shared)) {
      if (std::find(query.begin(), query.end(), w) == query.end()) twin.push_back(w);
    }
    std::sort(twin.begin(), twin.end());
    return twin;
  };
  const auto map_with_twin = [&](const std::vector<int>& twin, int unrelated_places) {
    FabMap fabmap(tree, options);
    for (int i = 0; i < unrelated_places; ++i) fabmap.AddPlace(random_sets.Next(40));
    fabmap.AddPlace(twin);
    return fabmap;
  };
  const std::vector<int> strong_twin = twin_of_query(30), weak_twin = twin_of_query(20);
  FabMap strong_map = map_with_twin(strong_twin, 20);
  const FabMapResult strong = strong_map.Compare(query);
  const FabMapResult weak = map_with_twin(weak_twin, 5).Compare(query);
  ASSERT_EQ(strong.best, 20);
  ASSERT_EQ(weak.best, 5);
  EXPECT_LT(strong.posterior[20], weak.posterior[5]);  // saturated: misleading
  EXPECT_NEAR(strong.posterior[20], 0.99 + 0.01 / 22, 1e-9);
  EXPECT_TRUE(std::isfinite(strong.best_log_odds));
  EXPECT_GT(strong.best_log_odds, weak.best_log_odds + 5);
  // A second keyframe of the same location does not make the first look unsure: the log odds
  // only give up the prior mass the new place takes, log(22 / 21).
  strong_map.AddPlace(strong_twin);
  const FabMapResult twice = strong_map.Compare(query);
  EXPECT_NEAR(strong.best_log_odds - twice.best_log_odds, std::log(22.0 / 21.0), 1e-6);
}

TEST(DetectorModel, MomentsRecoverTheRatesViewsWereDrawnWith) {
  // 400 places of 150 scene words out of 5,000; three views of each, every scene word seen with
  // p = 0.45 and every other word with p = 0.004 (20 false words a view).
  const int vocabulary = 5000, scene_words = 150;
  const double p_e = 0.45, p_not_e = 0.004;
  std::mt19937_64 random(3);
  std::uniform_real_distribution<double> unit(0, 1);
  std::vector<std::vector<std::vector<int>>> sequences;
  for (int place = 0; place < 400; ++place) {
    std::vector<int> words(vocabulary);
    std::iota(words.begin(), words.end(), 0);
    std::shuffle(words.begin(), words.end(), random);
    std::vector<char> in_scene(vocabulary, 0);
    for (int k = 0; k < scene_words; ++k) in_scene[words[k]] = 1;
    std::vector<std::vector<int>> views(3);
    for (auto& view : views) {
      for (int w = 0; w < vocabulary; ++w) {
        if (unit(random) < (in_scene[w] ? p_e : p_not_e)) view.push_back(w);
      }
    }
    sequences.push_back(views);
  }
  const DetectorModel model = EstimateDetectorModel(sequences, vocabulary);
  EXPECT_EQ(model.triples, 400);
  // Standard errors from the 400 triples' spread: p(z|e) through the triple intersections
  // (about 13.7 words a triple, +-0.19 on their mean): 1.5 %; p(z|not e) as the view size the
  // shared words leave unexplained (about 20 of 87 words): 8 %. Three of those.
  EXPECT_NEAR(model.p_z_given_e, p_e, 0.03);
  EXPECT_NEAR(model.p_z_given_not_e, p_not_e, 0.001);
  // Views that share nothing have no scene to detect: refused, not a model with p(z|e) = 0.
  std::vector<std::vector<std::vector<int>>> unrelated = {{{1, 2}, {3, 4}, {5, 6}}};
  EXPECT_THROW(EstimateDetectorModel(unrelated, vocabulary), std::invalid_argument);
  EXPECT_THROW(EstimateDetectorModel({{{1, 2}, {1, 2}}}, vocabulary), std::invalid_argument);
}

INSTANTIATE_TEST_SUITE_P(ModelsAndVersions, ToyFabMap,
                         ::testing::Combine(::testing::Values(NewPlaceModel::kMeanField,
                                                              NewPlaceModel::kSampling),
                                            ::testing::Bool()));

TEST(FabMap, VersionsOneAndTwoAgreeOnARandomMap) {
  // 300 words, 40 places (some observed several times), 20 queries resembling places.
  RandomWordSets random_sets(300, 9);
  const auto random_set = [&](int size) { return random_sets.Next(size); };
  std::vector<std::vector<int>> training;
  for (int i = 0; i < 200; ++i) training.push_back(random_set(30));
  const ChowLiuTree tree = ChowLiuTree::Train(training, 300);
  PlaceDatabase map(300);
  for (int i = 0; i < 40; ++i) map.AddPlace(random_set(40));
  for (int i = 0; i < 15; ++i) map.UpdatePlace(i, random_set(40));
  for (int i = 0; i < 5; ++i) map.UpdatePlace(i, random_set(40));
  FabMapOptions one, exact, fast;
  one.inverted_index = false;
  exact.exact_tree_corrections = true;
  FabMap fabmap_one(tree, one), fabmap_exact(tree, exact), fabmap_fast(tree, fast),
      fabmap_loaded(tree, exact);
  fabmap_one.SetPlaces(map);
  fabmap_exact.SetPlaces(map);
  fabmap_fast.SetPlaces(map);
  // A saved and loaded map rebuilds its index (and its groups of repeated places) from scratch.
  TemporaryDirectory temp;
  map.Save(temp.path() + "/places.bin");
  fabmap_loaded.SetPlaces(PlaceDatabase::Load(temp.path() + "/places.bin"));
  for (int q = 0; q < 20; ++q) {
    // Half of a place's words and some random others, as a real revisit would show.
    const std::vector<int>& place = map.place(2 * q).words;
    std::set<int> words(place.begin(),
                        place.begin() + static_cast<std::ptrdiff_t>(place.size() / 2));
    for (const int w : random_set(15)) words.insert(w);
    const std::vector<int> query(words.begin(), words.end());
    const FabMapResult a = fabmap_one.Compare(query), b = fabmap_exact.Compare(query),
                       c = fabmap_fast.Compare(query), d = fabmap_loaded.Compare(query);
    ASSERT_EQ(a.log_likelihoods.size(), b.log_likelihoods.size());
    ASSERT_EQ(a.log_likelihoods.size(), d.log_likelihoods.size());
    // Exact FAB-MAP 2.0 rearranges FAB-MAP 1.0's sum: the same numbers, up to its sums of
    // per-word changes in single precision (some 40 additions a place here: 1e-6 of the value).
    for (std::size_t i = 0; i < a.log_likelihoods.size(); ++i) {
      EXPECT_NEAR(a.log_likelihoods[i], b.log_likelihoods[i],
                  1e-6 * std::abs(a.log_likelihoods[i]));
      EXPECT_NEAR(a.log_likelihoods[i], d.log_likelihoods[i],
                  1e-6 * std::abs(a.log_likelihoods[i]));
    }
    EXPECT_EQ(a.best, b.best);
    EXPECT_NEAR(a.new_place, b.new_place, 1e-6);
    // The default FAB-MAP 2.0 leaves out the corrections of absent children: it still finds
    // the place the view came from (the order among the unrelated places, whose likelihoods
    // nearly tie, may differ).
    EXPECT_EQ(c.best, a.best);
    EXPECT_EQ(a.best, 2 * q);
    EXPECT_GT(c.posterior[static_cast<std::size_t>(c.best)], 0.9);
  }
}

TEST(FabMap, ComparingWithASubsetEqualsAMapOfTheSubsetAlone) {
  // 300 words, 30 places; the subset leaves out every third place, among them the one the query
  // comes from, as loop detection leaves out the recent past.
  RandomWordSets random_sets(300, 5);
  const auto random_set = [&](int size) { return random_sets.Next(size); };
  std::vector<std::vector<int>> training;
  for (int i = 0; i < 200; ++i) training.push_back(random_set(30));
  const ChowLiuTree tree = ChowLiuTree::Train(training, 300);
  FabMap whole(tree, FabMapOptions{}), subset(tree, FabMapOptions{});
  std::vector<char> candidates;
  std::vector<std::vector<int>> places;
  for (int i = 0; i < 30; ++i) {
    places.push_back(random_set(40));
    whole.AddPlace(places.back());
    candidates.push_back(i % 3 != 0);
    if (candidates.back()) subset.AddPlace(places.back());
  }
  for (const int source : {3, 4}) {
    const std::vector<int> query(places[source].begin(), places[source].begin() + 30);
    const FabMapResult masked = whole.Compare(query, candidates);
    const FabMapResult alone = subset.Compare(query);
    ASSERT_EQ(masked.posterior.size(), 30u);
    int k = 0;
    for (int i = 0; i < 30; ++i) {
      if (!candidates[i]) {
        EXPECT_EQ(masked.posterior[i], 0.0);
        continue;
      }
      EXPECT_DOUBLE_EQ(masked.posterior[i], alone.posterior[k++]);
    }
    EXPECT_DOUBLE_EQ(masked.new_place, alone.new_place);
    // The source place wins when it may; otherwise the answer is still one of the candidates.
    if (candidates[source]) {
      EXPECT_EQ(masked.best, source);
    }
    EXPECT_TRUE(candidates[static_cast<std::size_t>(masked.best)]);
  }
  EXPECT_THROW(whole.Compare(places[0], std::vector<char>(29, 1)), std::invalid_argument);
}

TEST(FabMap, AddUpdatesAMatchedPlaceAndAddsANewOne) {
  // 300 words from independent training images; views of 40 words.
  RandomWordSets random_sets(300, 4);
  const auto random_set = [&](int size) { return random_sets.Next(size); };
  std::vector<std::vector<int>> training;
  for (int i = 0; i < 200; ++i) training.push_back(random_set(40));
  FabMap fabmap(ChowLiuTree::Train(training, 300), FabMapOptions{});
  const std::vector<int> first = random_set(40), second = random_set(40);
  int place = -1;
  fabmap.Add(first, &place);
  EXPECT_EQ(place, 0);
  // The first view again, with a quarter of its words missed: the same place, observed twice.
  const std::vector<int> again(first.begin(), first.begin() + 30);
  const FabMapResult result = fabmap.Add(again, &place);
  EXPECT_EQ(place, 0);
  EXPECT_GT(result.posterior[0], 0.9);
  EXPECT_EQ(fabmap.places().place(0).observations, 2);
  fabmap.Add(second, &place);  // unrelated words: a new place
  EXPECT_EQ(place, 1);
  EXPECT_EQ(fabmap.places().size(), 2);
}

// A chain of views down a corridor: B shows half of A's words and 20 others, C those 20 and 20
// more, none of A's. Updating by appearance alone makes one place of all three; with
// update_near_first_view, C does not match the place's first view (A) and founds its own.
TEST(FabMap, UpdateNearFirstViewStopsAChainOfViews) {
  RandomWordSets random_sets(300, 4);
  std::vector<std::vector<int>> training;
  for (int i = 0; i < 200; ++i) training.push_back(random_sets.Next(40));
  const auto words = [](std::initializer_list<std::pair<int, int>> ranges) {
    std::vector<int> set;
    for (const auto& [first, last] : ranges) {
      for (int w = first; w < last; ++w) set.push_back(w);
    }
    return set;
  };
  const std::vector<int> a = words({{0, 40}}), b = words({{0, 20}, {100, 120}}),
                         c = words({{100, 120}, {200, 220}});
  for (const bool near_first_view : {false, true}) {
    SCOPED_TRACE(near_first_view);
    FabMapOptions options;
    options.update_near_first_view = near_first_view;
    FabMap fabmap(ChowLiuTree::Train(training, 300), options);
    int place_a = -1, place_b = -1, place_c = -1;
    fabmap.Add(a, &place_a);
    fabmap.Add(b, &place_b);
    EXPECT_EQ(place_b, place_a);  // half of A's words: A's place either way
    fabmap.Add(c, &place_c);
    if (near_first_view) {
      EXPECT_NE(place_c, place_a);
      EXPECT_EQ(fabmap.places().size(), 2);
    } else {
      EXPECT_EQ(place_c, place_a);  // through B's words: the chain
      EXPECT_EQ(fabmap.places().size(), 1);
    }
  }
}

// A corridor walked twice: 81 views 0.25 m apart along 20 m, each showing 30 words every view
// of the corridor shows (identical doors, lights) and 10 of its own location's (what differs a
// door further on). By appearance alone the corridor's words outweigh the rest and places grow
// down the corridor; with the odometry's positions a place takes only views within
// max_place_extent (1 m) of where it was founded: at most the 9 views of a pass within 1 m
// either side (the first pass fills only the 5 ahead; the second, 0.3 m of drift off the first,
// may reach behind), 18 of the 162, and the second pass updates the first pass's places
// instead of founding its own.
TEST(FabMap, UpdatedPlacesSpreadNoFartherThanTheOdometrySays) {
  RandomWordSets random_sets(300, 6);
  std::vector<std::vector<int>> training;
  for (int i = 0; i < 200; ++i) training.push_back(random_sets.Next(40));
  const ChowLiuTree tree = ChowLiuTree::Train(training, 300);
  const std::vector<int> corridor = random_sets.Next(30);
  constexpr int kViews = 81;
  std::vector<std::vector<int>> views;
  for (int i = 0; i < kViews; ++i) {
    std::set<int> words(corridor.begin(), corridor.end());
    for (const int word : random_sets.Next(10)) words.insert(word);
    views.emplace_back(words.begin(), words.end());
  }
  const auto largest_place = [](const std::vector<int>& place_of_view) {
    std::map<int, int> views_of_place;
    for (const int place : place_of_view) ++views_of_place[place];
    int largest = 0;
    for (const auto& [place, count] : views_of_place) largest = std::max(largest, count);
    return largest;
  };

  FabMap by_appearance(tree, FabMapOptions{});
  std::vector<int> place_of_view;
  for (int pass = 0; pass < 2; ++pass) {
    for (const auto& view : views) {
      int place = -1;
      by_appearance.Add(view, &place);
      place_of_view.push_back(place);
    }
  }
  // The problem the extent solves: one place swallows most of the corridor.
  EXPECT_GT(largest_place(place_of_view), kViews);

  FabMap by_odometry(tree, FabMapOptions{});
  place_of_view.clear();
  int first_pass_places = 0;
  for (int pass = 0; pass < 2; ++pass) {
    for (int i = 0; i < kViews; ++i) {
      ViewPose where;
      where.segment = 0;
      where.T_world_camera.translation() = Eigen::Vector3d(0.25 * i + 0.3 * pass, 0, 0);
      int place = -1;
      by_odometry.Add(views[static_cast<std::size_t>(i)], where, &place);
      place_of_view.push_back(place);
    }
    if (pass == 0) first_pass_places = by_odometry.places().size();
  }
  EXPECT_LE(largest_place(place_of_view), 18);
  EXPECT_GE(first_pass_places, 20.0 / 2.0);  // a place spans at most 2 m of the 20
  // The revisit joins the places of the first pass: a few new ones at most, where the drift
  // carries a view more than 1 m from every place founded near it.
  EXPECT_LE(by_odometry.places().size(), first_pass_places + first_pass_places / 4);

  // Another segment (after a tracking loss) or no pose at all: a place of its own, whatever the
  // words; and no later view updates a place founded without a pose.
  int place = -1;
  ViewPose elsewhere;
  elsewhere.segment = 1;
  by_odometry.Add(views[0], elsewhere, &place);
  EXPECT_EQ(place, by_odometry.places().size() - 1);
  const int lost_place = by_odometry.places().size();
  by_odometry.Add(views[1], ViewPose{}, &place);
  EXPECT_EQ(place, lost_place);
  by_odometry.Add(views[1], ViewPose{}, &place);
  EXPECT_EQ(place, lost_place + 1);
}

TEST(PostingList, KeepsPlacesInOrderAndAddsScoresOneOrTwoListsAtATime) {
  // Every encoded length; out-of-order inserts, merged once they are 1/64 of the list.
  // Gaps 0, 1, 127, 1, 2^14 - 1, 2^14, 2^21, 2^28, 1: 1, 1, 1, 1, 2, 3, 4, 5 and 1 bytes.
  const std::vector<std::uint32_t> a_places = {0,     1,       128,       129,      16512,
                                               32896, 2130048, 270565504, 270565505};
  PostingList a, b;
  for (const std::uint32_t place : a_places) a.Insert(place);
  EXPECT_EQ(a.Decode(), a_places);
  EXPECT_EQ(a.size(), a_places.size());
  std::vector<std::uint32_t> b_places;
  for (int place = 1000; place > 0; place -= 3) {  // 1000, 997, ..., 1: each below the last
    b.Insert(static_cast<std::uint32_t>(place));
    b_places.insert(b_places.begin(), static_cast<std::uint32_t>(place));
  }
  EXPECT_EQ(b.Decode(), b_places);
  b.Erase(1000);
  b.Erase(5);  // not in the list
  b.Erase(1);
  EXPECT_EQ(b.Decode(), std::vector<std::uint32_t>(b_places.begin() + 1, b_places.end() - 1));

  // Scores only for places below 100,000: a list of small gaps against a shorter one.
  PostingList dense, sparse;
  for (std::uint32_t place = 3; place < 100000; place += 1 + place % 200) dense.Insert(place);
  for (std::uint32_t place = 0; place < 100000; place += 4000) sparse.Insert(place);
  for (const std::uint32_t place : {50001U, 1234U}) sparse.Insert(place);  // still unmerged
  std::vector<float> one_by_one(100000, 0.0F), paired(100000, 0.0F), expected(100000, 0.0F);
  for (const std::uint32_t place : dense.Decode()) expected[place] += 0.5F;
  for (const std::uint32_t place : sparse.Decode()) expected[place] += 2.0F;
  dense.AddTo(0.5F, one_by_one.data());
  sparse.AddTo(2.0F, one_by_one.data());
  PostingList::AddTo(dense, 0.5F, sparse, 2.0F, paired.data());
  EXPECT_EQ(one_by_one, expected);
  EXPECT_EQ(paired, expected);
  std::fill(paired.begin(), paired.end(), 0.0F);
  PostingList::AddTo(sparse, 2.0F, dense, 0.5F, paired.data());  // the shorter list first
  EXPECT_EQ(paired, expected);
}

TEST(FabMap, MotionPriorFavoursTheLastMatchAndItsNeighbours) {
  RandomWordSets random_sets(300, 5);
  std::vector<std::vector<int>> training;
  for (int i = 0; i < 200; ++i) training.push_back(random_sets.Next(40));
  const ChowLiuTree tree = ChowLiuTree::Train(training, 300);
  std::vector<std::vector<int>> views;
  for (int i = 0; i < 6; ++i) views.push_back(random_sets.Next(40));
  // Half of view 1 and half of view 4: two places explain the query about equally well.
  std::set<int> mixed(views[1].begin(), views[1].begin() + 20);
  mixed.insert(views[4].begin(), views[4].begin() + 20);
  const std::vector<int> query(mixed.begin(), mixed.end());
  for (const double weight : {0.6, 1.0}) {
    FabMapOptions options;
    options.location_prior = LocationPrior::kMotion;
    options.motion_weight = weight;
    FabMap fabmap(tree, options);
    int place = -1;
    for (const auto& view : views) fabmap.Add(view, &place);
    ASSERT_EQ(place, 5);  // unrelated views: six places, the last one matched last
    const FabMapResult result = fabmap.Compare(query);
    // By hand: the existing-place mass 1 - 0.9 spread as (1 - weight) / 6 each, plus weight / 2
    // on places 4 and 5 (the last match and its only neighbour).
    std::vector<double> joint;
    for (int i = 0; i < 6; ++i) {
      const double prior = 0.1 * ((1 - weight) / 6 + (i >= 4 ? weight / 2 : 0));
      joint.push_back(std::exp(result.log_likelihoods[i]) * prior);
    }
    joint.push_back(std::exp(result.new_place_log_likelihood) * 0.9);
    const double total = std::accumulate(joint.begin(), joint.end(), 0.0);
    for (int i = 0; i < 6; ++i) {
      const double expected = 0.99 * joint[i] / total + 0.01 / 7;
      EXPECT_NEAR(result.posterior[i], expected, 1e-9 * expected)
          << "place " << i << ", weight " << weight;
    }
    EXPECT_NEAR(result.new_place, 0.99 * joint[6] / total + 0.01 / 7, 1e-9);
    EXPECT_EQ(result.best, 4);  // the last match's neighbour wins the near tie
    EXPECT_GT(result.posterior[4], 0.5);
  }
}

// Real images with the default vocabulary `make build` trains (opencv-doc photos and the
// synthetic hall; never the EuRoC data used here).
class RealImages : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    const std::string directory = STEREO_FABMAP_SLAM_DEFAULT_VOCABULARY;
    if (!std::filesystem::exists(directory + "/vocabulary.bin")) {
      FAIL() << "no default vocabulary in " << directory << ": `make build` trains it";
    }
  }
  // The shipped configuration: odometry features with place recognition's selection.
  static PlaceRecognitionOptions ShippedOptions() {
    return LoadPlaceRecognitionOptions(
        RepositoryRoot() + "/config/fabmap.yaml",
        io::OptionsFile::Load(RepositoryRoot() + "/config/euroc.yaml")
            .Read<features::FeatureOptions>());
  }
};

TEST_F(RealImages, KnownPlacesMatchAndAnotherBuildingIsNew) {
  const std::string directory = STEREO_FABMAP_SLAM_DEFAULT_VOCABULARY;
  const PlaceRecognitionOptions options = ShippedOptions();
  EXPECT_EQ(std::filesystem::canonical(options.vocabulary_directory),
            std::filesystem::canonical(directory));
  const Vocabulary vocabulary = Vocabulary::Load(directory + "/vocabulary.bin");
  FabMap fabmap(ChowLiuTree::Load(directory + "/chow_liu_tree.bin"),
                ResolveDetectorModel(options.fabmap, directory));
  ImageDescriber describer{options.features};
  const datasets::EurocSequence mh01 =
      datasets::EurocSequence::Open(EurocSequencePath("MH01_first10s"));
  const datasets::EurocSequence v101 =
      datasets::EurocSequence::Open(EurocSequencePath("V101_micro"));
  const auto words = [&](const datasets::EurocSequence& sequence, std::size_t frame) {
    return vocabulary.WordSet(describer.Describe(sequence.LoadStereoPair(frame).left));
  };
  // The map: every 10th frame of MH01 as its own place.
  PlaceDatabase map(vocabulary.size());
  for (std::size_t i = 0; i < mh01.size(); i += 10) map.AddPlace(words(mh01, i));
  fabmap.SetPlaces(map);

  int new_in_v101 = 0, queried_v101 = 0;
  for (std::size_t i = 0; i < v101.size(); i += 5, ++queried_v101) {
    new_in_v101 += fabmap.Compare(words(v101, i)).new_place > 0.5 ? 1 : 0;
  }
  int matched_in_mh01 = 0, queried_mh01 = 0;
  for (std::size_t i = 5; i < mh01.size(); i += 10, ++queried_mh01) {
    const FabMapResult result = fabmap.Compare(words(mh01, i));
    matched_in_mh01 += result.best >= 0 && result.posterior[result.best] > result.new_place ? 1 : 0;
  }
  RecordProperty("v101_new", std::to_string(new_in_v101) + "/" + std::to_string(queried_v101));
  RecordProperty("mh01_matched",
                 std::to_string(matched_in_mh01) + "/" + std::to_string(queried_mh01));
  // "Most" of each: at least 80 %.
  EXPECT_GE(new_in_v101, 0.8 * queried_v101);
  EXPECT_GE(matched_in_mh01, 0.8 * queried_mh01);
}

TEST_F(RealImages, ACameraStandingStillStaysOnePlace) {
  // 30 s at 20 Hz of the rendered hall from one place, as a hovering camera sees it: the pose
  // jitters by a few millimetres and a tenth of a degree, the exposure by 2 %, and the image
  // noise (2 grey levels, as the rendered routes) changes every frame; with them a few corners
  // and words come and go. FabMap::Add with the shipped configuration must update the first
  // place every time.
  const std::string directory = STEREO_FABMAP_SLAM_DEFAULT_VOCABULARY;
  const PlaceRecognitionOptions options = ShippedOptions();
  const Vocabulary vocabulary = Vocabulary::Load(directory + "/vocabulary.bin");
  const ChowLiuTree tree = ChowLiuTree::Load(directory + "/chow_liu_tree.bin");
  ImageDescriber describer{options.features};
  const datasets::HallOptions hall;
  const datasets::HallScene scene(
      hall, datasets::TextureLibrary::Load("/usr/share/doc/opencv-doc/examples/data"), 1);
  const camera::StereoCalibration rig = datasets::SyntheticSequence::Rig(true);
  const datasets::CameraRenderer renderer(rig.left);
  const Eigen::Isometry3d hover =
      datasets::Route(datasets::RouteKind::kLoop, hall).BodyPose(3.0) * rig.left.T_body_camera;
  std::mt19937_64 random(21);
  std::normal_distribution<double> gauss(0, 1);
  std::vector<std::vector<int>> views;
  for (int frame = 0; frame < 600; ++frame) {
    Eigen::Isometry3d pose = hover;
    pose.translation() += 0.003 * Eigen::Vector3d(gauss(random), gauss(random), gauss(random));
    pose.linear() =
        pose.linear() *
        Eigen::AngleAxisd(0.1 * M_PI / 180 * gauss(random),
                          Eigen::Vector3d(gauss(random), gauss(random), gauss(random)).normalized())
            .toRotationMatrix();
    const cv::Mat radiance = renderer.Render(scene, pose);
    cv::Mat noise(radiance.size(), CV_32F), image;
    cv::RNG(1000 + frame).fill(noise, cv::RNG::NORMAL, 0.0, 2.0);
    cv::Mat(radiance * (1 + 0.02 * gauss(random)) + noise).convertTo(image, CV_8U);
    views.push_back(vocabulary.WordSet(describer.Describe(image)));
  }
  // The views do differ: words come and go with the noise.
  int changed = 0;
  for (std::size_t i = 1; i < views.size(); ++i) changed += views[i] != views[0] ? 1 : 0;
  EXPECT_GT(changed, 500);

  const auto places_after_hovering = [&](const FabMapOptions& fabmap_options) {
    FabMap fabmap(tree, fabmap_options);
    double lowest = 1;
    for (const std::vector<int>& view : views) {
      const FabMapResult result = fabmap.Add(view);
      if (result.best >= 0) lowest = std::min(lowest, result.posterior[result.best]);
    }
    RecordProperty("lowest_posterior", std::to_string(lowest));
    return fabmap.places().size();
  };
  EXPECT_EQ(places_after_hovering(ResolveDetectorModel(options.fabmap, directory)), 1);
  // The model without false detections (Cummins & Newman's p(z | not e) = 0) is what split the
  // hovering camera's place: a place seen n times without a word rules it out as 1.6^-n.
  FabMapOptions without_false_detections = options.fabmap;
  without_false_detections.detector_model = DetectorModelSource::kFixed;
  without_false_detections.p_z_given_e = 0.39;
  without_false_detections.p_z_given_not_e = 0;
  EXPECT_GT(places_after_hovering(without_false_detections), 1);
}

template <typename Action>
std::string ErrorOf(Action action) {
  try {
    action();
  } catch (const io::InputError& error) {
    return error.what();
  }
  return "";
}

cv::Mat RandomBinaryDescriptors(int rows) {
  cv::Mat descriptors(rows, 32, CV_8U);
  cv::randu(descriptors, 0, 256);
  return descriptors;
}

// A vocabulary of at most 4^3 = 64 words: small enough to train in milliseconds.
Vocabulary SmallVocabulary(const cv::Mat& descriptors) {
  VocabularyOptions options;
  options.branching = 4;
  options.depth = 3;
  return Vocabulary::Train(descriptors, options);
}

void FlipByte(const std::string& path, std::size_t offset) {
  std::fstream file(path, std::ios::in | std::ios::out | std::ios::binary);
  file.seekg(static_cast<std::streamoff>(offset));
  const char byte = static_cast<char>(file.get());
  file.seekp(static_cast<std::streamoff>(offset));
  file.put(static_cast<char>(byte ^ 0x40));
}

TEST(FabMapFiles, RoundTripsExactlyAndRefusesDamage) {
  TemporaryDirectory temp;
  const cv::Mat descriptors = RandomBinaryDescriptors(400);
  const Vocabulary vocabulary = SmallVocabulary(descriptors);
  EXPECT_GT(vocabulary.size(), 30);
  EXPECT_LE(vocabulary.size(), 64);
  const ChowLiuTree tree = ToyTree();
  PlaceDatabase places(6);
  places.AddPlace({0, 3});
  places.UpdatePlace(0, {3, 5});
  places.AddPlace({1});

  vocabulary.Save(temp.path() + "/v.bin");
  tree.Save(temp.path() + "/t.bin");
  places.Save(temp.path() + "/p.bin");
  EXPECT_TRUE(Vocabulary::Load(temp.path() + "/v.bin") == vocabulary);
  EXPECT_TRUE(ChowLiuTree::Load(temp.path() + "/t.bin") == tree);
  PlaceDatabase loaded = PlaceDatabase::Load(temp.path() + "/p.bin");
  EXPECT_TRUE(loaded == places);
  EXPECT_EQ(Vocabulary::Load(temp.path() + "/v.bin").Quantize(descriptors),
            vocabulary.Quantize(descriptors));

  // A flipped byte in the payload, a truncated file, another kind of file: refused, clearly.
  std::filesystem::copy_file(temp.path() + "/p.bin", temp.path() + "/bad.bin");
  FlipByte(temp.path() + "/bad.bin", 30);
  EXPECT_NE(ErrorOf([&] {
              loaded = PlaceDatabase::Load(temp.path() + "/bad.bin");
            }).find("checksum mismatch"),
            std::string::npos);
  std::filesystem::resize_file(temp.path() + "/v.bin",
                               std::filesystem::file_size(temp.path() + "/v.bin") - 5);
  EXPECT_NE(ErrorOf([&] { Vocabulary::Load(temp.path() + "/v.bin"); }).find("truncated"),
            std::string::npos);
  EXPECT_NE(ErrorOf([&] { ChowLiuTree::Load(temp.path() + "/p.bin"); }).find("wrong magic number"),
            std::string::npos);
  EXPECT_NE(ErrorOf([&] { ChowLiuTree::Load(temp.path() + "/none.bin"); }).find("cannot open"),
            std::string::npos);
  // The failed loads left the loaded state as it was.
  EXPECT_TRUE(loaded == places);
}

// 2,000 mutants each of a vocabulary, a Chow-Liu tree and a place database (bit flips,
// truncations, appended bytes, and payload changes that pass the checksum): refused with an
// InputError or loaded, none crashing, hanging or allocating more than 256 MB.
TEST(FabMapFiles, FuzzedFilesAreRefusedOrLoadedNeverCrash) {
  TemporaryDirectory temp;
  SmallVocabulary(RandomBinaryDescriptors(400)).Save(temp.path() + "/v.bin");
  ToyTree().Save(temp.path() + "/t.bin");
  PlaceDatabase places(6);
  places.AddPlace({0, 3});
  places.UpdatePlace(0, {3, 5});
  places.AddPlace({1, 2, 4});
  places.Save(temp.path() + "/p.bin");
  const std::size_t bound = 256u << 20;
  const FuzzCounts vocabulary = LoadMutants(temp.path() + "/v.bin", 2000, 21, bound,
                                            [](const std::string& p) { Vocabulary::Load(p); });
  const FuzzCounts tree = LoadMutants(temp.path() + "/t.bin", 2000, 22, bound,
                                      [](const std::string& p) { ChowLiuTree::Load(p); });
  const FuzzCounts database = LoadMutants(temp.path() + "/p.bin", 2000, 23, bound,
                                          [](const std::string& p) { PlaceDatabase::Load(p); });
  for (const FuzzCounts& counts : {vocabulary, tree, database}) {
    EXPECT_GE(counts.refused, 1200);  // every mutant whose checksum was not fixed, at least
  }
  RecordProperty("vocabulary_loaded", vocabulary.loaded);
  RecordProperty("tree_loaded", tree.loaded);
  RecordProperty("places_loaded", database.loaded);
}

TEST(Vocabulary, QuantisesToTheNearestWordAndTrainsOnFloatDescriptors) {
  // Binary: a descriptor one bit away from a training descriptor falls into the same word in
  // nearly every case (a bit flip rarely crosses a cluster border).
  cv::Mat binary(2000, 64, CV_8U);
  cv::randu(binary, 0, 256);
  const Vocabulary words = Vocabulary::Train(binary, VocabularyOptions{});
  cv::Mat nudged = binary.clone();
  for (int r = 0; r < nudged.rows; ++r) nudged.at<std::uint8_t>(r, r % 64) ^= 1;
  const std::vector<int> a = words.Quantize(binary), b = words.Quantize(nudged);
  int same = 0;
  for (std::size_t i = 0; i < a.size(); ++i) same += a[i] == b[i] ? 1 : 0;
  EXPECT_GE(same, 0.9 * a.size());
  // Float (SIFT-like): two well separated blobs end in different words.
  cv::Mat floats(200, 16, CV_32F);
  cv::randn(floats, 0, 1);
  floats.rowRange(100, 200) += 50.0f;
  VocabularyOptions small;
  small.branching = 2;
  small.depth = 1;
  const Vocabulary float_words = Vocabulary::Train(floats, small);
  EXPECT_FALSE(float_words.binary());
  EXPECT_NE(float_words.Quantize(floats, 0), float_words.Quantize(floats, 150));
}

}  // namespace
}  // namespace stereo_fabmap_slam::test
