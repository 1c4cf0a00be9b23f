// evaluate_place_recognition end to end (issue 10): the same rendered places seen twice, as a
// EuRoC-layout sequence with ground-truth poses and as an image folder with a ground-truth
// matrix, the figure on MH01_first10s, and updated places in the rendered office.
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "test_support.h"

namespace stereo_fabmap_slam::test {
namespace {

namespace fs = std::filesystem;

// Rows of place_recognition_summary.csv by "method/mode", each column by its header name.
std::map<std::string, std::map<std::string, std::string>> ReadSummary(const std::string& path) {
  std::istringstream text(ReadTextFile(path));
  std::string line;
  std::getline(text, line);
  std::vector<std::string> header;
  std::stringstream names(line);
  for (std::string name; std::getline(names, name, ',');) header.push_back(name);
  std::map<std::string, std::map<std::string, std::string>> rows;
  while (std::getline(text, line)) {
    std::stringstream fields(line);
    std::map<std::string, std::string> row;
    std::string field;
    for (std::size_t i = 0; i < header.size() && std::getline(fields, field, ','); ++i)
      row[header[i]] = field;
    rows[row["method"] + "/" + row["mode"]] = row;
  }
  return rows;
}

double Value(const std::map<std::string, std::map<std::string, std::string>>& summary,
             const std::string& run, const std::string& column) {
  const auto row = summary.find(run);
  if (row == summary.end() || row->second.count(column) == 0) {
    ADD_FAILURE() << "no " << column << " for " << run;
    return -1;
  }
  return std::stod(row->second.at(column));
}

// Lines of a EuRoC CSV with the stamp (first field) shifted; `rename` also renames the file
// named in the second field to "<new stamp>.png".
std::string ShiftedRows(const std::string& csv, std::int64_t shift_ns, bool rename,
                        std::vector<std::pair<std::string, std::string>>* renamed) {
  std::istringstream lines(csv);
  std::string result;
  for (std::string line; std::getline(lines, line);) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty() || line[0] == '#') continue;
    const std::size_t comma = line.find(',');
    const std::string stamp = std::to_string(std::stoll(line.substr(0, comma)) + shift_ns);
    if (rename) {
      renamed->emplace_back(line.substr(comma + 1), stamp + ".png");
      result += stamp + "," + stamp + ".png\n";
    } else {
      result += stamp + line.substr(comma) + "\n";
    }
  }
  return result;
}

class RenderedTwice : public ::testing::Test {
 protected:
  // 4 s of the rendered loop (80 frames), once.
  static void SetUpTestSuite() {
    temp_ = new TemporaryDirectory();
    std::string output;
    ASSERT_EQ(RunCommand(std::string(MAKE_SYNTHETIC_SEQUENCE_BIN) + " --output " + temp_->path() +
                             "/once --route loop --seconds 4 --seed 1 --no-bag 2>&1",
                         &output),
              0)
        << output;
  }
  static void TearDownTestSuite() {
    delete temp_;
    temp_ = nullptr;
  }
  static TemporaryDirectory* temp_;
};

TemporaryDirectory* RenderedTwice::temp_ = nullptr;

