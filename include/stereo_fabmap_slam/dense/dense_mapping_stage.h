#pragma once

#include <cstddef>
#include <cstdint>
#include <deque>
#include <map>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "stereo_fabmap_slam/camera/stereo_rectifier.h"
#include "stereo_fabmap_slam/dense/dense_options.h"
#include "stereo_fabmap_slam/dense/keyframe_volume.h"

namespace stereo_fabmap_slam::dense {

// A raw (unrectified) mono8 stereo pair of the calibrated size, by its stamp. The stage keeps
// the images: they must own their data (a copy of a message's, not a view of it).
struct DenseStereoPair {
  std::int64_t stamp_ns = 0;
  cv::Mat left, right;
};

// A keyframe as the tracker made it: its id, the stamp of its pair and its odometry pose (the
// rectified left camera in odom).
struct DenseKeyframe {
  std::uint64_t id = 0;
  std::int64_t stamp_ns = 0;
  Eigen::Isometry3d T_odom_camera = Eigen::Isometry3d::Identity();
};

// The map's state as the stage follows it: map -> odom and the map poses of the keyframes it
// holds (a MapGraph message, a StereoSlam's MapState).
struct DenseMapUpdate {
  Eigen::Isometry3d T_map_odom = Eigen::Isometry3d::Identity();
  std::map<std::uint64_t, Eigen::Isometry3d> keyframe_poses;
};

// Any input of the stage, as a driver queues them in arrival order.
using DenseInput = std::variant<DenseStereoPair, DenseKeyframe, DenseMapUpdate>;

// What one Step did.
struct DenseStepReport {
  struct Fused {
    std::uint64_t id = 0;
    KeyframeVolume::Timing timing;
  };
  std::vector<Fused> fused;  // new keyframes, in the order they came
  // Keyframes left out of the dense map, and why (their pair never came while the stage kept
  // pairs, or it was not of the calibrated size).
  std::vector<std::string> left_out;
  std::size_t moved = 0;         // keyframes fused again where the map moved them
  std::size_t still_moving = 0;  // keyframes the map moved that wait for a later step
  // Set by the step whose fusions took the keyframes fused so far across a multiple of
  // kEvery: what a driver logs now and then about the dense map's cost and size.
  struct Progress {
    static constexpr std::size_t kEvery = 20;
    std::size_t keyframes = 0;         // in the volume
    double recent_fuse_median_ms = 0;  // depth + fusion, median of the last kEvery new ones
    std::size_t blocks = 0;
    double megabytes = 0;  // the volume's memory
  };
  std::optional<Progress> progress;

  bool changed() const { return !fused.empty() || moved > 0; }
};

// The dense mapping stage: what the DenseMapper nodelet runs in its worker thread and
// run_dataset --dense after each frame (docs/architecture.md). Stereo pairs, keyframes and the
// map's keyframe poses in; each keyframe is matched with its pair by stamp, its depth fused at
// its map pose (dense::KeyframeVolume), and fused again when the map moves it. The policy of
// what comes first lives here, so the graph and the offline runner make the same map: new
// keyframes are fused in the step after they and their pair came, then at most
// `moves_per_step` of the keyframes the map moved, those that moved most first, until none is
// left. Not thread-safe: one thread calls it (the nodelet queues its callbacks' inputs).
class DenseMappingStage {
 public:
  // Throws std::invalid_argument for invalid options.
  DenseMappingStage(const DenseMappingOptions& options, const StereoDepthOptions& depth_options,
                    const FusionOptions& fusion_options, const camera::StereoRectifier& rectifier);

  // The pairs, keyframes and map in the order they come; a keyframe may come before or after
  // its pair. Only the latest `buffered_pairs` pairs and as many waiting keyframes are kept.
  void AddPair(DenseStereoPair pair);
  void AddKeyframe(const DenseKeyframe& keyframe);
  // The map's state: map -> odom and the keyframes' map poses (those it holds; the others are
  // fused at their odometry pose through map -> odom until the map has them).
  void SetMap(const Eigen::Isometry3d& T_map_odom,
              std::map<std::uint64_t, Eigen::Isometry3d> keyframe_poses);
  // One of the three above.
  void Add(DenseInput input);

  // One round of work (see the class comment). Throws what Open3D throws (memory).
  DenseStepReport Step();
  // Whether a Step now would do something: a keyframe with its pair waits or the map moved
  // keyframes that were not fused again yet.
  bool busy() const { return !ready_.empty() || moves_pending_; }

  const KeyframeVolume& volume() const { return volume_; }
  // Depth and fusion times of every new keyframe fused so far, in order (not the moves): what
  // the nodelet's log and run_dataset's summary report.
  const std::vector<KeyframeVolume::Timing>& fused_timings() const { return fused_timings_; }
  // Median depth + fusion time [ms] of the last `count` new keyframes fused (fewer if fewer
  // were); 0 before the first.
  double RecentFuseMedianMs(std::size_t count) const;
  // Whether a step changed the map (new keyframes fused, or moved ones fused again) since the
  // view (cloud, mesh) was last sent: a viewer's output need not be rebuilt otherwise.
  bool view_changed() const { return view_changed_; }
  void ViewSent() { view_changed_ = false; }
  // The mesh and the point cloud written as PLY files (dense/ply_files.h); the mesh is returned
  // for what the caller reports of it, the cloud's point count likewise. Throw on I/O errors.
  Mesh SaveMesh(const std::string& path) const;
  std::size_t SaveCloud(const std::string& path) const;
  // The mesh simplified until it has at most `max_triangles` (for a viewer: rviz draws
  // 100,000 triangles smoothly); vertices merged per cube of twice the voxel, then doubled.
  Mesh ViewerMesh(std::size_t max_triangles) const;

 private:
  struct Ready {
    DenseKeyframe keyframe;
    DenseStereoPair pair;
  };
  Eigen::Isometry3d MapPose(const DenseKeyframe& keyframe) const;
  void Fuse(const Ready& ready, DenseStepReport* report);

  DenseMappingOptions options_;
  camera::StereoRectifier rectifier_;
  KeyframeVolume volume_;
  std::deque<DenseStereoPair> pairs_;  // the latest, by arrival
  std::deque<DenseKeyframe> waiting_;  // keyframes before their pair
  std::deque<Ready> ready_;            // keyframes with their pair, for the next step
  std::vector<std::string> left_out_;  // since the last step
  Eigen::Isometry3d T_map_odom_ = Eigen::Isometry3d::Identity();
  std::map<std::uint64_t, Eigen::Isometry3d> map_poses_;
  bool moves_pending_ = false;
  std::vector<KeyframeVolume::Timing> fused_timings_;
  bool view_changed_ = false;
};

}  // namespace stereo_fabmap_slam::dense
