// The PnP kernel study's measures on cases with a known answer: every kernel on exact
// correspondences, on noisy ones with outliers, the matching to the reference's stereo points,
// and the aggregation per kernel and distance bin against hand-computed numbers.
#include "stereo_fabmap_slam/evaluation/pnp_study.h"

#include <cmath>
#include <random>
#include <sstream>

#include <gtest/gtest.h>

namespace stereo_fabmap_slam::test {
namespace {

using evaluation::PnpStatistics;
using evaluation::PnpTrial;
using geometry::PnpKernel;

const geometry::StereoCamera kCamera{cv::Size(752, 480), 435.0, 435.0, 367.0, 248.0, 0.11};

// The test camera 0.6 m from the reference, turned by 12 degrees: a test frame of the study's
// middle distances.
Eigen::Isometry3d TrueTestFromReference() {
  Eigen::Isometry3d T_reference_test = Eigen::Isometry3d::Identity();
  T_reference_test.linear() =
      Eigen::AngleAxisd(12.0 * M_PI / 180, Eigen::Vector3d(0.3, 1.0, 0.2).normalized())
          .toRotationMatrix();
  T_reference_test.translation() = Eigen::Vector3d(0.4, -0.1, 0.43);
  return T_reference_test.inverse();
}

// 250 points 2-12 m in front of the test camera (all inside its image), expressed in the
// reference frame, with their projections and stereo points in the test frame. `noise` px on
// every measurement; `outliers` of them replaced by random pixels and stereo points.
geometry::PointMatches MakeMatches(const Eigen::Isometry3d& T_test_reference, double noise,
                                   double outliers, std::uint64_t seed) {
  std::mt19937_64 random(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::normal_distribution<double> pixel_noise(0.0, noise > 0 ? noise : 1.0);
  const auto jitter = [&]() { return noise > 0 ? pixel_noise(random) : 0.0; };
  const Eigen::Isometry3d T_reference_test = T_test_reference.inverse();
  geometry::PointMatches matches;
  for (int i = 0; i < 250; ++i) {
    const double z = 2.0 + 10.0 * unit(random);
    const Eigen::Vector3d in_test((unit(random) * 740 + 6 - kCamera.cx) * z / kCamera.fx,
                                  (unit(random) * 468 + 6 - kCamera.cy) * z / kCamera.fy, z);
    const Eigen::Vector3d projected = kCamera.Project(in_test);
    Eigen::Vector3d measured(projected.x() + jitter(), projected.y() + jitter(), 0);
    measured.z() = measured.x() - (projected.x() - projected.z()) + jitter();  // u_right
    Eigen::Vector3d camera_point =
        noise > 0 ? kCamera.Triangulate(measured.x(), measured.y(), measured.x() - measured.z())
                  : in_test;
    if (unit(random) < outliers) {
      measured = Eigen::Vector3d(unit(random) * 752, unit(random) * 480, 0);
      measured.z() = measured.x() - 5 - 40 * unit(random);
      camera_point = kCamera.Triangulate(measured.x(), measured.y(), measured.x() - measured.z());
    }
    const Eigen::Vector3d world = T_reference_test * in_test;
    matches.correspondences.push_back(
        {world, Eigen::Vector2d(measured.x(), measured.y()), true, camera_point});
    matches.observations.push_back({world, measured.x(), measured.y(), measured.z()});
  }
  return matches;
}

TEST(PnpStudy, EveryKernelIsExactOnExactCorrespondences) {
  const Eigen::Isometry3d truth = TrueTestFromReference();
  const geometry::PointMatches matches = MakeMatches(truth, 0.0, 0.0, 3);
  double now = 0;
  const evaluation::Clock clock = [&now]() { return now += 1.0; };  // 1 ms between readings
  const std::vector<PnpKernel> kernels = evaluation::AllPnpKernels();
  ASSERT_EQ(kernels.size(), 6u);
  const std::vector<PnpTrial> trials =
      evaluation::RunPnpKernels(matches, kCamera, truth, kernels, {}, clock);
  ASSERT_EQ(trials.size(), 12u);
  for (std::size_t k = 0; k < trials.size(); ++k) {
    const PnpTrial& trial = trials[k];
    SCOPED_TRACE(std::string(geometry::kPnpKernelNames[k / 2].name) +
                 (trial.refined ? " refined" : ""));
    EXPECT_EQ(trial.kernel, kernels[k / 2]);
    EXPECT_EQ(trial.refined, k % 2 == 1);
    EXPECT_NEAR(trial.distance_m, std::hypot(0.4, 0.1, 0.43), 1e-12);
    EXPECT_EQ(trial.matches, 250);
    ASSERT_TRUE(trial.success);
    EXPECT_EQ(trial.inliers, 250);
    EXPECT_LT(trial.error.translation_m, 1e-6);
    EXPECT_LT(trial.error.rotation_deg, 1e-6);
    // RANSAC between two readings; the refined estimate adds the refinement's two.
    EXPECT_DOUBLE_EQ(trial.time_ms, trial.refined ? 2.0 : 1.0);
  }
}

TEST(PnpStudy, RansacKeepsEveryKernelCloseWithOutliers) {
  const Eigen::Isometry3d truth = TrueTestFromReference();
  const geometry::PointMatches matches = MakeMatches(truth, 0.5, 0.3, 11);
  evaluation::PnpStudyOptions options;
  options.ransac.max_iterations = 300;
  double now = 0;
  const std::vector<PnpTrial> trials = evaluation::RunPnpKernels(
      matches, kCamera, truth, evaluation::AllPnpKernels(), options, [&now]() { return ++now; });
  ASSERT_EQ(trials.size(), 12u);
  for (const PnpTrial& trial : trials) {
    SCOPED_TRACE(std::string(geometry::kPnpKernelNames[static_cast<int>(trial.kernel)].name) +
                 (trial.refined ? " refined" : ""));
    ASSERT_TRUE(trial.success);
    // ~175 inliers with 0.5 px noise at 2-12 m fix the position to millimetres and the rotation
    // to hundredths of a degree (as in pnp_ransac_test); 3 cm and 0.2 degrees leave a factor of
    // ~5 for the minimal kernels and the 3-D fit, and are still far below what a wrong
    // consensus gives (decimetres, degrees).
    EXPECT_LT(trial.error.translation_m, 0.03);
    EXPECT_LT(trial.error.rotation_deg, 0.2);
    // 30 % of 250 are outliers; a random pixel rarely lands within 2 px of the right place.
    EXPECT_GE(trial.inliers, 150);
    EXPECT_LE(trial.inliers, 190);
  }
}

TEST(PnpStudy, TooFewMatchesFailEveryKernel) {
  const Eigen::Isometry3d truth = TrueTestFromReference();
  geometry::PointMatches matches = MakeMatches(truth, 0.0, 0.0, 5);
  matches.correspondences.resize(10);
  matches.observations.resize(10);
  double now = 0;
  const std::vector<PnpTrial> trials = evaluation::RunPnpKernels(
      matches, kCamera, truth, evaluation::AllPnpKernels(), {}, [&now]() { return ++now; });
  for (const PnpTrial& trial : trials) {
    // Exact, but below the 20 inliers a relocalization would need.
    EXPECT_FALSE(trial.success);
    // RANSAC between two readings; a failed estimate is not refined, so the refined trial
    // costs the same.
    EXPECT_DOUBLE_EQ(trial.time_ms, 1.0);
  }
}

TEST(PnpStudy, ComparePosesMeasuresTheCameraPositionAndTheAngle) {
  Eigen::Isometry3d T_reference_test = Eigen::Isometry3d::Identity();
  T_reference_test.translation() = Eigen::Vector3d(1, 2, 3);
  T_reference_test.linear() = Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  Eigen::Isometry3d estimate = T_reference_test;
  estimate.translation() += Eigen::Vector3d(0.06, 0.0, -0.08);  // 10 cm off in the reference
  estimate.linear() =
      estimate.linear() *
      Eigen::AngleAxisd(2.0 * M_PI / 180, Eigen::Vector3d(1, 1, 0).normalized()).toRotationMatrix();
  const evaluation::PoseError error =
      evaluation::ComparePoses(estimate.inverse(), T_reference_test.inverse());
  EXPECT_NEAR(error.translation_m, 0.1, 1e-12);
  EXPECT_NEAR(error.rotation_deg, 2.0, 1e-9);
  const evaluation::PoseError none =
      evaluation::ComparePoses(T_reference_test.inverse(), T_reference_test.inverse());
  EXPECT_LT(none.translation_m, 1e-12);
  EXPECT_LT(none.rotation_deg, 1e-9);
}

TEST(PnpStudy, MatchesTheTestKeyPointsToTheReferenceStereoPoints) {
  // Reference: 4 key points, the second without depth; test: the same descriptors in another
  // order, plus one that matches nothing well.
  std::mt19937_64 random(2);
  cv::Mat descriptors(5, 32, CV_8U);
  for (int r = 0; r < descriptors.rows; ++r) {
    for (int c = 0; c < descriptors.cols; ++c) descriptors.at<std::uint8_t>(r, c) = random() & 255;
  }
  features::StereoFeatures reference;
  for (int i = 0; i < 4; ++i) {
    reference.keypoints.emplace_back(10.0f * i, 20.0f, 7.0f);
    reference.u_right.push_back(i == 1 ? -1.0f : 5.0f);
    reference.points.emplace_back(i, 0, 5);
  }
  reference.descriptors = descriptors.rowRange(0, 4).clone();
  features::StereoFeatures test;
  const int order[] = {3, 1, 0, 2, 4};  // test key point k shows descriptor order[k]
  for (int k = 0; k < 5; ++k) {
    test.keypoints.emplace_back(100.0f + k, 50.0f, 7.0f);
    test.u_right.push_back(k == 2 ? -1.0f : 90.0f);
    test.points.emplace_back(0, k, 4);
    test.descriptors.push_back(descriptors.row(order[k]));
  }
  const geometry::PointMatches matches =
      evaluation::MatchToReference(reference, test, cv::NORM_HAMMING, 80.0, 0.8);
  // Test key points 0, 2, 3 find reference points 3, 0, 2; 1 and 4 have no stereo partner.
  ASSERT_EQ(matches.correspondences.size(), 3u);
  const int keypoint[] = {0, 2, 3}, point[] = {3, 0, 2};
  for (int m = 0; m < 3; ++m) {
    const geometry::PnpCorrespondence& c = matches.correspondences[static_cast<std::size_t>(m)];
    EXPECT_EQ(c.world, Eigen::Vector3d(point[m], 0, 5));
    EXPECT_EQ(c.pixel, Eigen::Vector2d(100.0 + keypoint[m], 50.0));
    EXPECT_EQ(c.has_depth, keypoint[m] != 2);
    EXPECT_EQ(c.camera_point, Eigen::Vector3d(0, keypoint[m], 4));
    EXPECT_EQ(matches.observations[static_cast<std::size_t>(m)].u_right,
              keypoint[m] == 2 ? -1.0 : 90.0);
  }
}

PnpTrial Trial(PnpKernel kernel, bool refined, double distance, bool success, double translation,
               double rotation, double time) {
  PnpTrial trial;
  trial.kernel = kernel;
  trial.refined = refined;
  trial.distance_m = distance;
  trial.success = success;
  // A failure's error fields must not count: give them values that would show.
  trial.error =
      success ? evaluation::PoseError{translation, rotation} : evaluation::PoseError{9, 9};
  trial.time_ms = time;
  return trial;
}

std::vector<PnpTrial> HandTrials() {
  return {Trial(PnpKernel::kAp3p, false, 0.05, true, 0.01, 1.0, 2.0),
          Trial(PnpKernel::kAp3p, false, 0.20, true, 0.03, 3.0, 4.0),
          Trial(PnpKernel::kAp3p, false, 0.24, false, 0, 0, 6.0),
          Trial(PnpKernel::kAp3p, false, 0.30, true, 0.02, 2.0, 1.0),
          Trial(PnpKernel::kAp3p, true, 0.60, false, 0, 0, 5.0),
          Trial(PnpKernel::kEpnp, true, 0.10, true, 0.04, 0.5, 3.0)};
}

TEST(PnpStudy, AggregatesPerKernelRefinementAndDistanceBin) {
  const std::vector<PnpStatistics> rows = evaluation::AggregatePnpTrials(HandTrials(), 0.25);
  // EPNP before AP3P (kPnpKernelNames order), unrefined before refined, then by distance.
  ASSERT_EQ(rows.size(), 4u);
  EXPECT_EQ(rows[0].kernel, PnpKernel::kEpnp);
  EXPECT_TRUE(rows[0].refined);
  EXPECT_DOUBLE_EQ(rows[0].distance_m, 0.125);
  EXPECT_EQ(rows[0].trials, 1);
  EXPECT_DOUBLE_EQ(rows[0].translation_error_mean_m, 0.04);
  EXPECT_DOUBLE_EQ(rows[0].translation_error_std_m, 0.0);

  // AP3P, bin [0, 0.25): errors of the two successes {0.01, 0.03}, {1, 3}; times {2, 4, 6}.
  const PnpStatistics& near = rows[1];
  EXPECT_EQ(near.kernel, PnpKernel::kAp3p);
  EXPECT_FALSE(near.refined);
  EXPECT_DOUBLE_EQ(near.distance_m, 0.125);
  EXPECT_EQ(near.trials, 3);
  EXPECT_EQ(near.successes, 2);
  EXPECT_DOUBLE_EQ(near.success_fraction(), 2.0 / 3.0);
  EXPECT_NEAR(near.translation_error_mean_m, 0.02, 1e-15);
  EXPECT_NEAR(near.translation_error_std_m, std::sqrt(2e-4), 1e-15);
  EXPECT_DOUBLE_EQ(near.rotation_error_mean_deg, 2.0);
  EXPECT_DOUBLE_EQ(near.rotation_error_std_deg, std::sqrt(2.0));
  EXPECT_DOUBLE_EQ(near.time_mean_ms, 4.0);
  EXPECT_DOUBLE_EQ(near.time_std_ms, 2.0);

  const PnpStatistics& far = rows[2];
  EXPECT_FALSE(far.refined);
  EXPECT_DOUBLE_EQ(far.distance_m, 0.375);
  EXPECT_EQ(far.trials, 1);
  EXPECT_EQ(far.successes, 1);
  EXPECT_DOUBLE_EQ(far.rotation_error_mean_deg, 2.0);
  EXPECT_DOUBLE_EQ(far.time_std_ms, 0.0);

  // No success: no error to average, but the time counts.
  const PnpStatistics& failed = rows[3];
  EXPECT_TRUE(failed.refined);
  EXPECT_DOUBLE_EQ(failed.distance_m, 0.625);
  EXPECT_EQ(failed.successes, 0);
  EXPECT_DOUBLE_EQ(failed.success_fraction(), 0.0);
  EXPECT_TRUE(std::isnan(failed.translation_error_mean_m));
  EXPECT_TRUE(std::isnan(failed.rotation_error_std_deg));
  EXPECT_DOUBLE_EQ(failed.time_mean_ms, 5.0);

  EXPECT_THROW(evaluation::AggregatePnpTrials(HandTrials(), 0.0), std::invalid_argument);
}

TEST(PnpStudy, SummarizesOverAllDistances) {
  const std::vector<PnpStatistics> rows = evaluation::SummarizePnpTrials(HandTrials());
  ASSERT_EQ(rows.size(), 3u);  // EPNP refined, AP3P unrefined, AP3P refined
  const PnpStatistics& ap3p = rows[1];
  EXPECT_EQ(ap3p.kernel, PnpKernel::kAp3p);
  EXPECT_FALSE(ap3p.refined);
  EXPECT_EQ(ap3p.trials, 4);
  EXPECT_EQ(ap3p.successes, 3);
  // Errors {0.01, 0.03, 0.02}: mean 0.02, sample deviation 0.01; {1, 3, 2}: 2 and 1.
  EXPECT_NEAR(ap3p.translation_error_mean_m, 0.02, 1e-15);
  EXPECT_NEAR(ap3p.translation_error_std_m, 0.01, 1e-15);
  EXPECT_DOUBLE_EQ(ap3p.rotation_error_mean_deg, 2.0);
  EXPECT_DOUBLE_EQ(ap3p.rotation_error_std_deg, 1.0);
  // Times {2, 4, 6, 1}: mean 3.25, squared deviations 14.75 over 3.
  EXPECT_DOUBLE_EQ(ap3p.time_mean_ms, 3.25);
  EXPECT_NEAR(ap3p.time_std_ms, std::sqrt(14.75 / 3), 1e-12);
}

TEST(PnpStudy, WritesTheReportColumns) {
  std::ostringstream by_distance, summary;
  evaluation::WritePnpCsvHeader(by_distance, true);
  evaluation::WritePnpCsvRows(by_distance, "MH01",
                              evaluation::AggregatePnpTrials(HandTrials(), 0.25), true);
  evaluation::WritePnpCsvHeader(summary, false);
  evaluation::WritePnpCsvRows(summary, "MH01", evaluation::SummarizePnpTrials(HandTrials()), false);
  const std::string csv = by_distance.str();
  EXPECT_EQ(csv.substr(0, csv.find('\n')),
            "sequence,kernel,refined,distance_m,trials,successes,translation_error_mean_m,"
            "translation_error_std_m,rotation_error_mean_deg,rotation_error_std_deg,time_mean_ms,"
            "time_std_ms");
  EXPECT_NE(csv.find("\nMH01,EPNP,1,0.125,1,1,0.04,0,0.5,0,3,0\n"), std::string::npos) << csv;
  EXPECT_NE(csv.find("\nMH01,AP3P,1,0.625,1,0,nan,nan,nan,nan,5,0\n"), std::string::npos) << csv;
  const std::string table = summary.str();
  EXPECT_EQ(table.substr(0, table.find('\n')),
            "sequence,kernel,refined,trials,successes,translation_error_mean_m,"
            "translation_error_std_m,rotation_error_mean_deg,rotation_error_std_deg,time_mean_ms,"
            "time_std_ms");
  EXPECT_NE(table.find("\nMH01,AP3P,0,4,3,0.02,0.01,2,1,3.25,"), std::string::npos) << table;
  // Every line has as many fields as its header.
  for (const std::string& text : {csv, table}) {
    std::istringstream lines(text);
    std::string line;
    std::getline(lines, line);
    const auto fields = std::count(line.begin(), line.end(), ',');
    while (std::getline(lines, line)) EXPECT_EQ(std::count(line.begin(), line.end(), ','), fields);
  }
}

}  // namespace
}  // namespace stereo_fabmap_slam::test