// The same images again 5.55 s later, ground truth and all: the second pass revisits every
// place of the first exactly, and its frames' twins lie 5.55 s back, outside the default 5 s
// window, while the first pass has no frame old enough to be a candidate. (Not 5.5 s: pairs
// exactly 5 s apart would sit on the window's edge, decided by rounding.)
TEST_F(RenderedTwice, SequenceWithPosesFindsEveryRevisit) {
  const fs::path once = fs::path(temp_->path()) / "once/mav0";
  const fs::path twice = fs::path(temp_->path()) / "twice/mav0";
  ASSERT_TRUE(CopyTree(once.parent_path().string(), twice.parent_path().string()));
  const std::int64_t shift = 5'550'000'000;
  for (const char* camera : {"cam0", "cam1"}) {
    const std::string csv = ReadTextFile((once / camera / "data.csv").string());
    std::vector<std::pair<std::string, std::string>> renamed;
    const std::string again = ShiftedRows(csv, shift, true, &renamed);
    for (const auto& [from, to] : renamed)
      fs::copy_file(once / camera / "data" / from, twice / camera / "data" / to);
    WriteTextFile((twice / camera / "data.csv").string(), csv + again);
  }
  const fs::path truth = fs::path("state_groundtruth_estimate0") / "data.csv";
  const std::string poses = ReadTextFile((once / truth).string());
  WriteTextFile((twice / truth).string(), poses + ShiftedRows(poses, shift, false, nullptr));

  std::string output;
  const std::string out = temp_->path() + "/twice_out";
  ASSERT_EQ(RunCommand(std::string(EVALUATE_PLACE_RECOGNITION_BIN) + " " +
                           twice.parent_path().string() + " --every 2 --output " + out + " --json",
                       &output),
            0)
      << output;
  EXPECT_EQ(output.rfind("{\"source\": ", 0), 0u) << output;
  const auto summary = ReadSummary(out + "/place_recognition_summary.csv");
  RecordProperty("summary", ReadTextFile(out + "/place_recognition_summary.csv"));
  for (const char* run : {"fabmap/per-image", "fabmap/update", "tfidf/per-image"}) {
    SCOPED_TRACE(run);
    // 40 frames a pass: every frame of the second pass, and only those, has a true match (its
    // twin); pairs within 5 s: the first pass's 40 x 39 / 2, the same in the second, and
    // between them the 34 x 35 / 2 no more than 5 s apart (second-pass frame a, first-pass
    // frame b, 0.1 s apart each: 5.55 + 0.1 a - 0.1 b <= 5 for b >= a + 6).
    EXPECT_EQ(Value(summary, run, "queries"), 40);
    EXPECT_EQ(Value(summary, run, "queries_with_true_match"), 40);
    EXPECT_EQ(Value(summary, run, "excluded_pairs"), 2 * 780 + 595);
    // Identical images differ in words only where the stream-adapted detector thresholds
    // differ; one query in ten may go to a look-alike view of the hall's repeated photos.
    EXPECT_GE(Value(summary, run, "recall_at_100_precision"), 0.9);
    EXPECT_GE(Value(summary, run, "auc"), 0.9);
    // The twin is the best candidate as often as it is the accepted answer, and a longer list
    // of candidates can only hold it more often.
    EXPECT_GE(Value(summary, run, "candidate_recall_at_1"), 0.9);
    EXPECT_LE(Value(summary, run, "candidate_recall_at_1"),
              Value(summary, run, "candidate_recall_at_3"));
    EXPECT_LE(Value(summary, run, "candidate_recall_at_3"),
              Value(summary, run, "candidate_recall_at_5"));
  }
  // One place per image: 80 places, none larger than one frame; a revisited location is a
  // frame, its twin and the neighbours within its view (tau 0.5): several places. Updating
  // merges them.
  EXPECT_EQ(Value(summary, "fabmap/per-image", "places"), 80);
  EXPECT_DOUBLE_EQ(Value(summary, "fabmap/per-image", "largest_place_share"), 1.0 / 80);
  EXPECT_GE(Value(summary, "fabmap/per-image", "places_per_revisited_location"), 2.0);
  EXPECT_LT(Value(summary, "fabmap/update", "places"), 80);
  EXPECT_LT(Value(summary, "fabmap/update", "places_per_revisited_location"),
            Value(summary, "fabmap/per-image", "places_per_revisited_location"));
  const std::string pr = ReadTextFile(out + "/place_recognition_pr.csv");
  EXPECT_EQ(pr.rfind("method,mode,threshold,precision,recall,declared,correct\n", 0), 0u);
  EXPECT_NE(ReadTextFile(out + "/place_recognition_queries.csv").find("\nfabmap,update,"),
            std::string::npos);
}

