// Feature detection, ANMS and stereo matching on real EuRoC images.
#include <algorithm>
#include <cmath>
#include <iterator>
#include <set>
#include <string>
#include <tuple>

#include <gtest/gtest.h>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>

#include "stereo_fabmap_slam/camera/stereo_rectifier.h"
#include "stereo_fabmap_slam/concurrency/helper_thread.h"
#include "stereo_fabmap_slam/datasets/euroc_sequence.h"
#include "stereo_fabmap_slam/features/adaptive_detector.h"
#include "stereo_fabmap_slam/features/anms.h"
#include "stereo_fabmap_slam/features/feature_factory.h"
#include "stereo_fabmap_slam/features/keypoint_grid.h"
#include "stereo_fabmap_slam/features/oast_detector.h"
#include "stereo_fabmap_slam/features/stereo_feature_extractor.h"
#include "test_support.h"

namespace stereo_fabmap_slam::test {
namespace {

using namespace features;  // NOLINT: the module under test

class RealStereoPair : public ::testing::Test {
 protected:
  RealStereoPair()
      : sequence_(datasets::EurocSequence::Open(EurocSequencePath("MH01_first10s"))),
        rectifier_(camera::StereoRectifier::FromCalibration(sequence_.calibration())) {
    const datasets::StereoImages raw = sequence_.LoadStereoPair(100);
    rectifier_.Rectify(raw.left, raw.right, &left_, &right_);
  }

