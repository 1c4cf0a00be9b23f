// FAB-MAP alone against ground truth (issue 10, part 1): every frame of a EuRoC-layout sequence
// or an image folder is a query against the places of the frames before it, with one place per
// image or places updated on revisits, and the same queries with a plain tf-idf score as the
// baseline. Precision-recall from sweeping the acceptance threshold, recall at 100 % precision
// as the headline. Writes place_recognition_pr.csv, place_recognition_summary.csv and
// place_recognition_queries.csv, and prints a table (or one JSON object).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <fstream>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "command_line.h"
#include "fabmap_files.h"
#include "image_sources.h"
#include "slam_configuration.h"
#include "stereo_fabmap_slam/camera/stereo_rectifier.h"
#include "stereo_fabmap_slam/datasets/euroc_sequence.h"
#include "stereo_fabmap_slam/evaluation/place_ground_truth.h"
#include "stereo_fabmap_slam/evaluation/place_recognition_precision_recall.h"
#include "stereo_fabmap_slam/evaluation/place_recognition_queries.h"
#include "stereo_fabmap_slam/evaluation/pose_interpolation.h"
#include "stereo_fabmap_slam/evaluation/trajectory.h"
#include "stereo_fabmap_slam/features/stereo_feature_extractor.h"
#include "stereo_fabmap_slam/pipeline/stereo_slam.h"
#include "stereo_fabmap_slam/place_recognition/detector_model.h"
#include "stereo_fabmap_slam/place_recognition/fab_map.h"
#include "stereo_fabmap_slam/place_recognition/image_describer.h"
#include "stereo_fabmap_slam/place_recognition/place_recognition_options.h"
#include "stereo_fabmap_slam/place_recognition/tf_idf_index.h"
#include "stereo_fabmap_slam/place_recognition/vocabulary.h"