// The same pass twice as an image folder with a benchmark's matrix: frames within 2 of each
// other (0.2 s, 0.2 m) are the same place, in a pass and across the two.
TEST_F(RenderedTwice, ImageFolderWithMatrixFindsEveryRevisit) {
  const fs::path once = fs::path(temp_->path()) / "once/mav0/cam0";
  const fs::path folder = fs::path(temp_->path()) / "folder";
  fs::create_directories(folder);
  std::istringstream lines(ReadTextFile((once / "data.csv").string()));
  std::vector<std::string> images;
  for (std::string line; std::getline(lines, line);) {
    if (line.empty() || line[0] == '#') continue;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    images.push_back(line.substr(line.find(',') + 1));
  }
  ASSERT_EQ(images.size(), 80u);
  const int n = 40;  // every second frame
  for (int pass = 0; pass < 2; ++pass) {
    for (int i = 0; i < n; ++i) {
      char name[32];
      std::snprintf(name, sizeof(name), "%03d.png", pass * n + i);
      fs::copy_file(once / "data" / images[static_cast<std::size_t>(2 * i)], folder / name);
    }
  }
  std::string matrix;
  for (int a = 0; a < 2 * n; ++a) {
    for (int b = 0; b < 2 * n; ++b)
      matrix += std::string(b > 0 ? "," : "") + (std::abs(a % n - b % n) <= 2 ? "1" : "0");
    matrix += "\n";
  }
  WriteTextFile(temp_->path() + "/matrix.csv", matrix);

  std::string output;
  const std::string out = temp_->path() + "/folder_out";
  const std::string command = std::string(EVALUATE_PLACE_RECOGNITION_BIN) + " " + folder.string() +
                              " --gt " + temp_->path() + "/matrix.csv --exclude-frames " +
                              std::to_string(n - 1) + " --output " + out;
  ASSERT_EQ(RunCommand(command + " 2>/dev/null", &output), 0) << output;
  EXPECT_NE(output.find("recall@P1"), std::string::npos) << output;
  const auto summary = ReadSummary(out + "/place_recognition_summary.csv");
  for (const char* run : {"fabmap/per-image", "fabmap/update", "tfidf/per-image"}) {
    SCOPED_TRACE(run);
    EXPECT_EQ(Value(summary, run, "queries"), n);  // the second pass
    EXPECT_EQ(Value(summary, run, "queries_with_true_match"), n);
    // As above, except for updated places: the matrix makes a place 5 frames (0.4 m) wide, and
    // FabMap::Add merges the first pass into wider ones (4 places of 3, 7, 26 and 4 frames), so a
    // query whose twin lies at a place's end may go to the neighbouring place. One did (twin
    // frame 12, matched to the place of frames 3-9) and outranks 6 right answers: 0.85. Two more
    // queries may be lost before the test asks for a look.
    const bool updated = std::string(run) == "fabmap/update";
    EXPECT_GE(Value(summary, run, "recall_at_100_precision"), updated ? 0.8 : 0.9);
  }
  // A matrix that does not fit the folder is an error, not a measurement.
  WriteTextFile(temp_->path() + "/small.csv", "1,0\n0,1\n");
  EXPECT_EQ(RunCommand(std::string(EVALUATE_PLACE_RECOGNITION_BIN) + " " + folder.string() +
                           " --gt " + temp_->path() + "/small.csv 2>&1",
                       &output),
            1);
  EXPECT_NE(output.find("2 x 2 matrix for 80 images"), std::string::npos) << output;
}

// Place recognition on real data: MH01's first 10 s (200 frames, 83 queries with a true match
// outside the 5 s window). The bounds hold for the property, not for one vocabulary: they are
// derived from four vocabularies trained as `make` trains the default, with the k-means seeds
// 1 (shipped), 2, 3 and 4 of config/fabmap.yaml (docs/benchmarks.md):
// - places updated on revisits (FabMap::Add) declare no false match at the default threshold
//   (precision 1 with all four), recall 82-98 % of the queries at 100 % precision (92.8 % with
//   the shipped seed) and beat tf-idf over the same words (29-57 %): at least 75 %, which is 5
//   queries below the lowest;
// - one place per image (what the SLAM map keeps) ranks true matches above false ones: area
//   under the precision-recall curve 0.80-0.89, at least 0.75. Its recall at 100 % precision
//   swings with the vocabulary (7, 13, 30 and 61 %: one confident false match decides it) and
//   is recorded, not bounded.
TEST(EvaluatePlaceRecognitionTool, Mh01RecallAtFullPrecision) {
  TemporaryDirectory temp;
  std::string output;
  ASSERT_EQ(RunCommand(std::string(EVALUATE_PLACE_RECOGNITION_BIN) + " " +
                           EurocSequencePath("MH01_first10s") + " --output " + temp.path() +
                           " --json 2>/dev/null",
                       &output),
            0)
      << output;
  const auto summary = ReadSummary(temp.path() + "/place_recognition_summary.csv");
  RecordProperty("summary", ReadTextFile(temp.path() + "/place_recognition_summary.csv"));
  EXPECT_GT(Value(summary, "fabmap/update", "queries_with_true_match"), 50);
  EXPECT_GT(Value(summary, "fabmap/update", "excluded_pairs"), 0);
  const double updated = Value(summary, "fabmap/update", "recall_at_100_precision");
  EXPECT_GE(updated, 0.75);
  EXPECT_GE(updated, Value(summary, "tfidf/per-image", "recall_at_100_precision"));
  EXPECT_EQ(Value(summary, "fabmap/update", "precision_at_default"), 1.0);
  EXPECT_GE(Value(summary, "fabmap/per-image", "auc"), 0.75);
}

