// Descriptor precision-recall for issue 13: every detector/descriptor pair on image pairs whose
// geometry is known (homographies of the Oxford sets, ground-truth poses with stereo depth of
// EuRoC-layout sequences, rendered illumination changes of one view), as CSV files for the
// report and a table of the areas under the curves.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <fstream>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "command_line.h"
#include "stereo_fabmap_slam/camera/stereo_rectifier.h"
#include "stereo_fabmap_slam/datasets/euroc_sequence.h"
#include "stereo_fabmap_slam/evaluation/descriptor_case.h"
#include "stereo_fabmap_slam/evaluation/homography_transfer.h"
#include "stereo_fabmap_slam/evaluation/illumination_change.h"
#include "stereo_fabmap_slam/evaluation/pose_interpolation.h"
#include "stereo_fabmap_slam/features/feature_factory.h"
#include "stereo_fabmap_slam/io/input_error.h"

namespace {

using namespace stereo_fabmap_slam;  // NOLINT: a tool's main file
namespace fs = std::filesystem;

constexpr char kUsage[] =
    "usage: evaluate_descriptors --output DIR [--pairs DET/DESC,...] [--epsilon PX]\n"
    "                            [--max-keypoints N] [--oxford DIR] [--graf DIR]\n"
    "                            [--euroc ASL_DIR[,ASL_DIR...]] [--illumination IMAGE]\n"
    "                            [--data DIR]\n"
    "Descriptor precision-recall: each reference key point's nearest test descriptor is a match\n"
    "when d1 < t * d2 (t from 0 to 1 in 101 steps), correct when the reference key point carried\n"
    "into the test image lies within --epsilon px (default 2.5) of the matched key point;\n"
    "recall = correct / reference key points with some test key point within epsilon.\n"
    "Cases:\n"
    "  --oxford DIR        img1 against img2..imgN of an Oxford set, homographies H1toNp\n"
    "  --graf DIR          graf1.png against graf3.png, homography H1to3p.xml (opencv-doc)\n"
    "  --euroc DIRS        EuRoC-layout sequences (also make_synthetic_sequence's routes): the\n"
    "                      first frame with ground truth against frames 0.25, 0.5, 1, 2, 4 s\n"
    "                      later (case names give the offset, distance and rotation); the\n"
    "                      reference stereo depth moved by the ground-truth poses\n"
    "  --illumination IMG  the image against itself under exposure, gamma and a directional\n"
    "                      light (rendered; identity geometry)\n"
    "Without a case option, all of: --oxford DATA/oxford/boat, --graf (opencv-doc's examples),\n"
    "--illumination DATA/oxford/boat/img1.pgm, --euroc DATA/euroc/MH01_first10s, where DATA is\n"
    "--data, else $STEREO_FABMAP_SLAM_DATA, else ../shared/data beside the repository.\n"
    "Pairs (default AGAST/BRISK,FAST/BRISK,AGAST/ORB,ORB/ORB,ORB/BRISK,AKAZE/AKAZE,SIFT/SIFT, of\n"
    "those this OpenCV has) keep their --max-keypoints strongest (default 1000) per image.\n"
    "Writes DIR/descriptor_pr.csv (case,pair,threshold,precision,recall,selected,correct) and\n"
    "DIR/descriptor_auc.csv (case,pair,auc,reference_keypoints,correct_possible,\n"
    "milliseconds_per_image); prints the areas as a table.\n";

constexpr char kOpencvDocData[] = "/usr/share/doc/opencv-doc/examples/data";
// Test frames this long after the reference frame: the motion grows with the time, and a
// sequence that comes back (MH01's first 10 s never leave 0.3 m of the start) still gives pairs.
const std::vector<double> kEurocOffsets = {0.25, 0.5, 1.0, 2.0, 4.0};  // [s]

double NowMs() {
  return std::chrono::duration<double, std::milli>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

std::vector<std::string> SplitList(const std::string& text) {
  std::vector<std::string> items;
  std::stringstream stream(text);
  std::string item;
  while (std::getline(stream, item, ',')) {
    if (!item.empty()) items.push_back(item);
  }
  return items;
}

// "DETECTOR/DESCRIPTOR" pairs, each checked against this OpenCV build.
std::vector<features::FeatureOptions> ParsePairs(const std::optional<std::string>& text) {
  std::vector<std::string> names;
  if (text) {
    names = SplitList(*text);
    if (names.empty()) throw std::invalid_argument("--pairs lists no pair");
  } else {
    const auto& detectors = features::AvailableDetectors();
    const auto& descriptors = features::AvailableDescriptors();
    for (const char* name : {"AGAST/BRISK", "FAST/BRISK", "AGAST/ORB", "ORB/ORB", "ORB/BRISK",
                             "AKAZE/AKAZE", "SIFT/SIFT"}) {
      const std::string pair = name;
      const std::string detector = pair.substr(0, pair.find('/'));
      const std::string descriptor = pair.substr(pair.find('/') + 1);
      if (std::count(detectors.begin(), detectors.end(), detector) &&
          std::count(descriptors.begin(), descriptors.end(), descriptor)) {
        names.push_back(pair);
      }
    }
  }
  std::vector<features::FeatureOptions> pairs;
  for (const std::string& name : names) {
    const std::size_t slash = name.find('/');
    if (slash == std::string::npos) {
      throw std::invalid_argument("pair '" + name + "' is not DETECTOR/DESCRIPTOR");
    }
    features::FeatureOptions pair;
    pair.detector = name.substr(0, slash);
    pair.descriptor = name.substr(slash + 1);
    features::CreateDetector(pair);  // throws std::invalid_argument naming what is available
    features::CreateDescriptor(pair);
    pairs.push_back(pair);
  }
  return pairs;
}

cv::Mat ReadGrey(const std::string& path) {
  const cv::Mat image = cv::imread(path, cv::IMREAD_GRAYSCALE);
  if (image.empty()) throw io::FileError(path, 0, "cannot read the image");
  return image;
}

// Case names go into CSV cells unquoted.
std::string CsvSafe(std::string text) {
  for (char& c : text) {
    if (c == ',' || c == '"' || c == '\n') c = '_';
  }
  return text;
}

std::string FolderName(const std::string& path) {
  fs::path folder = fs::path(path).lexically_normal();
  if (folder.filename().empty()) folder = folder.parent_path();
  if (folder.filename() == "mav0") folder = folder.parent_path();
  return CsvSafe(folder.filename().string());
}

std::vector<evaluation::DescriptorCase> OxfordCases(const std::string& directory) {
  std::vector<evaluation::DescriptorCase> cases;
  const cv::Mat reference = ReadGrey(directory + "/img1.pgm");
  for (int n = 2; fs::exists(directory + "/img" + std::to_string(n) + ".pgm"); ++n) {
    evaluation::DescriptorCase oxford;
    oxford.name = FolderName(directory) + ":1-" + std::to_string(n);
    oxford.reference = reference;
    oxford.test = ReadGrey(directory + "/img" + std::to_string(n) + ".pgm");
    oxford.homography = evaluation::ReadHomography(directory + "/H1to" + std::to_string(n) + "p");
    cases.push_back(oxford);
  }
  if (cases.empty()) throw io::FileError(directory, 0, "no img2.pgm: no Oxford image pairs");
  return cases;
}

evaluation::DescriptorCase GrafCase(const std::string& directory) {
  evaluation::DescriptorCase graf;
  graf.name = "graf:1-3";
  graf.reference = ReadGrey(directory + "/graf1.png");
  graf.test = ReadGrey(directory + "/graf3.png");
  graf.homography = evaluation::ReadHomography(directory + "/H1to3p.xml");
  return graf;
}

std::vector<evaluation::DescriptorCase> IlluminationCases(const std::string& path) {
  const cv::Mat image = ReadGrey(path);
  std::vector<evaluation::DescriptorCase> cases;
  for (const evaluation::IlluminationChange& change : evaluation::StandardIlluminationChanges()) {
    evaluation::DescriptorCase lit;
    lit.name = "illumination:" + change.name;
    lit.reference = image;
    lit.test = evaluation::ApplyIlluminationChange(image, change);
    cases.push_back(lit);
  }
  return cases;
}

// The first frame with ground truth against the first later frames kEurocOffsets after it.
std::vector<evaluation::DescriptorCase> EurocCases(const std::string& directory) {
  const datasets::EurocSequence sequence = datasets::EurocSequence::Open(directory);
  if (!sequence.has_ground_truth()) {
    throw io::FileError(directory, 0, "the sequence has no ground truth");
  }
  const camera::StereoRectifier rectifier =
      camera::StereoRectifier::FromCalibration(sequence.calibration());
  const auto time = [&](std::size_t i) { return sequence.frames()[i].timestamp_ns * 1e-9; };
  const auto camera_pose = [&](std::size_t i) -> std::optional<Eigen::Isometry3d> {
    const std::optional<Eigen::Isometry3d> body =
        evaluation::InterpolatePose(sequence.ground_truth(), time(i), /*max_gap=*/0.05);
    if (!body) return std::nullopt;
    return *body * rectifier.T_body_rectified_left();
  };
  std::size_t first = 0;
  while (first < sequence.size() && !camera_pose(first)) ++first;
  if (first == sequence.size()) throw io::FileError(directory, 0, "no frame has ground truth");
  const Eigen::Isometry3d T_world_reference = *camera_pose(first);
  const datasets::StereoImages reference_raw = sequence.LoadStereoPair(first);
  cv::Mat reference_left, reference_right;
  rectifier.Rectify(reference_raw.left, reference_raw.right, &reference_left, &reference_right);

  std::vector<evaluation::DescriptorCase> cases;
  std::size_t next_offset = 0;
  for (std::size_t i = first + 1; i < sequence.size() && next_offset < kEurocOffsets.size(); ++i) {
    // Half a frame early counts: stamps jitter around the nominal rate.
    if (time(i) - time(first) < kEurocOffsets[next_offset] - 0.025) continue;
    const double offset = kEurocOffsets[next_offset++];
    const std::optional<Eigen::Isometry3d> T_world_test = camera_pose(i);
    if (!T_world_test) continue;
    const Eigen::Isometry3d T_test_reference = T_world_test->inverse() * T_world_reference;
    const double distance = T_test_reference.translation().norm();
    const double angle = Eigen::AngleAxisd(T_test_reference.linear()).angle() * 180 / M_PI;
    const datasets::StereoImages test_raw = sequence.LoadStereoPair(i);
    cv::Mat test_left, test_right;
    rectifier.Rectify(test_raw.left, test_raw.right, &test_left, &test_right);
    evaluation::DescriptorCase pair;
    char name[96];
    std::snprintf(name, sizeof(name), ":+%.2fs/%.2fm/%.0fdeg", offset, distance, angle);
    pair.name = FolderName(directory) + name;
    pair.reference = reference_left;
    pair.test = test_left;
    pair.stereo = evaluation::DescriptorCase::Stereo{
        reference_right, rectifier.camera(), T_test_reference, {}};
    std::fprintf(stderr, "  %s: frames %zu and %zu\n", pair.name.c_str(), first, i);
    cases.push_back(pair);
  }
  if (cases.empty()) {
    throw io::FileError(directory, 0, "no frame with ground truth 0.25 s after the first");
  }
  return cases;
}

std::string DefaultDataRoot() {
  const char* from_environment = std::getenv("STEREO_FABMAP_SLAM_DATA");
  if (from_environment != nullptr && *from_environment != '\0') return from_environment;
  return STEREO_FABMAP_SLAM_DEFAULT_DATA;
}

std::vector<evaluation::DescriptorCase> LoadCases(const tools::CommandLine& args) {
  std::optional<std::string> oxford = args.Value("oxford"), graf = args.Value("graf"),
                             euroc = args.Value("euroc"), illumination = args.Value("illumination");
  if (!oxford && !graf && !euroc && !illumination) {
    const std::string data = args.ValueOr("data", DefaultDataRoot());
    oxford = data + "/oxford/boat";
    graf = kOpencvDocData;
    illumination = data + "/oxford/boat/img1.pgm";
    euroc = data + "/euroc/MH01_first10s";
  }
  std::vector<evaluation::DescriptorCase> cases;
  const auto append = [&cases](std::vector<evaluation::DescriptorCase> more) {
    cases.insert(cases.end(), more.begin(), more.end());
  };
  std::fputs("evaluate_descriptors: reading the cases\n", stderr);
  if (oxford) append(OxfordCases(*oxford));
  if (graf) cases.push_back(GrafCase(*graf));
  if (illumination) append(IlluminationCases(*illumination));
  if (euroc) {
    const std::vector<std::string> sequences = SplitList(*euroc);
    if (sequences.empty()) throw std::invalid_argument("--euroc lists no sequence");
    for (const std::string& sequence : sequences) append(EurocCases(sequence));
  }
  return cases;
}

std::ofstream OpenCsv(const fs::path& path, const char* header) {
  std::ofstream file(path);
  if (!file) throw io::FileError(path.string(), 0, "cannot write");
  file << header << '\n';
  return file;
}

}  // namespace

int main(int argc, char** argv) {
  std::optional<tools::CommandLine> args;
  std::vector<features::FeatureOptions> pairs;
  evaluation::DescriptorPrecisionRecallOptions options;
  try {
    args.emplace(argc, argv,
                 std::set<std::string>{"output", "pairs", "epsilon", "max-keypoints", "oxford",
                                       "graf", "euroc", "illumination", "data"},
                 std::set<std::string>{"help"});
    if (args->Flag("help")) {
      std::fputs(kUsage, stdout);
      return 0;
    }
    if (!args->positional().empty()) {
      throw std::invalid_argument("unexpected argument " + args->positional().front());
    }
    if (!args->Value("output")) throw std::invalid_argument("--output DIR is required");
    options.epsilon = args->NumberOr("epsilon", options.epsilon);
    const double max_keypoints = args->NumberOr("max-keypoints", options.max_keypoints);
    if (max_keypoints != static_cast<int>(max_keypoints)) {
      throw std::invalid_argument("--max-keypoints must be a whole number");
    }
    options.max_keypoints = static_cast<int>(max_keypoints);
    options.Validate();
    pairs = ParsePairs(args->Value("pairs"));
  } catch (const std::invalid_argument& error) {
    std::fprintf(stderr, "evaluate_descriptors: %s\n%s", error.what(), kUsage);
    return 2;
  }
  try {
    const double start = NowMs();
    const std::vector<evaluation::DescriptorCase> cases = LoadCases(*args);
    const fs::path output = *args->Value("output");
    fs::create_directories(output);
    std::ofstream pr_csv = OpenCsv(output / "descriptor_pr.csv",
                                   "case,pair,threshold,precision,recall,selected,correct");
    std::ofstream auc_csv =
        OpenCsv(output / "descriptor_auc.csv",
                "case,pair,auc,reference_keypoints,correct_possible,milliseconds_per_image");
    std::printf("%-36s %-12s %6s %9s %8s %9s\n", "case", "pair", "AUC", "ref_kps", "possible",
                "ms/image");
    for (std::size_t c = 0; c < cases.size(); ++c) {
      std::fprintf(stderr, "evaluate_descriptors: case %zu / %zu: %s\n", c + 1, cases.size(),
                   cases[c].name.c_str());
      for (const features::FeatureOptions& pair : pairs) {
        const std::string pair_name = pair.detector + "/" + pair.descriptor;
        const evaluation::DescriptorCaseResult result =
            evaluation::EvaluateDescriptorCase(cases[c], pair, options, NowMs);
        const evaluation::DescriptorPrecisionRecall& pr = result.precision_recall;
        char line[256];
        for (const evaluation::PrecisionRecallPoint& point : pr.curve) {
          std::snprintf(line, sizeof(line), "%s,%s,%.2f,%.6f,%.6f,%d,%d\n", cases[c].name.c_str(),
                        pair_name.c_str(), point.threshold, point.precision, point.recall,
                        point.selected, point.correct);
          pr_csv << line;
        }
        std::snprintf(line, sizeof(line), "%s,%s,%.6f,%d,%d,%.3f\n", cases[c].name.c_str(),
                      pair_name.c_str(), pr.auc, pr.reference_keypoints, pr.correct_possible,
                      result.milliseconds_per_image);
        auc_csv << line;
        std::printf("%-36s %-12s %6.3f %9d %8d %9.1f\n", cases[c].name.c_str(), pair_name.c_str(),
                    pr.auc, pr.reference_keypoints, pr.correct_possible,
                    result.milliseconds_per_image);
        std::fflush(stdout);
      }
    }
    if (!pr_csv || !auc_csv)
      throw io::FileError(output.string(), 0, "writing the CSV files failed");
    std::fprintf(stderr, "evaluate_descriptors: %zu cases x %zu pairs in %.1f s; wrote %s\n",
                 cases.size(), pairs.size(), (NowMs() - start) / 1000, output.c_str());
  } catch (const std::exception& error) {
    std::fprintf(stderr, "evaluate_descriptors: %s\n", error.what());
    return 1;
  }
  return 0;
}
