// evaluate_reconstruction: a dense mesh or cloud (run_dataset --dense, the DenseMapper's
// save_mesh / save_cloud) against a reference: the exact geometry of a rendered sequence, or
// any reference point cloud (e.g. the laser scan of EuRoC's Vicon room). Accuracy: distances of
// the reconstruction's points to the reference (median, 90th percentile); completeness: the
// fraction of the reference within --radius of the reconstruction.
#include <cstdio>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "command_line.h"
#include "stereo_fabmap_slam/camera/camera_calibration.h"
#include "stereo_fabmap_slam/camera/stereo_rectifier.h"
#include "stereo_fabmap_slam/datasets/hall_scene.h"
#include "stereo_fabmap_slam/datasets/synthetic_sequence.h"
#include "stereo_fabmap_slam/dense/ply_files.h"
#include "stereo_fabmap_slam/dense/surface_comparison.h"
#include "stereo_fabmap_slam/evaluation/pose_interpolation.h"
#include "stereo_fabmap_slam/evaluation/trajectory.h"
#include "stereo_fabmap_slam/evaluation/trajectory_metrics.h"
#include "stereo_fabmap_slam/evaluation/trajectory_plot.h"
#include "stereo_fabmap_slam/io/trajectory_file.h"

namespace {

using namespace stereo_fabmap_slam;

constexpr char kUsage[] =
    "usage: evaluate_reconstruction RECONSTRUCTION.ply (--sequence DIR | --reference REF.ply)\n"
    "                               [--run RUN_DIR [--gt GT --calibration STEREO.yaml]]\n"
    "                               [--radius 0.05] [--max-depth 6] [--picture OUT.png] [--json]\n"
    "RECONSTRUCTION.ply: a mesh (its vertices) or a point cloud, e.g. mesh.ply of\n"
    "run_dataset --dense or of the DenseMapper's save_mesh.\n"
    "--sequence DIR: a rendered sequence (make_synthetic_sequence); the reference is its exact\n"
    "geometry. Accuracy: each point's distance to the nearest surface; completeness (with --run):\n"
    "the surface the run's keyframes saw, ray-cast from their true poses through every 8th pixel\n"
    "within --max-depth, covered within --radius; and of that surface the walls (with the sides\n"
    "of pillars and boxes) and what faces up or down (floor, ceiling, tops of boxes) apart.\n"
    "--reference REF.ply: any reference cloud; accuracy: each point's distance to the nearest\n"
    "reference point; completeness: the reference's points covered within --radius.\n"
    "--run RUN_DIR: the run that made the reconstruction (trajectory.txt, keyframes.txt): its\n"
    "trajectory is aligned to the ground truth (SE(3), as evaluate_trajectory) and the alignment\n"
    "moves the reconstruction into the reference's frame. The ground truth is the sequence's\n"
    "(with --sequence) or --gt, moved to the rectified left camera of --calibration.\n"
    "Without --run the reconstruction is taken to be in the reference's frame already.\n"
    "--picture: a top view of the reconstruction coloured by its distance to the reference.\n";

struct Run {
  evaluation::Similarity3 alignment;       // run frame -> reference frame
  evaluation::Trajectory true_keyframes;   // ground truth at the keyframes' stamps
  std::vector<Eigen::Vector3d> keyframes;  // aligned keyframe positions
};

evaluation::Trajectory Read(const std::string& path) { return io::ReadTrajectory(path); }

Run AlignRun(const std::string& run_dir, const std::string& gt_path,
             const camera::StereoRectifier& rectifier) {
  const evaluation::Trajectory ground_truth =
      evaluation::TransformToSensorFrame(Read(gt_path), rectifier.T_body_rectified_left());
  evaluation::EvaluationOptions options;
  const evaluation::EvaluationResult result =
      evaluation::EvaluateTrajectory(ground_truth, Read(run_dir + "/trajectory.txt"), options);
  Run run;
  run.alignment = result.alignment;
  for (const evaluation::StampedPose& keyframe : Read(run_dir + "/keyframes.txt")) {
    run.keyframes.push_back(run.alignment * keyframe.pose.translation());
    if (const auto truth = evaluation::InterpolatePose(ground_truth, keyframe.timestamp, 0.1))
      run.true_keyframes.push_back({keyframe.timestamp, *truth});
  }
  std::fprintf(stderr, "run aligned to the ground truth: ATE %.4f m over %zu poses\n",
               result.ate.rmse, result.matched);
  return run;
}

// The surface a rendered scene shows each camera pose, every 8th rectified pixel, within reach,
// split by the way the surface faces: walls (and the sides of pillars and boxes) and what faces
// up or down (floor, ceiling, tops of boxes). The hall is made of axis-aligned boxes (z up), so
// the face is the axis along which the distance to the scene changes fastest, 2 cm in front of
// the surface toward the camera.
struct SeenSurfaces {
  std::vector<Eigen::Vector3d> walls, horizontal;
};

SeenSurfaces SeenSurface(const datasets::HallScene& scene, const evaluation::Trajectory& poses,
                         const geometry::StereoCamera& camera, double max_depth) {
  constexpr float kBack = 0.02f, kStep = 0.005f;  // [m]
  SeenSurfaces seen;
  for (const evaluation::StampedPose& pose : poses) {
    const Eigen::Vector3f origin = pose.pose.translation().cast<float>();
    const Eigen::Matrix3f rotation = pose.pose.linear().cast<float>();
    for (int v = 0; v < camera.size.height; v += 8) {
      for (int u = 0; u < camera.size.width; u += 8) {
        const Eigen::Vector3f ray(static_cast<float>((u - camera.cx) / camera.fx),
                                  static_cast<float>((v - camera.cy) / camera.fy), 1.0f);
        const Eigen::Vector3f direction = (rotation * ray).normalized();
        const float distance = scene.Distance(origin, direction);
        if (!(distance > 0.0f) || distance / ray.norm() > max_depth)
          continue;  // z = distance * cos
        const Eigen::Vector3f point = origin + distance * direction;
        const Eigen::Vector3f in_front = point - kBack * direction;
        Eigen::Vector3f change;
        for (int axis = 0; axis < 3; ++axis) {
          const Eigen::Vector3f step = kStep * Eigen::Vector3f::Unit(axis);
          change[axis] = std::abs(scene.SurfaceDistance(in_front + step) -
                                  scene.SurfaceDistance(in_front - step));
        }
        Eigen::Index normal_axis = 0;
        change.maxCoeff(&normal_axis);
        (normal_axis == 2 ? seen.horizontal : seen.walls).push_back(point.cast<double>());
      }
    }
  }
  return seen;
}

// Top view, points binned by error into colours from blue (0) to red (2 x radius and beyond),
// with the keyframes' aligned path.
void DrawPicture(const std::vector<Eigen::Vector3d>& points, const std::vector<double>& distances,
                 const std::vector<Eigen::Vector3d>& keyframes, double radius,
                 const std::string& title, const std::string& path) {
  constexpr int kBins = 5;
  const cv::Scalar colours[kBins] = {
      {255, 0, 0}, {255, 200, 0}, {0, 200, 0}, {0, 200, 255}, {0, 0, 255}};  // BGR
  std::vector<std::vector<Eigen::Vector3d>> binned(kBins);
  for (std::size_t i = 0; i < points.size(); ++i) {
    const int bin =
        std::min(kBins - 1, static_cast<int>(distances[i] / (2.0 * radius) * (kBins - 1)));
    binned[static_cast<std::size_t>(bin)].push_back(points[i]);
  }
  // The worst first: later layers cover earlier ones, and where good and bad surfaces lie above
  // each other (a wall and the noise beside it) the picture shows the good one.
  evaluation::TrajectoryPlot plot;
  for (int b = kBins - 1; b >= 0; --b) {
    char label[64];
    const double step = 2.0 * radius / (kBins - 1) * 100.0;
    if (b < kBins - 1)
      std::snprintf(label, sizeof(label), "%.1f-%.1f cm", b * step, (b + 1) * step);
    else
      std::snprintf(label, sizeof(label), ">= %.1f cm", b * step);
    plot.AddPoints(binned[static_cast<std::size_t>(b)], colours[b], label, 1);
  }
  if (!keyframes.empty()) plot.AddPath(keyframes, cv::Scalar(0, 0, 0), "keyframes", 2);
  if (!cv::imwrite(path, plot.Render(cv::Size(1200, 900), title)))
    throw std::runtime_error("cannot write " + path);
}

}  // namespace