// Perceptual aliasing: the rendered hall hangs the same photographs on several walls, and the
// figure eight (40 s, seed 2: 455 queries with a true match) sees them from places 5-11 m
// apart. With places updated on revisits, no match FAB-MAP declares at the default threshold
// (fabmap.match_log_odds) may be false. With the four vocabularies above: precision 1 with each,
// recall at the default 21.3-27.0 % (25.3 % shipped), at 100 % precision 28.6-29.5 % against
// tf-idf's 0.7-4.0 %. At least 15 % at the default: 27 queries below the lowest. Those figures
// were measured with the visibility test alone (--max-distance inf), which counts the views
// across the hall as revisits: the bounds hold for that relation, so the test keeps it. (With the
// default 3 m, 174 queries have a true match; shipped vocabulary: precision 1, recall 66 %.)
TEST(EvaluatePlaceRecognitionTool, RepeatedPhotographsGiveNoFalseMatchAtTheDefaultThreshold) {
  TemporaryDirectory temp;
  std::string output;
  ASSERT_EQ(RunCommand(std::string(MAKE_SYNTHETIC_SEQUENCE_BIN) + " --output " + temp.path() +
                           "/figure8 --route figure8 --seconds 40 --seed 2 --no-bag 2>&1",
                       &output),
            0)
      << output;
  ASSERT_EQ(RunCommand(std::string(EVALUATE_PLACE_RECOGNITION_BIN) + " " + temp.path() +
                           "/figure8 --places update --max-distance inf --output " + temp.path() +
                           " 2>/dev/null",
                       &output),
            0)
      << output;
  const auto summary = ReadSummary(temp.path() + "/place_recognition_summary.csv");
  RecordProperty("summary", ReadTextFile(temp.path() + "/place_recognition_summary.csv"));
  EXPECT_GT(Value(summary, "fabmap/update", "queries_with_true_match"), 400);
  EXPECT_EQ(Value(summary, "fabmap/update", "precision_at_default"), 1.0);
  EXPECT_GE(Value(summary, "fabmap/update", "recall_at_default"), 0.15);
  EXPECT_GE(Value(summary, "fabmap/update", "recall_at_100_precision"),
            Value(summary, "tfidf/per-image", "recall_at_100_precision"));
}

// Updated places in the office (issue 32): 90 s of the office loop (the sequence
// loop_closing_test maps), a lap of corridors of identical doors and the first corridor again.
// By appearance alone places swallow corridors (measured: one place holds 60 % of the frames);
// with the odometry's poses (the default on a sequence) a place takes views within 1 m and
// 20 deg of where it was founded, at most 2 m of path per pass, about 2 % of the route's 90 m a
// pass: the 10 % leaves room for the slow turns at corridor ends (measured 2.7 %). The
// corridor walked twice stays many places, and smaller places rank revisits better.
TEST(EvaluatePlaceRecognitionTool, UpdatedPlacesInTheOfficeStayNearWhereTheyWereFounded) {
  const std::string sequence = SharedSyntheticSequence(MAKE_SYNTHETIC_SEQUENCE_BIN, "loop", 90, 21,
                                                       "office", /*with_bag=*/false);
  ASSERT_FALSE(sequence.empty());
  TemporaryDirectory temp;
  std::map<std::string, std::map<std::string, std::map<std::string, std::string>>> summaries;
  for (const std::string odometry : {"", " --no-odometry"}) {
    std::string output;
    const std::string out = temp.path() + "/out" + (odometry.empty() ? "" : "_appearance");
    ASSERT_EQ(RunCommand(std::string(EVALUATE_PLACE_RECOGNITION_BIN) + " " + sequence +
                             " --every 4 --places update" + odometry + " --output " + out + " 2>&1",
                         &output),
              0)
        << output;
    summaries[odometry] = ReadSummary(out + "/place_recognition_summary.csv");
    RecordProperty("summary" + odometry, ReadTextFile(out + "/place_recognition_summary.csv"));
  }
  const auto& with_odometry = summaries[""];
  const auto& appearance = summaries[" --no-odometry"];
  EXPECT_GT(Value(with_odometry, "fabmap/update", "queries_with_true_match"), 40);
  EXPECT_LE(Value(with_odometry, "fabmap/update", "largest_place_share"), 0.10);
  EXPECT_LT(Value(with_odometry, "fabmap/update", "largest_place_share"),
            Value(appearance, "fabmap/update", "largest_place_share"));
  EXPECT_GE(Value(with_odometry, "fabmap/update", "recall_at_100_precision"),
            Value(appearance, "fabmap/update", "recall_at_100_precision"));
}

TEST(EvaluatePlaceRecognitionTool, InputWithoutImagesIsAnError) {
  TemporaryDirectory temp;
  std::string output;
  EXPECT_NE(RunCommand(std::string(EVALUATE_PLACE_RECOGNITION_BIN) + " " + temp.path() + " 2>&1",
                       &output),
            0);
  WriteTextFile(temp.path() + "/gt.csv", "1\n");
  EXPECT_NE(RunCommand(std::string(EVALUATE_PLACE_RECOGNITION_BIN) + " " + temp.path() + " --gt " +
                           temp.path() + "/gt.csv 2>&1",
                       &output),
            0);
  EXPECT_NE(output.find("no images"), std::string::npos) << output;
}

}  // namespace
}  // namespace stereo_fabmap_slam::test
