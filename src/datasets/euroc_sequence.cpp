#include "stereo_fabmap_slam/datasets/euroc_sequence.h"

#include <sys/stat.h>

#include <cstdlib>

#include <opencv2/imgcodecs.hpp>

#include "stereo_fabmap_slam/io/csv_reader.h"
#include "stereo_fabmap_slam/io/trajectory_file.h"

namespace stereo_fabmap_slam::datasets {

using io::FileError;
using io::InputError;
using io::ParseInt64;
using io::ReadDelimitedText;
using io::Separator;
using io::TextRow;
namespace {

bool IsDirectory(const std::string& path) {
  struct stat info;
  return stat(path.c_str(), &info) == 0 && S_ISDIR(info.st_mode);
}

bool IsFile(const std::string& path) {
  struct stat info;
  return stat(path.c_str(), &info) == 0 && S_ISREG(info.st_mode);
}

struct ImageEntry {
  std::int64_t timestamp_ns;
  std::string path;
};

// Reads camX/data.csv: "timestamp [ns],filename" a line, stamps increasing, files present.
std::vector<ImageEntry> ReadImageList(const std::string& camera_dir) {
  const std::string list_path = camera_dir + "/data.csv";
  std::vector<ImageEntry> images;
  for (const TextRow& row : ReadDelimitedText(list_path, Separator::kComma)) {
    if (row.fields.size() != 2 || row.fields[1].empty()) {
      throw FileError(list_path, row.line_number, "expected 'timestamp [ns],filename'");
    }
    const std::int64_t stamp = ParseInt64(row.fields[0], list_path, row.line_number);
    if (!images.empty() && stamp <= images.back().timestamp_ns) {
      throw FileError(list_path, row.line_number, "timestamps must increase");
    }
    const std::string image_path = camera_dir + "/data/" + row.fields[1];
    if (!IsFile(image_path)) {
      throw FileError(list_path, row.line_number, "image file " + image_path + " does not exist");
    }
    images.push_back({stamp, image_path});
  }
  if (images.empty()) throw FileError(list_path, 0, "no images listed");
  return images;
}

cv::Mat LoadMonoImage(const std::string& path, const cv::Size& expected_size) {
  const cv::Mat image = cv::imread(path, cv::IMREAD_GRAYSCALE);
  if (image.empty()) throw FileError(path, 0, "cannot read image");
  if (image.size() != expected_size) {
    throw FileError(path, 0,
                    "image is " + std::to_string(image.cols) + "x" + std::to_string(image.rows) +
                        ", sensor.yaml says " + std::to_string(expected_size.width) + "x" +
                        std::to_string(expected_size.height));
  }
  return image;
}

}  // namespace

EurocSequence EurocSequence::Open(const std::string& directory,
                                  const EurocSequenceOptions& options) {
  if (options.max_pair_dt_ns < 0) throw InputError("max_pair_dt_ns must not be negative");
  EurocSequence sequence;
  if (IsDirectory(directory + "/mav0")) {
    sequence.mav0_ = directory + "/mav0";
  } else if (IsDirectory(directory + "/cam0")) {
    sequence.mav0_ = directory;
  } else {
    throw FileError(directory, 0, "not an EuRoC ASL folder: neither mav0/ nor cam0/ inside");
  }
  const std::string left_dir = sequence.mav0_ + "/cam0";
  const std::string right_dir = sequence.mav0_ + "/cam1";
  for (const std::string& dir : {left_dir, right_dir, left_dir + "/data", right_dir + "/data"}) {
    if (!IsDirectory(dir)) throw FileError(dir, 0, "missing folder");
  }

  sequence.calibration_.left = camera::ReadEurocSensorYaml(left_dir + "/sensor.yaml");
  sequence.calibration_.right = camera::ReadEurocSensorYaml(right_dir + "/sensor.yaml");
  try {
    sequence.calibration_.Validate();
  } catch (const std::invalid_argument& error) {
    throw FileError(sequence.mav0_, 0, std::string("stereo calibration: ") + error.what());
  }

  // Merge the two sorted lists: pairs within the tolerance, everything else unpaired.
  const std::vector<ImageEntry> left = ReadImageList(left_dir);
  const std::vector<ImageEntry> right = ReadImageList(right_dir);
  std::size_t l = 0, r = 0;
  while (l < left.size() || r < right.size()) {
    if (l < left.size() && r < right.size() &&
        std::llabs(left[l].timestamp_ns - right[r].timestamp_ns) <= options.max_pair_dt_ns) {
      sequence.frames_.push_back({left[l].timestamp_ns, left[l].path, right[r].path});
      ++l;
      ++r;
    } else if (r == right.size() ||
               (l < left.size() && left[l].timestamp_ns < right[r].timestamp_ns)) {
      sequence.unpaired_.push_back({"cam0", left[l].timestamp_ns, left[l].path});
      ++l;
    } else {
      sequence.unpaired_.push_back({"cam1", right[r].timestamp_ns, right[r].path});
      ++r;
    }
  }
  if (sequence.frames_.empty()) {
    throw FileError(sequence.mav0_, 0, "no left image has a right image with the same timestamp");
  }

  const std::string ground_truth_path = sequence.mav0_ + "/state_groundtruth_estimate0/data.csv";
  if (IsFile(ground_truth_path)) {
    sequence.ground_truth_ = io::ReadEurocTrajectory(ground_truth_path);
  }
  return sequence;
}

StereoImages EurocSequence::LoadStereoPair(std::size_t i) const {
  const StereoFrameEntry& frame = frames_.at(i);
  return {frame.timestamp_ns, LoadMonoImage(frame.left_path, calibration_.left.resolution),
          LoadMonoImage(frame.right_path, calibration_.right.resolution)};
}

}  // namespace stereo_fabmap_slam::datasets