  datasets::EurocSequence sequence_;
  camera::StereoRectifier rectifier_;
  cv::Mat left_, right_;
};

// Cells of an 8 x 6 grid over the image that hold at least one key point.
int OccupiedCells(const std::vector<cv::KeyPoint>& keypoints, const cv::Size& size) {
  std::set<int> cells;
  for (const cv::KeyPoint& k : keypoints) {
    cells.insert(static_cast<int>(k.pt.y * 6 / size.height) * 8 +
                 static_cast<int>(k.pt.x * 8 / size.width));
  }
  return static_cast<int>(cells.size());
}

TEST_F(RealStereoPair, AnmsSpreadsKeyPointsOverTheImage) {
  std::vector<cv::KeyPoint> corners;
  cv::AgastFeatureDetector::create(10)->detect(left_, corners);
  ASSERT_GT(corners.size(), 2000u);
  const int available = OccupiedCells(corners, left_.size());
  const std::vector<cv::KeyPoint> strongest = SelectStrongest(corners, 300);
  const std::vector<cv::KeyPoint> spread = SelectWithAnms(corners, 300, left_.size(), 0.1);
  EXPECT_NEAR(static_cast<double>(spread.size()), 300.0, 30.0);
  const int strongest_cells = OccupiedCells(strongest, left_.size());
  const int spread_cells = OccupiedCells(spread, left_.size());
  RecordProperty("cells_strongest", strongest_cells);
  RecordProperty("cells_anms", spread_cells);
  // ANMS reaches nearly every cell that has a corner at all; the strongest 300 pile up on the
  // most textured part of the hall and leave clearly more cells empty.
  EXPECT_GE(spread_cells, 0.9 * available);
  EXPECT_GE(spread_cells, strongest_cells + 5);
}

TEST(Anms, FewerPointsThanRequestedAreAllKept) {
  std::vector<cv::KeyPoint> points = {{10, 10, 7, -1, 5}, {20, 20, 7, -1, 9}};
  EXPECT_EQ(SelectWithAnms(points, 10, cv::Size(100, 100), 0.1).size(), 2u);
  EXPECT_FLOAT_EQ(SelectStrongest(points, 1)[0].response, 9.0f);
}

// OastDetector must give OpenCV's AGAST (OAST_9_16, suppression on) key points exactly, field
// by field and in the same order, whatever the image: real frames of both EuRoC sequences
// (raw and rectified, both cameras) and opencv-doc's photographs (graf: strong texture and
// viewpoint change; HappyFish: large plain areas), at thresholds over the adaptive range.
TEST(OastDetector, GivesOpenCvsAgastKeyPointsExactly) {
  std::vector<cv::Mat> images;
  for (const char* name : {"MH01_first10s", "V101_micro"}) {
    const datasets::EurocSequence sequence = datasets::EurocSequence::Open(EurocSequencePath(name));
    const camera::StereoRectifier rectifier =
        camera::StereoRectifier::FromCalibration(sequence.calibration());
    for (std::size_t frame = 0; frame < sequence.size(); frame += sequence.size() / 4) {
      const datasets::StereoImages raw = sequence.LoadStereoPair(frame);
      cv::Mat left, right;
      rectifier.Rectify(raw.left, raw.right, &left, &right);
      images.insert(images.end(), {raw.left, raw.right, left, right});
    }
  }
  for (const char* name : {"graf1.png", "graf3.png", "HappyFish.jpg"}) {
    const cv::Mat photo = cv::imread(std::string("/usr/share/doc/opencv-doc/examples/data/") + name,
                                     cv::IMREAD_GRAYSCALE);
    ASSERT_FALSE(photo.empty()) << name;
    images.push_back(photo);
  }
  std::size_t compared = 0;
  for (const int threshold : {5, 12, 20, 40, 80}) {
    const cv::Ptr<cv::AgastFeatureDetector> opencv =
        cv::AgastFeatureDetector::create(threshold, true, cv::AgastFeatureDetector::OAST_9_16);
    const cv::Ptr<OastDetector> ours = OastDetector::create(threshold);
    for (std::size_t i = 0; i < images.size(); ++i) {
      std::vector<cv::KeyPoint> expected, found;
      opencv->detect(images[i], expected);
      ours->detect(images[i], found);
      ASSERT_EQ(found.size(), expected.size()) << "image " << i << ", threshold " << threshold;
      for (std::size_t k = 0; k < found.size(); ++k) {
        const cv::KeyPoint &a = found[k], &b = expected[k];
        ASSERT_TRUE(a.pt == b.pt && a.size == b.size && a.angle == b.angle &&
                    a.response == b.response && a.octave == b.octave && a.class_id == b.class_id)
            << "image " << i << ", threshold " << threshold << ", key point " << k;
      }
      compared += found.size();
    }
  }
  EXPECT_GT(compared, 100000u);  // the comparison saw many key points, blobs among them
  // The threshold set through the interface the adaptive detector uses takes effect.
  const cv::Ptr<OastDetector> adapted = OastDetector::create(5);
  cv::Ptr<cv::AgastFeatureDetector> as_agast = adapted;
  as_agast->setThreshold(40);
  std::vector<cv::KeyPoint> at_40, expected_40;
  adapted->detect(images[0], at_40);
  cv::AgastFeatureDetector::create(40)->detect(images[0], expected_40);
  EXPECT_EQ(at_40.size(), expected_40.size());
}

// The extractor detects the left image in two bands (for two threads). FAST suppresses
// non-maxima in 3 x 3 neighbourhoods, which the bands' 4-row margins contain: its bands give
// the whole image's corners exactly. AGAST keeps one corner of each 4-connected blob of corners,
// and a blob cut by the split may keep one corner on either side: the corners may differ, but
// only next to the split. The bound: a blob is the few pixels around one image corner where the
// segment test holds (2-6 rows on EuRoC at the default threshold); 12 rows is twice the most
// seen, and the differing corners must be under 2 % of all.
TEST_F(RealStereoPair, BandDetectionDiffersFromTheWholeImageOnlyAtTheSplit) {
  for (const std::string name : {"FAST", "AGAST"}) {
    FeatureOptions options;
    options.detector = name;
    options.adaptive_threshold = false;
    options.detector_threshold = 10;  // many corners, so that blobs do meet the splits
    const AdaptiveDetector detector(options, false);
    const auto key = [](const cv::KeyPoint& k) {
      return std::make_tuple(k.pt.y, k.pt.x, k.response);
    };
    std::set<std::tuple<float, float, float>> whole;
    for (const auto& k : detector.DetectRows(left_, 0, left_.rows)) whole.insert(key(k));
    ASSERT_GT(whole.size(), 1000u) << name;
    for (const int split : {100, 200, left_.rows * 3 / 5, 350}) {
      std::vector<cv::KeyPoint> bands = detector.DetectRows(left_, 0, split);
      const std::vector<cv::KeyPoint> lower = detector.DetectRows(left_, split, left_.rows);
      bands.insert(bands.end(), lower.begin(), lower.end());
      std::set<std::tuple<float, float, float>> banded;
      for (const auto& k : bands) banded.insert(key(k));
      std::vector<std::tuple<float, float, float>> differing;
      std::set_symmetric_difference(whole.begin(), whole.end(), banded.begin(), banded.end(),
                                    std::back_inserter(differing));
      if (name == "FAST") {
        EXPECT_TRUE(differing.empty()) << "split " << split << ": " << differing.size();
        continue;
      }
      EXPECT_LE(differing.size(), 0.02 * whole.size()) << "split " << split;
      for (const auto& [y, x, response] : differing) {
        EXPECT_LE(std::abs(y - split), 12.0f) << "split " << split << ", corner " << x << " " << y;
      }
    }
  }
}

// With the front end's helper thread, the extractor splits detection (bands of rows of both
// images), description (pieces of key points, one BRISK instance on both threads: its 47 MB
// pattern table once, DescriptorKind::shareable) and stereo matching (pieces of key points):
// the features must be those of one thread, bit for bit, every time (20 runs each: a race on
// shared state would show as differing bits). With both segment-test detectors, as the left
// one's cost differs (AGAST about five times FAST's).
TEST_F(RealStereoPair, ExtractionOnTwoThreadsEqualsOneThread) {
  for (const std::string detector : {"AGAST", "FAST"}) {
    FeatureOptions options;
    options.detector = detector;
    options.adaptive_threshold = false;
    ASSERT_EQ(options.descriptor, "BRISK");
    ASSERT_TRUE(CreateDescriptor(options).shareable);
    const geometry::StereoCamera& camera = rectifier_.camera();
    StereoMatcherOptions stereo;
    FeatureOptions serial_options = options;
    serial_options.parallel = false;
    options.parallel = true;
    concurrency::HelperThread helper;
    StereoFeatureExtractor parallel(options, stereo, camera, &helper);
    StereoFeatureExtractor serial(serial_options, stereo, camera, &helper);
    const StereoFeatures expected = serial.Extract(left_, right_);
    ASSERT_GT(expected.size(), 300u) << detector;
    ASSERT_GT(expected.CountWithDepth(), 150) << detector;
    for (int run = 0; run < 20; ++run) {
      const StereoFeatures features = parallel.Extract(left_, right_);
      ASSERT_EQ(features.size(), expected.size()) << detector << " run " << run;
      for (std::size_t i = 0; i < features.size(); ++i) {
        ASSERT_EQ(features.keypoints[i].pt, expected.keypoints[i].pt) << detector << " " << i;
        ASSERT_EQ(features.keypoints[i].angle, expected.keypoints[i].angle) << detector << " " << i;
        ASSERT_EQ(features.u_right[i], expected.u_right[i]) << detector << " " << i;
      }
      ASSERT_EQ(cv::norm(features.descriptors, expected.descriptors, cv::NORM_HAMMING), 0.0)
          << detector << " run " << run;
    }
  }
}

TEST_F(RealStereoPair, TriangulatedDepthsAgreeWithDisparity) {
  StereoFeatureExtractor extractor(FeatureOptions{}, StereoMatcherOptions{}, rectifier_.camera());
  const StereoFeatures features = extractor.Extract(left_, right_);
  ASSERT_GT(features.CountWithDepth(), 150);
  const geometry::StereoCamera& camera = rectifier_.camera();
  std::vector<double> depths;
  for (std::size_t i = 0; i < features.size(); ++i) {
    if (!features.HasDepth(i)) continue;
    const cv::Point2f& p = features.keypoints[i].pt;
    const double disparity = p.x - features.u_right[i];
    const Eigen::Vector3d& point = features.points[i];
    ASSERT_GT(disparity, 0);
    EXPECT_NEAR(point.z(), camera.fx * camera.baseline / disparity, 1e-9 * point.z());
    EXPECT_GE(point.z(), StereoMatcherOptions{}.min_depth);
    EXPECT_LE(point.z(), StereoMatcherOptions{}.max_depth);
    // Re-projecting the point gives back the measured pixels in both images (to the precision
    // of the float pixel coordinates).
    const Eigen::Vector3d projected = camera.Project(point);
    EXPECT_NEAR(projected.x(), p.x, 1e-4);
    EXPECT_NEAR(projected.y(), p.y, 1e-4);
    EXPECT_NEAR(projected.z(), features.u_right[i], 1e-4);
    // And OpenCV's linear triangulation with the rectified projections agrees.
    cv::Mat homogeneous;
    cv::triangulatePoints(rectifier_.left_parameters().P, rectifier_.right_parameters().P,
                          std::vector<cv::Point2f>{p},
                          std::vector<cv::Point2f>{{features.u_right[i], p.y}}, homogeneous);
    EXPECT_NEAR(homogeneous.at<float>(2) / homogeneous.at<float>(3), point.z(), 1e-3 * point.z());
    depths.push_back(point.z());
  }
  // Frame 100 looks at structure about a metre away with the hall behind it: the depths spread
  // over the configured range instead of collapsing to one end of it.
  std::sort(depths.begin(), depths.end());
  EXPECT_LT(depths[depths.size() / 10], 1.0);
  EXPECT_GT(depths[depths.size() * 9 / 10], 2.0);
}

TEST_F(RealStereoPair, PatchAndDescriptorStereoMatchingAgree) {
  FeatureOptions options;
  options.adaptive_threshold = false;
  StereoMatcherOptions patch, descriptor;
  descriptor.mode = StereoMatchMode::kDescriptor;
  StereoFeatureExtractor by_patch(options, patch, rectifier_.camera());
  StereoFeatureExtractor by_descriptor(options, descriptor, rectifier_.camera());
  const StereoFeatures a = by_patch.Extract(left_, right_);
  const StereoFeatures b = by_descriptor.Extract(left_, right_);
  ASSERT_EQ(a.size(), b.size());
  int both = 0, agree = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (!a.HasDepth(i) || !b.HasDepth(i)) continue;
    ++both;
    if (std::abs(a.u_right[i] - b.u_right[i]) < 0.5) ++agree;
  }
  ASSERT_GT(both, 100);
  // Two independent ways of finding the right image point: they must find the same one.
  EXPECT_GE(agree, 0.97 * both) << agree << " of " << both;
}

// The grid's radius search against a brute-force one: every key point within the radius once,
// none outside, over random points that include cell borders, image edges and points off the
// image (binned into the border cells), and cells with several points.
TEST(KeypointGrid, RadiusSearchFindsExactlyThePointsWithinTheRadius) {
  const cv::Size size(752, 480);
  const int cell = 16;
  cv::RNG rng(7);
  std::vector<cv::KeyPoint> keypoints;
  for (int i = 0; i < 600; ++i) {
    keypoints.emplace_back(rng.uniform(-5.0F, 757.0F), rng.uniform(-5.0F, 485.0F), 7.0F);
  }
  for (int i = 0; i < 40; ++i) {  // exactly on cell borders
    keypoints.emplace_back(static_cast<float>(cell * rng.uniform(0, 48)),
                           static_cast<float>(cell * rng.uniform(0, 31)), 7.0F);
  }
  const features::KeypointGrid grid(keypoints, size, cell);
  int compared = 0;
  for (int query = 0; query < 300; ++query) {
    const double u = rng.uniform(-20.0, 772.0), v = rng.uniform(-20.0, 500.0);
    const double radius = rng.uniform(0.5, 40.0);
    std::multiset<int> found;
    grid.ForEachWithin(u, v, radius, [&](int i) { found.insert(i); });
    std::multiset<int> expected;
    for (int i = 0; i < static_cast<int>(keypoints.size()); ++i) {
      const double du = keypoints[i].pt.x - u, dv = keypoints[i].pt.y - v;
      if (du * du + dv * dv <= radius * radius) expected.insert(i);
    }
    EXPECT_EQ(found, expected) << "query (" << u << ", " << v << ") radius " << radius;
    compared += static_cast<int>(expected.size());
  }
  EXPECT_GT(compared, 300) << "the queries must find points to compare";
}

TEST(FeatureFactory, UnknownNamesListWhatIsAvailable) {
  FeatureOptions options;
  options.detector = "HARRIS";
  try {
    CreateDetector(options);
    ADD_FAILURE();
  } catch (const std::invalid_argument& error) {
    EXPECT_NE(std::string(error.what()).find("AGAST, FAST, ORB, AKAZE, SIFT"), std::string::npos);
  }
  options.detector = "AGAST";
  options.descriptor = "SURF";
  EXPECT_THROW(CreateDescriptor(options), std::invalid_argument);
  for (const std::string& name : AvailableDescriptors()) {
    options.descriptor = name;
    options.detector = name == "AKAZE" ? "AKAZE" : "AGAST";
    EXPECT_NO_THROW(CreateDescriptor(options)) << name;
  }
}

}  // namespace
}  // namespace stereo_fabmap_slam::test