namespace {

using namespace stereo_fabmap_slam;  // NOLINT: a tool's main file
namespace fs = std::filesystem;

constexpr char kUsage[] =
    "usage: evaluate_place_recognition ASL_DIR [--tau T] [--mutual] [--max-distance D]\n"
    "                                  [--exclude-seconds S]\n"
    "       evaluate_place_recognition IMAGE_DIR --gt FILE [--exclude-frames K]\n"
    "           [--places per-image|update|both] [--every N] [--sequence L] [--vocabulary FILE]\n"
    "           [--config FILE] [--fabmap-config FILE] [--output DIR] [--json] [--no-odometry]\n"
    "Each frame in turn is a query against the earlier frames' places; FAB-MAP answers with\n"
    "its best place and posterior, a plain tf-idf bag-of-words score over the same words with\n"
    "the best earlier image and its cosine. Sweeping the acceptance threshold gives\n"
    "precision-recall against ground truth; the headline is the recall at 100 % precision.\n"
    "  ASL_DIR            EuRoC layout with ground truth: two frames show the same place when\n"
    "                     at least T (--tau, default 0.5) of one frame's stereo points land in\n"
    "                     the other's image, carried there by the ground-truth poses;\n"
    "                     --mutual: each frame must see T of the other's points (looking\n"
    "                     down a corridor, the view from far back sees the doors ahead, not\n"
    "                     the other way round); --max-distance D: cameras at most D m apart\n"
    "                     (default 3; inf for none)\n"
    "  --gt F             for an image folder (*.png, *.jpg in name order): an N x N matrix,\n"
    "                     CSV/text of N rows of N numbers or a grey N x N image, non-zero =\n"
    "                     same place\n"
    "  --exclude-seconds  earlier frames at most S seconds (default 5) before a query are\n"
    "                     neither loop candidates nor loops; --exclude-frames K (default 5)\n"
    "                     for folders, in frames\n"
    "  --places           per-image: every image a place of its own; update: FabMap::Add\n"
    "                     updates the best place when it matches; both (default). On a\n"
    "                     sequence, update mode runs the stereo odometry first: a view updates\n"
    "                     only a place founded within fabmap.max_place_extent and\n"
    "                     max_place_turn_deg of it in the same odometry segment\n"
    "                     (--no-odometry: appearance alone, as in a folder)\n"
    "  --every N          every N-th frame only (default 1)\n"
    "  --sequence L       FAB-MAP ranks places by the summed log odds along the best chain of\n"
    "                     the last L queries over neighbouring places, as the loop detector\n"
    "                     does (default: loop_detection.sequence_length of the config; 1: each\n"
    "                     query alone)\n"
    "  --vocabulary FILE  vocabulary.bin with chow_liu_tree.bin and training_places.bin beside\n"
    "                     it (default: vocabulary_directory of config/fabmap.yaml); the training\n"
    "                     places also give tf-idf's inverse document frequencies\n"
    "  --output DIR       place_recognition_pr.csv (method,mode,threshold,precision,recall,\n"
    "                     declared,correct), place_recognition_summary.csv, and\n"
    "                     place_recognition_queries.csv (one row per method, mode and query)\n"
    "  --json             print one summary object instead of the table\n"
    "FAB-MAP's answers are ranked by their log odds against a new place; precision and recall\n"
    "at fabmap.match_log_odds (the default threshold, 0) are reported beside the curve.\n"
    "What the loop detector needs: candidate recall @1/3/5 (of the queries with a true match,\n"
    "those whose true place is among FAB-MAP's K best candidates as the loop detector picks\n"
    "them for geometric verification: by sequence score (or, with a sequence of 1, posterior at\n"
    "least loop_detection.min_probability) of at least loop_detection.min_log_odds; tf-idf: its\n"
    "K best images); and for FAB-MAP's places the count, the largest place's share of all frames\n"
    "and the mean number of places among the frames of a revisited location (1 is ideal).\n";

double NowSeconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

std::string Number(double value) {
  if (std::isnan(value)) return "";
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%.6g", value);
  return buffer;
}

// Frames as place recognition sees them, their names, and the ground truth among them.
struct Input {
  evaluation::PlaceRecognitionFrames frames;
  std::vector<std::string> names;
  std::optional<evaluation::PlaceGroundTruth> truth;
  std::string window_unit;  // "s" or "frames"
};

void AddWords(const place_recognition::Vocabulary& vocabulary, const cv::Mat& descriptors,
              Input* input) {
  std::vector<int> words = vocabulary.Quantize(descriptors);
  std::vector<int> set(words);
  std::sort(set.begin(), set.end());
  set.erase(std::unique(set.begin(), set.end()), set.end());
  input->frames.words.push_back(std::move(words));
  input->frames.word_sets.push_back(std::move(set));
}

// The stereo odometry alone (StereoSlam without loop closing), fed every pair of the sequence
// in order: where it put each pair's rectified left camera, and in which segment: every lost
// frame starts the next, also one whose map the tracker kept (conservative: places of the two
// sides are then never one). Only what the running system itself knows; ground truth stays for
// judging.
class OdometryFollower {
 public:
  OdometryFollower(const camera::StereoRectifier& rectifier,
                   const tools::SlamConfiguration& options)
      : slam_(options.front_end, options.bundle_adjustment, rectifier,
              [] { return NowSeconds() * 1e3; }) {}

  place_recognition::ViewPose Follow(const datasets::StereoImages& images) {
    const pipeline::FrameRecord* frame =
        slam_.ProcessFrame(images.timestamp_ns * 1e-9, images.left, images.right);
    place_recognition::ViewPose pose;  // segment -1: no pose
    if (frame == nullptr || frame->state == odometry::TrackingState::kLost) {
      lost_ = true;
      return pose;
    }
    if (lost_) ++segment_;
    lost_ = false;
    pose.segment = segment_;
    pose.T_world_camera = frame->T_world_camera;
    return pose;
  }