int main(int argc, char** argv) {
  std::optional<tools::CommandLine> args;
  try {
    args.emplace(argc, argv,
                 std::set<std::string>{"sequence", "reference", "run", "gt", "calibration",
                                       "radius", "max-depth", "picture"},
                 std::set<std::string>{"json", "help"});
    if (args->Flag("help")) {
      std::fputs(kUsage, stdout);
      return 0;
    }
    if (args->positional().size() != 1)
      throw std::invalid_argument("one reconstruction (PLY) expected");
    if (args->Value("sequence").has_value() == args->Value("reference").has_value())
      throw std::invalid_argument("give one of --sequence and --reference");
    if (args->Value("run") && !args->Value("sequence") &&
        !(args->Value("gt") && args->Value("calibration")))
      throw std::invalid_argument("--run with --reference needs --gt and --calibration");
    if (!(args->NumberOr("radius", 0.05) > 0) || !(args->NumberOr("max-depth", 6.0) > 0))
      throw std::invalid_argument("--radius and --max-depth must be > 0");
  } catch (const std::invalid_argument& error) {
    std::fprintf(stderr, "evaluate_reconstruction: %s\n%s", error.what(), kUsage);
    return 2;
  }
  try {
    const double radius = args->NumberOr("radius", 0.05);
    const double max_depth = args->NumberOr("max-depth", 6.0);
    std::vector<Eigen::Vector3d> points = dense::ReadCloudPly(args->positional()[0]).points;
    if (points.empty()) throw std::runtime_error(args->positional()[0] + " has no points");
    const std::optional<std::string> sequence = args->Value("sequence");
    const std::string calibration =
        sequence ? *sequence + "/stereo_calibration.yaml" : args->ValueOr("calibration", "");
    std::optional<Run> run;
    std::optional<camera::StereoRectifier> rectifier;
    if (const auto run_dir = args->Value("run")) {
      rectifier.emplace(
          camera::StereoRectifier::FromCalibration(camera::ReadStereoCalibrationYaml(calibration)));
      const std::string gt =
          sequence ? *sequence + "/mav0/state_groundtruth_estimate0/data.csv" : *args->Value("gt");
      run = AlignRun(*run_dir, gt, *rectifier);
      for (Eigen::Vector3d& point : points) point = run->alignment * point;
    }

    std::vector<double> distances;
    std::vector<Eigen::Vector3d> reference;
    SeenSurfaces seen;
    if (sequence) {
      const datasets::HallScene scene = datasets::SyntheticSequence::SceneOf(*sequence);
      for (const Eigen::Vector3d& point : points)
        distances.push_back(scene.SurfaceDistance(point.cast<float>()));
      if (run) {
        seen = SeenSurface(scene, run->true_keyframes, rectifier->camera(), max_depth);
        reference = seen.walls;
        reference.insert(reference.end(), seen.horizontal.begin(), seen.horizontal.end());
      }
    } else {
      reference = dense::ReadCloudPly(*args->Value("reference")).points;
      distances = dense::NearestDistances(points, reference);
    }
    const double median = dense::Quantile(distances, 0.5), p90 = dense::Quantile(distances, 0.9);
    const bool has_completeness = !reference.empty();
    // With the faces apart (a rendered world) the whole is their average by points: one search
    // of the reconstruction per kind, none again for the whole.
    const bool has_faces = !seen.walls.empty() || !seen.horizontal.empty();
    const double walls_completeness = dense::Completeness(points, seen.walls, radius);
    const double horizontal_completeness = dense::Completeness(points, seen.horizontal, radius);
    double completeness = 0.0;
    if (has_faces) {
      completeness = (walls_completeness * seen.walls.size() +
                      horizontal_completeness * seen.horizontal.size()) /
                     reference.size();
    } else if (has_completeness) {
      completeness = dense::Completeness(points, reference, radius);
    }

    if (args->Flag("json")) {
      std::printf("{\"points\": %zu, \"accuracy_median\": %.6f, \"accuracy_p90\": %.6f",
                  points.size(), median, p90);
      if (has_completeness)
        std::printf(", \"completeness\": %.6f, \"reference_points\": %zu, \"radius\": %.3f",
                    completeness, reference.size(), radius);
      if (has_faces)
        std::printf(
            ", \"completeness_walls\": %.6f, \"wall_points\": %zu, "
            "\"completeness_horizontal\": %.6f, \"horizontal_points\": %zu",
            walls_completeness, seen.walls.size(), horizontal_completeness, seen.horizontal.size());
      std::printf("}\n");
    } else {
      std::printf("points               %zu\n", points.size());
      std::printf("accuracy median      %.4f m\n", median);
      std::printf("accuracy 90 %%        %.4f m\n", p90);
      if (has_completeness)
        std::printf("completeness         %.4f (of %zu reference points within %.3f m)\n",
                    completeness, reference.size(), radius);
      else
        std::printf("completeness         - (needs --run with --sequence, or --reference)\n");
      if (has_faces) {
        std::printf("  of the walls       %.4f (%zu points: walls, sides of pillars and boxes)\n",
                    walls_completeness, seen.walls.size());
        std::printf("  facing up or down  %.4f (%zu points: floor, ceiling, tops of boxes)\n",
                    horizontal_completeness, seen.horizontal.size());
      }
    }
    if (const auto picture = args->Value("picture")) {
      char title[160];
      std::snprintf(title, sizeof(title),
                    "distance to the reference: median %.1f cm, 90 %% %.1f cm", 100 * median,
                    100 * p90);
      DrawPicture(points, distances, run ? run->keyframes : std::vector<Eigen::Vector3d>{}, radius,
                  title, *picture);
    }
  } catch (const std::exception& error) {
    std::fprintf(stderr, "evaluate_reconstruction: %s\n", error.what());
    return 1;
  }
  return 0;
}
