// Place recognition measured against ground truth (issue 10): the precision-recall sweep, the
// tf-idf baseline, the ground-truth matrix and poses, and the queries of FAB-MAP and tf-idf on
// a hand-built case whose answers are known.
#include <cmath>
#include <limits>
#include <optional>
#include <random>
#include <set>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include "stereo_fabmap_slam/evaluation/place_ground_truth.h"
#include "stereo_fabmap_slam/evaluation/place_recognition_precision_recall.h"
#include "stereo_fabmap_slam/evaluation/place_recognition_queries.h"
#include "stereo_fabmap_slam/io/input_error.h"
#include "stereo_fabmap_slam/place_recognition/chow_liu_tree.h"
#include "stereo_fabmap_slam/place_recognition/fab_map.h"
#include "stereo_fabmap_slam/place_recognition/sequence_score.h"
#include "stereo_fabmap_slam/place_recognition/tf_idf_index.h"
#include "test_support.h"

namespace stereo_fabmap_slam::test {
namespace {

using evaluation::PlaceGroundTruth;
using evaluation::PlaceQueryResult;
using place_recognition::TfIdfIndex;

PlaceQueryResult Answer(int query, double score, bool is_true, bool has_true_match) {
  PlaceQueryResult result;
  result.query = query;
  result.has_candidates = true;
  result.has_true_match = has_true_match;
  result.best_place = 0;
  result.best_frame = 0;
  result.score = score;
  result.is_true = is_true;
  return result;
}

TEST(PlaceRecognitionPrecisionRecall, HandBuiltCurve) {
  std::vector<PlaceQueryResult> results = {Answer(1, 0.6, true, true), Answer(2, 0.9, true, true),
                                           Answer(3, 0.7, false, true), Answer(4, 0.8, true, true),
                                           Answer(5, 0.5, false, false)};
  PlaceQueryResult unanswered;  // a true match exists, but no candidate was returned
  unanswered.query = 6;
  unanswered.has_candidates = true;
  unanswered.has_true_match = true;
  results.push_back(unanswered);
  PlaceQueryResult first;  // nothing earlier outside the window: not a query
  results.insert(results.begin(), first);

  // Five queries have a true match. Declared from the top: 0.9 right, 0.8 right, 0.7 wrong,
  // 0.6 right, 0.5 wrong.
  const std::vector<evaluation::PlacePrecisionRecallPoint> curve =
      evaluation::PrecisionRecallCurve(results);
  ASSERT_EQ(curve.size(), 5u);
  const double thresholds[] = {0.9, 0.8, 0.7, 0.6, 0.5};
  const int declared[] = {1, 2, 3, 4, 5}, correct[] = {1, 2, 2, 3, 3};
  for (std::size_t i = 0; i < curve.size(); ++i) {
    EXPECT_DOUBLE_EQ(curve[i].threshold, thresholds[i]);
    EXPECT_EQ(curve[i].declared, declared[i]);
    EXPECT_EQ(curve[i].correct, correct[i]);
    EXPECT_DOUBLE_EQ(curve[i].precision, static_cast<double>(correct[i]) / declared[i]);
    EXPECT_DOUBLE_EQ(curve[i].recall, correct[i] / 5.0);
  }
  EXPECT_DOUBLE_EQ(evaluation::RecallAtFullPrecision(curve), 0.4);
  // 0.2 x 1 + 0.2 x 1 + 0 x 2/3 + 0.2 x 3/4 + 0 x 3/5.
  EXPECT_DOUBLE_EQ(evaluation::AreaUnderCurve(curve), 0.55);

  const evaluation::PlaceRecognitionSummary summary =
      evaluation::SummarizePlaceRecognition(results);
  EXPECT_EQ(summary.queries, 6);
  EXPECT_EQ(summary.queries_with_true_match, 5);
  EXPECT_DOUBLE_EQ(summary.recall_at_full_precision, 0.4);
  EXPECT_DOUBLE_EQ(summary.auc, 0.55);

  // A fixed threshold between the sweep's points: 0.75 declares 0.9 and 0.8, both right.
  const evaluation::PlacePrecisionRecallPoint at = evaluation::PointAtThreshold(results, 0.75);
  EXPECT_EQ(at.declared, 2);
  EXPECT_EQ(at.correct, 2);
  EXPECT_DOUBLE_EQ(at.precision, 1.0);
  EXPECT_DOUBLE_EQ(at.recall, 0.4);
  const evaluation::PlacePrecisionRecallPoint low = evaluation::PointAtThreshold(results, 0.55);
  EXPECT_EQ(low.declared, 4);
  EXPECT_DOUBLE_EQ(low.precision, 0.75);
  EXPECT_EQ(evaluation::PointAtThreshold(results, 2.0).declared, 0);
  EXPECT_DOUBLE_EQ(evaluation::PointAtThreshold(results, 2.0).precision, 1.0);
}

TEST(PlaceRecognitionPrecisionRecall, TiedScoresAreDeclaredTogether) {
  // A right and a wrong answer with the same score: no threshold takes the right one alone.
  const std::vector<evaluation::PlacePrecisionRecallPoint> curve =
      evaluation::PrecisionRecallCurve({Answer(1, 0.7, true, true), Answer(2, 0.7, false, true)});
  ASSERT_EQ(curve.size(), 1u);
  EXPECT_EQ(curve[0].declared, 2);
  EXPECT_DOUBLE_EQ(curve[0].precision, 0.5);
  EXPECT_DOUBLE_EQ(evaluation::RecallAtFullPrecision(curve), 0.0);
  EXPECT_DOUBLE_EQ(evaluation::AreaUnderCurve(curve), 0.25);
  EXPECT_TRUE(evaluation::PrecisionRecallCurve({}).empty());
}

TEST(TfIdfIndex, InverseDocumentFrequencyFromTrainingImages) {
  const std::vector<double> idf = TfIdfIndex::InverseDocumentFrequency({{0, 1}, {0}, {0, 2, 2}}, 4);
  ASSERT_EQ(idf.size(), 4u);
  EXPECT_DOUBLE_EQ(idf[0], 0.0);            // in every image: says nothing
  EXPECT_DOUBLE_EQ(idf[1], std::log(2.0));  // (3 + 1) / (1 + 1)
  EXPECT_DOUBLE_EQ(idf[2], std::log(2.0));  // counted once per image
  EXPECT_DOUBLE_EQ(idf[3], std::log(4.0));  // never seen: the largest weight
  EXPECT_THROW(TfIdfIndex::InverseDocumentFrequency({{4}}, 4), std::invalid_argument);
}

TEST(TfIdfIndex, CosineOfHandMadeWordLists) {
  TfIdfIndex index({1.0, 1.0, 2.0, 0.0});
  EXPECT_EQ(index.Add({0, 0, 1}), 0);  // tf-idf (2, 1, 0, 0) / sqrt(5)
  EXPECT_EQ(index.Add({2}), 1);        // (0, 0, 1, 0)
  EXPECT_EQ(index.Add({3, 3}), 2);     // only a word of idf 0: no vector, scores 0
  EXPECT_EQ(index.size(), 3);
  // (1, 2, 0, 0) / sqrt(5): with image 0, (2 + 2) / 5.
  std::vector<double> scores = index.Score({1, 0, 1});
  ASSERT_EQ(scores.size(), 3u);
  EXPECT_NEAR(scores[0], 0.8, 1e-6);
  EXPECT_DOUBLE_EQ(scores[1], 0.0);
  EXPECT_DOUBLE_EQ(scores[2], 0.0);
  // (1, 0, 2, 0) / sqrt(5): with image 0, 2 / 5; with image 1, 2 / sqrt(5).
  scores = index.Score({0, 2});
  EXPECT_NEAR(scores[0], 0.4, 1e-6);
  EXPECT_NEAR(scores[1], 2 / std::sqrt(5.0), 1e-6);
  // An image scores 1 with itself, and the order of its words does not matter.
  EXPECT_NEAR(index.Score({1, 0, 0})[0], 1.0, 1e-6);
  EXPECT_THROW(index.Score({4}), std::invalid_argument);
  EXPECT_THROW(index.Add({-1}), std::invalid_argument);
  EXPECT_THROW(TfIdfIndex({}), std::invalid_argument);
}

TEST(PlaceGroundTruth, ReadsCsvTextAndImageMatrices) {
  TemporaryDirectory temp;
  // One triangle filled, as benchmarks often ship it: read symmetrically.
  WriteTextFile(temp.path() + "/gt.csv", "1,0,1\n0,1,0\n0,0,1\n");
  WriteTextFile(temp.path() + "/gt.txt", "# a comment\n1 0 0\n0 1 0.5\n0 0 1\n");
  cv::Mat image = cv::Mat::zeros(3, 3, CV_8U);
  image.at<unsigned char>(1, 0) = 255;
  ASSERT_TRUE(cv::imwrite(temp.path() + "/gt.png", image));

  const PlaceGroundTruth csv = PlaceGroundTruth::Load(temp.path() + "/gt.csv");
  ASSERT_EQ(csv.size(), 3);
  EXPECT_TRUE(csv.Same(0, 2));
  EXPECT_TRUE(csv.Same(2, 0));
  EXPECT_FALSE(csv.Same(0, 1));
  EXPECT_FALSE(csv.Same(1, 2));
  EXPECT_EQ(csv.SamePairs(), 1);

  const PlaceGroundTruth text = PlaceGroundTruth::Load(temp.path() + "/gt.txt");
  ASSERT_EQ(text.size(), 3);
  EXPECT_TRUE(text.Same(2, 1));  // any non-zero number
  EXPECT_FALSE(text.Same(0, 2));

  const PlaceGroundTruth png = PlaceGroundTruth::Load(temp.path() + "/gt.png");
  ASSERT_EQ(png.size(), 3);
  EXPECT_TRUE(png.Same(0, 1));
  EXPECT_FALSE(png.Same(0, 2));
  EXPECT_EQ(png.SamePairs(), 1);

  const PlaceGroundTruth subset = csv.Subset({0, 2});
  ASSERT_EQ(subset.size(), 2);
  EXPECT_TRUE(subset.Same(0, 1));
  EXPECT_THROW(csv.Subset({3}), std::out_of_range);
}

TEST(PlaceGroundTruth, RefusesMatricesThatAreNotSquare) {
  TemporaryDirectory temp;
  WriteTextFile(temp.path() + "/short_row.csv", "1,0,1\n0,1\n0,0,1\n");
  try {
    PlaceGroundTruth::Load(temp.path() + "/short_row.csv");
    ADD_FAILURE() << "a short row was accepted";
  } catch (const io::InputError& error) {
    EXPECT_NE(std::string(error.what()).find("short_row.csv:2"), std::string::npos) << error.what();
  }
  WriteTextFile(temp.path() + "/word.csv", "1,x\n0,1\n");
  EXPECT_THROW(PlaceGroundTruth::Load(temp.path() + "/word.csv"), io::InputError);
  ASSERT_TRUE(cv::imwrite(temp.path() + "/wide.png", cv::Mat::zeros(3, 4, CV_8U)));
  EXPECT_THROW(PlaceGroundTruth::Load(temp.path() + "/wide.png"), io::InputError);
  EXPECT_THROW(PlaceGroundTruth::Load(temp.path() + "/missing.png"), io::InputError);
}

// 640 x 480, focal 500 px, 10 cm baseline.
geometry::StereoCamera TestCamera() {
  geometry::StereoCamera camera;
  camera.size = cv::Size(640, 480);
  camera.fx = camera.fy = 500;
  camera.cx = 320;
  camera.cy = 240;
  camera.baseline = 0.1;
  return camera;
}

// 11 x 7 points 0.2 m apart, `depth` ahead of the camera, around its axis.
std::vector<Eigen::Vector3d> PointGrid(double depth) {
  std::vector<Eigen::Vector3d> points;
  for (int x = -5; x <= 5; ++x) {
    for (int y = -3; y <= 3; ++y) points.emplace_back(0.2 * x, 0.2 * y, depth);
  }
  return points;
}

TEST(PlaceGroundTruth, FromPosesUsesTheVisibleFraction) {
  const geometry::StereoCamera camera = TestCamera();
  // A wall of points 5 m ahead, filling the middle of the image.
  const std::vector<Eigen::Vector3d> wall = PointGrid(5.0);
  const auto pose = [](double x, double yaw_deg) {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.translation().x() = x;
    T.linear() = Eigen::AngleAxisd(yaw_deg * M_PI / 180, Eigen::Vector3d::UnitY()).matrix();
    return std::optional<Eigen::Isometry3d>(T);
  };
  // 0: the reference; 1: 0.2 m to the side (the wall stays in view); 2: turned round;
  // 3: without ground truth; 4: 5 m to the side, the wall out of view; 5: no points of its
  // own, at the reference's pose; 6: 3 m to the side, where the wall's points at x >= -0.2 m,
  // 7 of its 11 columns, land at u >= 0 (u = 500 (x - 3) / 5 + 320).
  const std::vector<std::optional<Eigen::Isometry3d>> poses = {
      pose(0, 0), pose(0.2, 0), pose(0, 180), std::nullopt, pose(5.0, 0), pose(0, 0), pose(3, 0)};
  const std::vector<std::vector<Eigen::Vector3d>> points = {wall, wall, wall, wall, wall, {}, wall};
  const PlaceGroundTruth truth = PlaceGroundTruth::FromPoses(points, poses, camera, 0.5);
  ASSERT_EQ(truth.size(), 7);
  EXPECT_TRUE(truth.Same(0, 1));
  EXPECT_FALSE(truth.Same(0, 2));
  EXPECT_FALSE(truth.Same(0, 3));
  EXPECT_FALSE(truth.Same(0, 4));
  // Frame 5 has no points, but frame 0's points all land in its image: either direction counts.
  EXPECT_TRUE(truth.Same(0, 5));
  EXPECT_TRUE(truth.Same(5, 0));
  // 7 / 11 = 0.64 of the points in view: the same place up to tau 0.64, not above.
  EXPECT_TRUE(truth.Same(0, 6));
  EXPECT_TRUE(PlaceGroundTruth::FromPoses(points, poses, camera, 0.63).Same(0, 6));
  EXPECT_FALSE(PlaceGroundTruth::FromPoses(points, poses, camera, 0.65).Same(0, 6));
  EXPECT_THROW(PlaceGroundTruth::FromPoses(points, poses, camera, 0.0), std::invalid_argument);
  EXPECT_THROW(PlaceGroundTruth::FromPoses({wall}, poses, camera, 0.5), std::invalid_argument);
}

// `count` distinct random words of the block [first, first + size).
std::vector<int> RandomWords(int first, int size, int count, std::mt19937* random) {
  std::uniform_int_distribution<int> word(first, first + size - 1);
  std::set<int> words;
  while (static_cast<int>(words.size()) < count) words.insert(word(*random));
  return std::vector<int>(words.begin(), words.end());
}

// Two passes over ten places. The vocabulary of 300 words falls into ten blocks of 30 that
// occur together (the training images show 15 words of one block each, so the Chow-Liu tree
// learns that), and place k shows 20 words of block k: places share no word. The second pass
// shows 10 of each place's words and 5 others of its block, as a revisit does. Frame 10 + k
// revisits frame k and nothing else.
struct TwoPasses {
  evaluation::PlaceRecognitionFrames frames;
  cv::Mat same = cv::Mat::eye(20, 20, CV_8U);
  std::vector<std::vector<int>> training;
};

TwoPasses MakeTwoPasses() {
  std::mt19937 random(7);
  TwoPasses passes;
  for (int i = 0; i < 200; ++i)
    passes.training.push_back(RandomWords(30 * (i % 10), 30, 15, &random));
  for (int k = 0; k < 10; ++k)
    passes.frames.word_sets.push_back(RandomWords(30 * k, 30, 20, &random));
  for (int k = 0; k < 10; ++k) {
    const std::vector<int>& place = passes.frames.word_sets[static_cast<std::size_t>(k)];
    std::set<int> words(place.begin(), place.begin() + 10);
    while (words.size() < 15) words.insert(RandomWords(30 * k, 30, 1, &random).front());
    passes.frames.word_sets.emplace_back(words.begin(), words.end());
    passes.same.at<unsigned char>(k, 10 + k) = 1;
  }
  passes.frames.words = passes.frames.word_sets;
  for (int i = 0; i < 20; ++i) passes.frames.times.push_back(i);
  passes.frames.window = 2;  // frames j - 1 and j - 2 are the recent past of frame j
  // A same-place pair inside the window: excluded, and counted as such.
  passes.same.at<unsigned char>(18, 19) = 1;
  return passes;
}

// Looking down a corridor: camera B stands 4 m behind camera A, both looking along +z. A's
// points (a wall 5 m ahead of it) lie inside B's image, 9 m ahead; B's points (a frame around
// the corridor 1 m ahead of B) lie behind A. One sees the other's points, not the other way
// round; and the cameras are 4 m apart.
TEST(PlaceGroundTruth, MutualVisibilityAndDistanceNarrowTheRelation) {
  const geometry::StereoCamera camera = TestCamera();
  const std::vector<Eigen::Vector3d> wall = PointGrid(5.0), frame = PointGrid(1.0);
  Eigen::Isometry3d behind = Eigen::Isometry3d::Identity();
  behind.translation().z() = -4.0;
  const std::vector<std::optional<Eigen::Isometry3d>> poses = {Eigen::Isometry3d::Identity(),
                                                               behind};
  const std::vector<std::vector<Eigen::Vector3d>> points = {wall, frame};
  evaluation::PlaceRelevance relevance;
  EXPECT_TRUE(PlaceGroundTruth::FromPoses(points, poses, camera, relevance).Same(0, 1));
  relevance.mutual = true;
  EXPECT_FALSE(PlaceGroundTruth::FromPoses(points, poses, camera, relevance).Same(0, 1));
  relevance.mutual = false;
  relevance.max_distance = 3.9;
  EXPECT_FALSE(PlaceGroundTruth::FromPoses(points, poses, camera, relevance).Same(0, 1));
  relevance.max_distance = 4.1;
  EXPECT_TRUE(PlaceGroundTruth::FromPoses(points, poses, camera, relevance).Same(0, 1));
  relevance.max_distance = 0.0;
  EXPECT_THROW(PlaceGroundTruth::FromPoses(points, poses, camera, relevance),
               std::invalid_argument);
}

TEST(PlaceRecognitionQueries, TwoPassesOfHandBuiltPlacesGiveAKnownCurve) {
  const TwoPasses passes = MakeTwoPasses();
  const PlaceGroundTruth truth(passes.same);
  const evaluation::ExcludedPairs excluded = evaluation::CountExcludedPairs(passes.frames, truth);
  EXPECT_EQ(excluded.pairs, 1 + 2 * 18);  // frame 1 has one frame before it, the others two
  EXPECT_EQ(excluded.same_place, 1);

  const place_recognition::ChowLiuTree tree =
      place_recognition::ChowLiuTree::Train(passes.training, 300);
  for (const evaluation::PlacesMode mode :
       {evaluation::PlacesMode::kPerImage, evaluation::PlacesMode::kUpdate}) {
    SCOPED_TRACE(evaluation::PlacesModeName(mode));
    place_recognition::FabMapOptions options;
    place_recognition::FabMap fabmap(tree, options);
    evaluation::FabMapQueryOptions query_options;
    query_options.mode = mode;
    query_options.match_log_odds = options.match_log_odds;
    const evaluation::FabMapQueries queries =
        evaluation::RunFabMapQueries(passes.frames, truth, query_options, &fabmap);
    const std::vector<PlaceQueryResult>& results = queries.results;
    ASSERT_EQ(results.size(), 20u);
    for (int j = 0; j < 20; ++j) {
      const PlaceQueryResult& result = results[static_cast<std::size_t>(j)];
      EXPECT_EQ(result.has_candidates, j >= 3) << j;
      EXPECT_EQ(result.has_true_match, j >= 10) << j;
      if (j >= 10) {
        // Each revisit finds its place, far above the unrelated ones.
        EXPECT_EQ(result.best_frame, j - 10);
        EXPECT_TRUE(result.is_true);
        EXPECT_GT(result.score, 0.9);
      } else if (j >= 3) {
        EXPECT_LT(result.score, 0.1) << j;
        EXPECT_GT(result.new_place_probability, 0.9) << j;
      }
    }
    const evaluation::PlaceRecognitionSummary summary =
        evaluation::SummarizePlaceRecognition(results);
    EXPECT_EQ(summary.queries, 17);
    EXPECT_EQ(summary.queries_with_true_match, 10);
    EXPECT_DOUBLE_EQ(summary.recall_at_full_precision, 1.0);
    EXPECT_DOUBLE_EQ(summary.auc, 1.0);
    // Every revisit's place is FAB-MAP's best candidate.
    EXPECT_DOUBLE_EQ(summary.candidate_recall_at_1, 1.0);
    EXPECT_DOUBLE_EQ(summary.candidate_recall_at_5, 1.0);
    // A floor above every posterior leaves no candidate to verify.
    query_options.candidate_floor = 1.01;
    place_recognition::FabMap floored(tree, options);
    EXPECT_DOUBLE_EQ(
        evaluation::SummarizePlaceRecognition(
            evaluation::RunFabMapQueries(passes.frames, truth, query_options, &floored).results)
            .candidate_recall_at_5,
        0.0);
    const evaluation::PlaceMapShape shape =
        evaluation::DescribePlaces(passes.frames, truth, queries.place_of_frame);
    EXPECT_EQ(shape.revisited_locations, 10);
    // Updating: the first pass makes ten places, the revisits update them; a revisited location
    // is one place, but for frames 18 and 19, which ground truth also joins to each other (their
    // locations hold places 8 and 9).
    if (mode == evaluation::PlacesMode::kUpdate) {
      EXPECT_EQ(summary.declared_new, 10);
      EXPECT_EQ(fabmap.places().size(), 10);
      EXPECT_EQ(shape.places, 10);
      EXPECT_DOUBLE_EQ(shape.largest_place_share, 2.0 / 20);
      EXPECT_DOUBLE_EQ(shape.places_per_revisited_location, (8 * 1 + 2 * 2) / 10.0);
    } else {
      EXPECT_EQ(fabmap.places().size(), 20);
      EXPECT_EQ(shape.places, 20);
      EXPECT_DOUBLE_EQ(shape.largest_place_share, 1.0 / 20);
      EXPECT_DOUBLE_EQ(shape.places_per_revisited_location, (8 * 2 + 2 * 3) / 10.0);
    }
  }

  TfIdfIndex index(TfIdfIndex::InverseDocumentFrequency(passes.training, 300));
  const std::vector<PlaceQueryResult> results =
      evaluation::RunTfIdfQueries(passes.frames, truth, &index);
  ASSERT_EQ(results.size(), 20u);
  for (int j = 10; j < 20; ++j) {
    EXPECT_EQ(results[static_cast<std::size_t>(j)].best_frame, j - 10);
    EXPECT_EQ(results[static_cast<std::size_t>(j)].true_candidate_rank, 0);
  }
  const evaluation::PlaceRecognitionSummary summary =
      evaluation::SummarizePlaceRecognition(results);
  EXPECT_EQ(summary.queries_with_true_match, 10);
  EXPECT_DOUBLE_EQ(summary.recall_at_full_precision, 1.0);
  EXPECT_EQ(summary.declared_new, 0);  // tf-idf has no new-place decision
}

// A relocalization attempt is scored against the chain without joining it: Peek gives what
// Push would, and the chain goes on as if the attempt had not been made.
TEST(SequenceScore, PeekScoresAViewWithoutAddingItToTheChain) {
  std::vector<std::vector<double>> queries(4, std::vector<double>(8, -5.0));
  for (int t = 0; t < 4; ++t)
    queries[static_cast<std::size_t>(t)][static_cast<std::size_t>(1 + t)] = 7;
  place_recognition::SequenceScore peeked({3, 1}), pushed({3, 1});
  for (int t = 0; t < 3; ++t) {
    peeked.Push(queries[static_cast<std::size_t>(t)]);
    pushed.Push(queries[static_cast<std::size_t>(t)]);
  }
  std::vector<double> attempt(8, -5.0);
  attempt[6] = 30;  // a look-alike the chain does not lead to
  EXPECT_EQ(peeked.Peek(attempt), pushed.Push(attempt));
  EXPECT_DOUBLE_EQ(peeked.Peek(attempt)[6], 30) << "its own evidence, nothing from the chain";
  EXPECT_DOUBLE_EQ(peeked.Peek(queries[3])[4], 21) << "three of the chain's sevens";
  // The attempt left no trace: the next query continues the chain of the first three.
  EXPECT_DOUBLE_EQ(peeked.Push(queries[3])[4], 21);
}

// A revisit run through places 2, 3, 4 (log odds 10 each), and at the last query a look-alike
// at place 9 (15) where the earlier queries saw nothing like it (-20).
TEST(SequenceScore, AChainOfNeighbouringMatchesOutranksALoneLookAlike) {
  const double inf = std::numeric_limits<double>::infinity();
  std::vector<std::vector<double>> queries(3, std::vector<double>(10, -20.0));
  for (int t = 0; t < 3; ++t) queries[t][static_cast<std::size_t>(2 + t)] = 10;
  queries[2][9] = 15;
  queries[2][0] = -inf;  // no candidate (the recent past)
  place_recognition::SequenceScore alone({1, 3});
  std::vector<double> scores;
  for (const auto& query : queries) scores = alone.Push(query);
  EXPECT_EQ(scores, queries[2]);  // length 1: the log odds themselves

  place_recognition::SequenceScore sequence({3, 1});
  for (const auto& query : queries) scores = sequence.Push(query);
  EXPECT_DOUBLE_EQ(scores[4], 30.0);  // 2 -> 3 -> 4
  // The look-alike keeps its own view's log odds (a chain may start at any query: the views
  // before it showed new places), and nothing near it before adds to them.
  EXPECT_DOUBLE_EQ(scores[9], 15.0);
  EXPECT_DOUBLE_EQ(scores[5], -20.0);  // a step past the run's end: no chain reaches it
  EXPECT_EQ(scores[0], -inf);          // no candidate stays none
  // A run walked the other way, 4 -> 3 -> 2, is a chain too.
  place_recognition::SequenceScore backwards({3, 1});
  for (int t = 0; t < 3; ++t) {
    std::vector<double> query(10, -20.0);
    query[static_cast<std::size_t>(4 - t)] = 10;
    scores = backwards.Push(query);
  }
  EXPECT_DOUBLE_EQ(scores[2], 30.0);
  // Places added since an earlier query add nothing there; a reset starts chains afresh.
  backwards.Reset();
  scores = backwards.Push(std::vector<double>(12, 1.0));
  EXPECT_DOUBLE_EQ(scores[11], 1.0);
  scores = backwards.Push(std::vector<double>(13, 1.0));
  EXPECT_DOUBLE_EQ(scores[12], 1.0 + 1.0);  // place 11 is a step away
  EXPECT_THROW(place_recognition::SequenceScore({0, 3}), std::invalid_argument);
  EXPECT_THROW(place_recognition::SequenceScore({3, -1}), std::invalid_argument);
}

// The two passes, with frame 15 (a revisit of place 5) showing place 8's words instead: alone it
// picks the look-alike, in a sequence of three the run 3 -> 4 -> 5 of its neighbours places it.
TEST(PlaceRecognitionQueries, ASequenceOfQueriesOutranksALookAlike) {
  TwoPasses passes = MakeTwoPasses();
  passes.frames.word_sets[15] = passes.frames.word_sets[18];
  passes.frames.words = passes.frames.word_sets;
  const PlaceGroundTruth truth(passes.same);
  const place_recognition::ChowLiuTree tree =
      place_recognition::ChowLiuTree::Train(passes.training, 300);
  place_recognition::FabMapOptions options;
  evaluation::FabMapQueryOptions query_options;
  {
    place_recognition::FabMap fabmap(tree, options);
    const auto results =
        evaluation::RunFabMapQueries(passes.frames, truth, query_options, &fabmap).results;
    EXPECT_EQ(results[15].best_frame, 8);
    EXPECT_FALSE(results[15].is_true);
  }
  query_options.sequence.length = 3;
  // Each hand-made place is a location of its own (unlike frames at 5 Hz, several a metre): a
  // chain moves one place per query.
  query_options.sequence.max_step = 1;
  place_recognition::FabMap fabmap(tree, options);
  const auto results =
      evaluation::RunFabMapQueries(passes.frames, truth, query_options, &fabmap).results;
  for (int j = 12; j < 20; ++j) {
    SCOPED_TRACE(j);
    const PlaceQueryResult& result = results[static_cast<std::size_t>(j)];
    if (j == 15) {
      // Its own words say nothing of place 5: the run places it, to within its step.
      EXPECT_NEAR(result.best_frame, 5, 1);
    } else {
      EXPECT_EQ(result.best_frame, j - 10);
      EXPECT_TRUE(result.is_true);
    }
  }
}

TEST(PlaceRecognitionQueries, CandidateRecallCountsTrueAnswersAmongTheBestK) {
  // Six queries with a true match whose true answer ranks 0, 1, 2, 4, beyond the ranking, and
  // 0; one without a true match (its rank does not count).
  std::vector<PlaceQueryResult> results;
  for (const int rank : {0, 1, 2, 4, -1, 0}) {
    PlaceQueryResult result;
    result.has_candidates = result.has_true_match = true;
    result.true_candidate_rank = rank;
    results.push_back(result);
  }
  PlaceQueryResult no_match;
  no_match.has_candidates = true;
  no_match.true_candidate_rank = 0;
  results.push_back(no_match);
  EXPECT_DOUBLE_EQ(evaluation::CandidateRecall(results, 1), 2.0 / 6);
  EXPECT_DOUBLE_EQ(evaluation::CandidateRecall(results, 3), 4.0 / 6);
  EXPECT_DOUBLE_EQ(evaluation::CandidateRecall(results, 5), 5.0 / 6);
  EXPECT_THROW(evaluation::CandidateRecall(results, 0), std::invalid_argument);
  EXPECT_THROW(evaluation::CandidateRecall(results, PlaceQueryResult::kRankedCandidates + 1),
               std::invalid_argument);
  EXPECT_DOUBLE_EQ(evaluation::CandidateRecall({no_match}, 1), 0.0);
}

// A place that swallows a corridor: frames 0, 3, 4 and 5 in one place. Frame 3 revisits frame 0
// and frame 4 frame 1 (window: one frame).
TEST(PlaceRecognitionQueries, DescribePlacesFindsAPlaceThatSwallowsACorridor) {
  evaluation::PlaceRecognitionFrames frames;
  frames.times = {0, 1, 2, 3, 4, 5};
  frames.words = frames.word_sets = std::vector<std::vector<int>>(6, std::vector<int>{1});
  frames.window = 1;
  cv::Mat same = cv::Mat::eye(6, 6, CV_8U);
  same.at<unsigned char>(0, 3) = same.at<unsigned char>(1, 4) = 1;
  const PlaceGroundTruth truth(same);
  const evaluation::PlaceMapShape shape =
      evaluation::DescribePlaces(frames, truth, {0, 1, 2, 0, 0, 0});
  EXPECT_EQ(shape.places, 3);
  EXPECT_EQ(shape.largest_place_frames, 4);
  EXPECT_DOUBLE_EQ(shape.largest_place_share, 4.0 / 6);
  EXPECT_EQ(shape.revisited_locations, 2);
  // Frame 3's location (frames 0 and 3) is one place; frame 4's (1 and 4) is two.
  EXPECT_DOUBLE_EQ(shape.places_per_revisited_location, (1 + 2) / 2.0);
  EXPECT_THROW(evaluation::DescribePlaces(frames, truth, {0, 1}), std::invalid_argument);
  EXPECT_THROW(evaluation::DescribePlaces(frames, truth, {0, 1, 2, -1, 0, 0}),
               std::invalid_argument);
}

TEST(PlaceRecognitionQueries, RefusesMismatchedInput) {
  TwoPasses passes = MakeTwoPasses();
  const PlaceGroundTruth truth(cv::Mat::eye(19, 19, CV_8U));
  TfIdfIndex index(std::vector<double>(300, 1.0));
  EXPECT_THROW(evaluation::RunTfIdfQueries(passes.frames, truth, &index), std::invalid_argument);
}

}  // namespace
}  // namespace stereo_fabmap_slam::test