 private:
  pipeline::StereoSlam slam_;
  int segment_ = 0;
  bool lost_ = false;
};

// A EuRoC-layout sequence: words of the rectified left image (what a keyframe carries), and
// stereo points with the rectified left camera's ground-truth pose for the relevance test.
Input ReadSequence(const std::string& directory, int every,
                   const evaluation::PlaceRelevance& relevance, double window,
                   const tools::SlamConfiguration& options,
                   const place_recognition::PlaceRecognitionOptions& place_options,
                   const place_recognition::Vocabulary& vocabulary, bool with_odometry) {
  const datasets::EurocSequence sequence = datasets::EurocSequence::Open(directory);
  if (sequence.size() == 0) throw std::invalid_argument(directory + ": no images");
  if (!sequence.has_ground_truth()) {
    throw std::invalid_argument(directory + ": no ground truth (give an image folder with --gt)");
  }
  const camera::StereoRectifier rectifier =
      camera::StereoRectifier::FromCalibration(sequence.calibration(), options.rectification);
  // Ground truth is the body's pose; the points are in the rectified left camera (T_WB T_BS).
  const evaluation::Trajectory truth = evaluation::TransformToSensorFrame(
      sequence.ground_truth(), rectifier.T_body_rectified_left());
  // Every pair goes to the odometry; every `every`-th is also a query (one read of each).
  std::optional<OdometryFollower> odometry;
  if (with_odometry) odometry.emplace(rectifier, options);
  features::StereoFeatureExtractor extractor(options.front_end.features, options.front_end.stereo,
                                             rectifier.camera());
  place_recognition::ImageDescriber describer(place_options.features);
  Input input;
  input.frames.window = window;
  input.window_unit = "s";
  std::vector<std::vector<Eigen::Vector3d>> points;
  std::vector<std::optional<Eigen::Isometry3d>> poses;
  const double start = sequence.frames().front().timestamp_ns * 1e-9;
  const std::size_t total = (sequence.size() + every - 1) / every;
  std::size_t without_truth = 0;
  const std::size_t step = with_odometry ? 1 : static_cast<std::size_t>(every);
  for (std::size_t i = 0; i < sequence.size(); i += step) {
    const datasets::StereoImages images = sequence.LoadStereoPair(i);
    const place_recognition::ViewPose odometry_pose =
        odometry ? odometry->Follow(images) : place_recognition::ViewPose();
    if (i % static_cast<std::size_t>(every) != 0) continue;
    cv::Mat left, right;
    rectifier.Rectify(images.left, images.right, &left, &right);
    // Both in time order, as the odometry and the keyframes' describer see the stream (their
    // detectors adapt their thresholds from frame to frame).
    const features::StereoFeatures stereo = extractor.Extract(left, right);
    const cv::Mat descriptors = describer.Describe(left);
    // Ground truth at 200 Hz: a gap above 20 ms is missing data, not a pose to interpolate.
    const std::optional<Eigen::Isometry3d> pose =
        evaluation::InterpolatePose(truth, images.timestamp_ns * 1e-9, 0.02);
    // A frame without ground truth cannot be judged, as a query or as an answer: it is left
    // out (EuRoC's ground truth often starts a second after the images).
    if (!pose) {
      ++without_truth;
      continue;
    }
    AddWords(vocabulary, descriptors, &input);
    std::vector<Eigen::Vector3d> with_depth;
    for (std::size_t k = 0; k < stereo.size(); ++k) {
      if (stereo.HasDepth(k)) with_depth.push_back(stereo.points[k]);
    }
    points.push_back(std::move(with_depth));
    poses.push_back(pose);
    if (odometry) input.frames.odometry_poses.push_back(odometry_pose);
    input.frames.times.push_back(images.timestamp_ns * 1e-9 - start);
    input.names.push_back(fs::path(sequence.frames()[i].left_path).filename().string());
    const std::size_t done = points.size() + without_truth;
    if (done % 100 == 0 || done == total)
      std::fprintf(stderr, "features of %zu / %zu frames\n", done, total);
  }
  if (without_truth > 0) {
    std::fprintf(stderr, "%zu of %zu frames without ground truth left out\n", without_truth, total);
  }
  if (points.empty()) throw std::invalid_argument(directory + ": no frame has ground truth");
  std::fprintf(stderr, "ground truth of %zu frames (tau %.2f%s, within %g m)\n", points.size(),
               relevance.tau, relevance.mutual ? ", mutual" : "", relevance.max_distance);
  input.truth =
      evaluation::PlaceGroundTruth::FromPoses(points, poses, rectifier.camera(), relevance);
  return input;
}

// An image folder with a benchmark's N x N matrix over all its images.
Input ReadFolder(const std::string& directory, const std::string& matrix, int every,
                 double window_frames, const place_recognition::PlaceRecognitionOptions& options,
                 const place_recognition::Vocabulary& vocabulary) {
  if (fs::is_directory(directory + "/mav0") || fs::is_directory(directory + "/cam0"))
    throw std::invalid_argument("--gt is for image folders; a sequence has poses");
  // Every image first: the matrix covers all of them, also with --every.
  const std::vector<tools::ImageSource> all_images = tools::ListImages(directory, 1);
  const evaluation::PlaceGroundTruth all = evaluation::PlaceGroundTruth::Load(matrix);
  if (all.size() != static_cast<int>(all_images.size())) {
    throw std::invalid_argument(matrix + ": " + std::to_string(all.size()) + " x " +
                                std::to_string(all.size()) + " matrix for " +
                                std::to_string(all_images.size()) + " images in " + directory);
  }
  std::vector<tools::ImageSource> images;
  for (std::size_t i = 0; i < all_images.size(); i += static_cast<std::size_t>(every))
    images.push_back(all_images[i]);
  place_recognition::ImageDescriber describer(options.features);
  Input input;
  input.frames.window = window_frames;
  input.window_unit = "frames";
  std::vector<int> indices;
  for (const tools::ImageSource& image : images) {
    const cv::Mat pixels = cv::imread(image.path, cv::IMREAD_GRAYSCALE);
    if (pixels.empty()) throw std::runtime_error(image.path + ": cannot read image");
    AddWords(vocabulary, describer.Describe(pixels), &input);
    indices.push_back(static_cast<int>(std::lround(image.timestamp)));
    input.frames.times.push_back(image.timestamp);
    input.names.push_back(fs::path(image.path).filename().string());
    if (indices.size() % 100 == 0 || indices.size() == images.size())
      std::fprintf(stderr, "words of %zu / %zu images\n", indices.size(), images.size());
  }
  input.truth = all.Subset(indices);
  return input;
}

struct Run {
  std::string method, mode;
  std::vector<evaluation::PlaceQueryResult> results;
  std::vector<evaluation::PlacePrecisionRecallPoint> curve;
  evaluation::PlaceRecognitionSummary summary;
  // FAB-MAP: matches declared at the configured fabmap.match_log_odds; tf-idf has no default.
  std::optional<evaluation::PlacePrecisionRecallPoint> at_default;
  std::optional<evaluation::PlaceMapShape> shape;  // FAB-MAP: how the frames fell into places
  std::vector<int> place_of_frame;                 // FAB-MAP: the place each frame joined
  double seconds = 0;
};

std::string AtDefault(const Run& run, double evaluation::PlacePrecisionRecallPoint::*field) {
  return run.at_default ? Number((*run.at_default).*field) : "";
}

void WriteText(const std::string& path, const std::string& text) {
  std::ofstream file(path);
  file << text;
  if (!file) throw std::runtime_error("cannot write " + path);
}

void WriteOutputs(const std::string& directory, const Input& input,
                  const evaluation::ExcludedPairs& excluded, const std::vector<Run>& runs) {
  fs::create_directories(directory);
  std::string pr = "method,mode,threshold,precision,recall,declared,correct\n";
  std::string summary =
      "method,mode,queries,queries_with_true_match,excluded_pairs,excluded_same_place_pairs,"
      "recall_at_100_precision,auc,declared_new_places,seconds,default_threshold,"
      "precision_at_default,recall_at_default,candidate_recall_at_1,candidate_recall_at_3,"
      "candidate_recall_at_5,places,largest_place_share,places_per_revisited_location\n";
  std::string queries =
      "method,mode,query,image,time,best_place,best_frame,best_image,score,"
      "new_place_probability,declared_new,has_true_match,is_true,true_candidate_rank,place\n";
  for (const Run& run : runs) {
    const std::string prefix = run.method + "," + run.mode + ",";
    for (const evaluation::PlacePrecisionRecallPoint& point : run.curve) {
      pr += prefix + Number(point.threshold) + "," + Number(point.precision) + "," +
            Number(point.recall) + "," + std::to_string(point.declared) + "," +
            std::to_string(point.correct) + "\n";
    }
    summary += prefix + std::to_string(run.summary.queries) + "," +
               std::to_string(run.summary.queries_with_true_match) + "," +
               std::to_string(excluded.pairs) + "," + std::to_string(excluded.same_place) + "," +
               Number(run.summary.recall_at_full_precision) + "," + Number(run.summary.auc) + "," +
               (run.method == "fabmap" ? std::to_string(run.summary.declared_new) : "") + "," +
               Number(run.seconds) + "," +
               AtDefault(run, &evaluation::PlacePrecisionRecallPoint::threshold) + "," +
               AtDefault(run, &evaluation::PlacePrecisionRecallPoint::precision) + "," +
               AtDefault(run, &evaluation::PlacePrecisionRecallPoint::recall) + "," +
               Number(run.summary.candidate_recall_at_1) + "," +
               Number(run.summary.candidate_recall_at_3) + "," +
               Number(run.summary.candidate_recall_at_5) + "," +
               (run.shape ? std::to_string(run.shape->places) + "," +
                                Number(run.shape->largest_place_share) + "," +
                                Number(run.shape->places_per_revisited_location)
                          : ",,") +
               "\n";
    for (const evaluation::PlaceQueryResult& result : run.results) {
      const std::size_t q = static_cast<std::size_t>(result.query);
      queries +=
          prefix + std::to_string(result.query) + "," + input.names[q] + "," +
          Number(input.frames.times[q]) + "," + std::to_string(result.best_place) + "," +
          std::to_string(result.best_frame) + "," +
          (result.best_frame >= 0 ? input.names[static_cast<std::size_t>(result.best_frame)] : "") +
          "," + (result.best_place >= 0 ? Number(result.score) : "") + "," +
          Number(result.new_place_probability) + "," +
          (run.method == "fabmap" ? (result.declared_new ? "1" : "0") : "") + "," +
          (result.has_true_match ? "1" : "0") + "," + (result.is_true ? "1" : "0") + "," +
          (result.has_true_match ? std::to_string(result.true_candidate_rank) : "") + "," +
          (run.place_of_frame.empty() ? "" : std::to_string(run.place_of_frame[q])) + "\n";
    }
  }
  WriteText(directory + "/place_recognition_pr.csv", pr);
  WriteText(directory + "/place_recognition_summary.csv", summary);
  WriteText(directory + "/place_recognition_queries.csv", queries);
}

std::string SummaryJson(const std::string& source, const Input& input,
                        const evaluation::ExcludedPairs& excluded, const std::vector<Run>& runs) {
  std::string json =
      "{\"source\": \"" + source + "\", \"frames\": " + std::to_string(input.frames.size()) +
      ", \"window\": " + Number(input.frames.window) + ", \"window_unit\": \"" + input.window_unit +
      "\", \"excluded_pairs\": " + std::to_string(excluded.pairs) +
      ", \"excluded_same_place_pairs\": " + std::to_string(excluded.same_place) +
      ", \"results\": [";
  for (std::size_t i = 0; i < runs.size(); ++i) {
    const Run& run = runs[i];
    json +=
        std::string(i > 0 ? ", " : "") + "{\"method\": \"" + run.method + "\", \"mode\": \"" +
        run.mode + "\", \"queries\": " + std::to_string(run.summary.queries) +
        ", \"queries_with_true_match\": " + std::to_string(run.summary.queries_with_true_match) +
        ", \"recall_at_100_precision\": " + Number(run.summary.recall_at_full_precision) +
        ", \"auc\": " + Number(run.summary.auc) +
        ", \"candidate_recall_at_1\": " + Number(run.summary.candidate_recall_at_1) +
        ", \"candidate_recall_at_3\": " + Number(run.summary.candidate_recall_at_3) +
        ", \"candidate_recall_at_5\": " + Number(run.summary.candidate_recall_at_5);
    if (run.shape) {
      json += ", \"places\": " + std::to_string(run.shape->places) +
              ", \"largest_place_share\": " + Number(run.shape->largest_place_share) +
              ", \"places_per_revisited_location\": " +
              Number(run.shape->places_per_revisited_location);
    }
    if (run.method == "fabmap")
      json += ", \"declared_new_places\": " + std::to_string(run.summary.declared_new);
    if (run.at_default) {
      json += ", \"default_threshold\": " + Number(run.at_default->threshold) +
              ", \"precision_at_default\": " + Number(run.at_default->precision) +
              ", \"recall_at_default\": " + Number(run.at_default->recall);
    }
    json += "}";
  }
  return json + "]}\n";
}

void PrintTable(const Input& input, const evaluation::ExcludedPairs& excluded,
                const std::vector<Run>& runs) {
  std::printf("%d frames; window %s %s: %ld pairs excluded (%ld of them the same place)\n",
              input.frames.size(), Number(input.frames.window).c_str(), input.window_unit.c_str(),
              excluded.pairs, excluded.same_place);
  std::printf("%-8s %-10s %8s %11s %11s %8s %10s %8s %13s %17s %7s %8s %10s\n", "method", "mode",
              "queries", "true_match", "recall@P1", "AUC", "new_places", "time_s", "P/R@default",
              "cand@1/3/5", "places", "largest", "per_locat.");
  for (const Run& run : runs) {
    char at_default[32] = "-";
    if (run.at_default) {
      std::snprintf(at_default, sizeof(at_default), "%.1f/%.1f%%",
                    100.0 * run.at_default->precision, 100.0 * run.at_default->recall);
    }
    char candidates[32];
    std::snprintf(candidates, sizeof(candidates), "%.0f/%.0f/%.0f%%",
                  100.0 * run.summary.candidate_recall_at_1,
                  100.0 * run.summary.candidate_recall_at_3,
                  100.0 * run.summary.candidate_recall_at_5);
    char places[16] = "-", largest[16] = "-", per_location[16] = "-";
    if (run.shape) {
      std::snprintf(places, sizeof(places), "%d", run.shape->places);
      std::snprintf(largest, sizeof(largest), "%.1f%%", 100.0 * run.shape->largest_place_share);
      std::snprintf(per_location, sizeof(per_location), "%.2f",
                    run.shape->places_per_revisited_location);
    }
    std::printf("%-8s %-10s %8d %11d %10.1f%% %8.3f %10s %8.2f %13s %17s %7s %8s %10s\n",
                run.method.c_str(), run.mode.c_str(), run.summary.queries,
                run.summary.queries_with_true_match, 100.0 * run.summary.recall_at_full_precision,
                run.summary.auc,
                run.method == "fabmap" ? std::to_string(run.summary.declared_new).c_str() : "-",
                run.seconds, at_default, candidates, places, largest, per_location);
  }
}

}  // namespace

int main(int argc, char** argv) {
  std::optional<tools::CommandLine> args;
  std::vector<evaluation::PlacesMode> modes;
  int every = 1;
  evaluation::PlaceRelevance relevance;
  // Two views are one place only with the cameras within 3 m: three times the revisit radius of
  // the rendered routes (1 m), near enough for the two views' stereo points to verify a loop,
  // and short of the far side of a hall or a room. Without it, looking down a corridor, the view
  // from 20 m back "sees" the doors ahead and every frame of a long corridor is a revisit.
  relevance.max_distance = 3.0;
  double exclude_seconds = 5, exclude_frames = 5;
  std::optional<int> sequence_length;  // --sequence; else the loop detector's
  try {
    args.emplace(argc, argv,
                 std::set<std::string>{"tau", "max-distance", "exclude-seconds", "exclude-frames",
                                       "gt", "places", "every", "vocabulary", "config",
                                       "fabmap-config", "output", "sequence"},
                 std::set<std::string>{"mutual", "json", "no-odometry", "help"});
    if (args->Flag("help")) {
      std::fputs(kUsage, stdout);
      return 0;
    }
    if (args->positional().size() != 1)
      throw std::invalid_argument("one ASL_DIR or IMAGE_DIR is required");
    const double every_number = args->NumberOr("every", 1);
    if (every_number < 1 || every_number != std::floor(every_number))
      throw std::invalid_argument("--every must be a whole number >= 1");
    every = static_cast<int>(every_number);
    relevance.tau = args->NumberOr("tau", relevance.tau);
    if (!(relevance.tau > 0 && relevance.tau <= 1))
      throw std::invalid_argument("--tau must lie in (0, 1]");
    relevance.max_distance = args->NumberOr("max-distance", relevance.max_distance);
    if (!(relevance.max_distance > 0)) throw std::invalid_argument("--max-distance must be > 0");
    relevance.mutual = args->Flag("mutual");
    exclude_seconds = args->NumberOr("exclude-seconds", exclude_seconds);
    exclude_frames = args->NumberOr("exclude-frames", exclude_frames);
    if (!(exclude_seconds >= 0) || !(exclude_frames >= 0))
      throw std::invalid_argument("--exclude-seconds and --exclude-frames must be >= 0");
    if (args->Value("gt") ? args->Value("exclude-seconds").has_value()
                          : args->Value("exclude-frames").has_value()) {
      throw std::invalid_argument(
          "--exclude-seconds is for sequences, --exclude-frames for folders with --gt");
    }
    if (args->Value("gt") &&
        (args->Value("tau") || args->Value("max-distance") || args->Flag("mutual")))
      throw std::invalid_argument(
          "--tau, --max-distance and --mutual are for sequences (ground truth from poses)");
    if (args->Value("sequence")) {
      const double sequence_number = args->NumberOr("sequence", 1);
      if (sequence_number < 1 || sequence_number != std::floor(sequence_number))
        throw std::invalid_argument("--sequence must be a whole number >= 1");
      sequence_length = static_cast<int>(sequence_number);
    }
    const std::string places = args->ValueOr("places", "both");
    if (places == "per-image" || places == "both")
      modes.push_back(evaluation::PlacesMode::kPerImage);
    if (places == "update" || places == "both") modes.push_back(evaluation::PlacesMode::kUpdate);
    if (modes.empty()) throw std::invalid_argument("--places must be per-image, update or both");
  } catch (const std::invalid_argument& error) {
    std::fprintf(stderr, "evaluate_place_recognition: %s\n%s", error.what(), kUsage);
    return 2;
  }
  try {
    const tools::SlamConfiguration options = tools::SlamConfiguration::Load(
        args->ValueOr("config", STEREO_FABMAP_SLAM_CONFIG_DIR "/euroc.yaml"));
    place_recognition::PlaceRecognitionOptions place_options =
        place_recognition::LoadPlaceRecognitionOptions(
            args->ValueOr("fabmap-config", STEREO_FABMAP_SLAM_CONFIG_DIR "/fabmap.yaml"),
            options.front_end.features);
    const tools::FabMapFiles files = tools::LoadFabMapFiles(
        args->ValueOr("vocabulary", place_options.vocabulary_directory + "/vocabulary.bin"));
    place_options.fabmap =
        place_recognition::ResolveDetectorModel(place_options.fabmap, files.directory);
    std::fprintf(stderr, "detector model: p(z|e) %.3f, p(z|not e) %.4f\n",
                 place_options.fabmap.p_z_given_e, place_options.fabmap.p_z_given_not_e);
    const place_recognition::Vocabulary& vocabulary = files.vocabulary;
    const place_recognition::ChowLiuTree& tree = files.tree;
    const place_recognition::PlaceDatabase& training = files.training_places;

    const std::string source = args->positional()[0];
    // Updated places are limited by the odometry's distance and turn between views (fabmap.
    // max_place_extent, max_place_turn_deg); an image folder has no odometry, and appearance
    // alone decides there.
    const bool with_odometry =
        std::find(modes.begin(), modes.end(), evaluation::PlacesMode::kUpdate) != modes.end() &&
        (std::isfinite(place_options.fabmap.max_place_extent) ||
         place_options.fabmap.max_place_turn_deg < 180) &&
        !args->Flag("no-odometry");
    const double start = NowSeconds();
    const Input input = args->Value("gt")
                            ? ReadFolder(source, *args->Value("gt"), every, exclude_frames,
                                         place_options, vocabulary)
                            : ReadSequence(source, every, relevance, exclude_seconds, options,
                                           place_options, vocabulary, with_odometry);
    std::fprintf(stderr, "features, words and ground truth: %.1f s\n", NowSeconds() - start);
    const evaluation::ExcludedPairs excluded =
        evaluation::CountExcludedPairs(input.frames, *input.truth);

    std::vector<Run> runs;
    for (const evaluation::PlacesMode mode : modes) {
      Run run{"fabmap", evaluation::PlacesModeName(mode), {}, {}, {}, {}, {}, {}, 0};
      const double run_start = NowSeconds();
      place_recognition::FabMap fabmap(tree, place_options.fabmap, training);
      evaluation::FabMapQueryOptions query_options;
      query_options.mode = mode;
      query_options.match_log_odds = place_options.fabmap.match_log_odds;
      query_options.candidate_floor = options.loop_detection.min_probability;
      query_options.candidate_min_log_odds = options.loop_detection.min_log_odds;
      query_options.sequence.length =
          sequence_length.value_or(options.loop_detection.sequence_length);
      query_options.sequence.max_step = options.loop_detection.sequence_max_step;
      evaluation::FabMapQueries queries = evaluation::RunFabMapQueries(
          input.frames, *input.truth, query_options, &fabmap, [&](int done, int total) {
            if (done % 500 == 0 || done == total)
              std::fprintf(stderr, "FAB-MAP (%s): %d / %d queries\n", run.mode.c_str(), done,
                           total);
          });
      run.seconds = NowSeconds() - run_start;
      run.results = std::move(queries.results);
      run.shape = evaluation::DescribePlaces(input.frames, *input.truth, queries.place_of_frame);
      run.place_of_frame = std::move(queries.place_of_frame);
      runs.push_back(std::move(run));
    }
    {
      // tf-idf has no places to update: one image each, under both modes' queries.
      Run run{"tfidf", "per-image", {}, {}, {}, {}, {}, {}, 0};
      const double run_start = NowSeconds();
      std::vector<std::vector<int>> training_words;
      for (int i = 0; i < training.size(); ++i) {
        const std::vector<std::int32_t>& words = training.place(i).words;
        training_words.emplace_back(words.begin(), words.end());
      }
      place_recognition::TfIdfIndex index(place_recognition::TfIdfIndex::InverseDocumentFrequency(
          training_words, vocabulary.size()));
      run.results = evaluation::RunTfIdfQueries(input.frames, *input.truth, &index);
      run.seconds = NowSeconds() - run_start;
      runs.push_back(std::move(run));
    }
    for (Run& run : runs) {
      run.curve = evaluation::PrecisionRecallCurve(run.results);
      run.summary = evaluation::SummarizePlaceRecognition(run.results);
      if (run.method == "fabmap") {
        run.at_default =
            evaluation::PointAtThreshold(run.results, place_options.fabmap.match_log_odds);
      }
    }
    if (args->Value("output")) {
      WriteOutputs(*args->Value("output"), input, excluded, runs);
      std::fprintf(stderr, "wrote %s/place_recognition_{pr,summary,queries}.csv\n",
                   args->Value("output")->c_str());
    }
    if (args->Flag("json")) {
      std::fputs(SummaryJson(source, input, excluded, runs).c_str(), stdout);
    } else {
      PrintTable(input, excluded, runs);
    }
  } catch (const std::exception& error) {
    std::fprintf(stderr, "evaluate_place_recognition: %s\n", error.what());
    return 1;
  }
  return 0;
}
