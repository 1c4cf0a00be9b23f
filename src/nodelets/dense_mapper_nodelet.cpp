// DenseMapper: the dense map beside the SLAM, in a nodelet (and library) of its own so that
// tracking never waits for it and never loads Open3D. The stereo pairs (as the StereoTracker
// gets them), keyframes and map_graph in; each keyframe's pair is matched by stamp, its depth
// fused at the keyframe's map pose in a worker thread, and moved again when map_graph moves the
// keyframe (dense::KeyframeVolume). dense_cloud (PointCloud2, thinned) and dense_mesh (a marker)
// out at ~rate when someone listens; save_mesh and save_cloud write PLY files.
#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <nodelet/nodelet.h>
#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>
#include <stereo_fabmap_slam/Keyframe.h>
#include <stereo_fabmap_slam/MapGraph.h>
#include <stereo_fabmap_slam/SavePly.h>
#include <visualization_msgs/Marker.h>
#include <pluginlib/class_list_macros.hpp>

#include "dense_messages.h"
#include "parameter_reader.h"
#include "ros_conversions.h"
#include "stereo_fabmap_slam/dense/keyframe_volume.h"
#include "stereo_fabmap_slam/dense/mesh_simplification.h"
#include "stereo_fabmap_slam/dense/ply_files.h"
#include "stereo_image_input.h"
#include "tracker_wiring.h"

namespace stereo_fabmap_slam {
namespace dense_mapper {

struct DenseMapperParameters {
  camera::RectificationOptions rectification;
  dense::StereoDepthOptions depth;
  dense::FusionOptions fusion;
  std::string calibration_file;
  bool use_camera_info = false;
  bool approximate_sync = false;
  std::string map_frame = "map";
  int queue_size = 10;
  // Pairs kept to find a keyframe's: the tracker publishes a keyframe after it has tracked its
  // pair, at most its queue (a few pairs) behind; 100 pairs are 5 s at EuRoC's 20 Hz.
  int buffered_pairs = 100;
  double rate = 0.5;         // [Hz] of dense_cloud and dense_mesh, when they changed
  double cloud_cell = 0.05;  // [m] one point of dense_cloud a cube of this edge
  // Triangles of dense_mesh at most (the mesh simplified until it fits): 100,000 are 12 MB a
  // message.
  int max_mesh_triangles = 100000;
  std::string save_mesh;  // a PLY file the mesh is written to when the nodelet shuts down
  std::string printed;
};

DenseMapperParameters ReadParameters(const ros::NodeHandle& private_node) {
  DenseMapperParameters p;
  p.rectification = ros_parameters::ReadModuleOptions(private_node, p.rectification);
  p.depth = ros_parameters::ReadModuleOptions(private_node, p.depth);
  p.fusion = ros_parameters::ReadModuleOptions(private_node, p.fusion);
  p.printed = ros_parameters::PrintedOptions(p.rectification) +
              ros_parameters::PrintedOptions(p.depth) + ros_parameters::PrintedOptions(p.fusion);
  p.use_camera_info = private_node.param("use_camera_info", p.use_camera_info);
  if (!p.use_camera_info && !private_node.getParam("calibration_file", p.calibration_file)) {
    throw std::invalid_argument("set ~calibration_file or ~use_camera_info");
  }
  p.approximate_sync = private_node.param("approximate_sync", p.approximate_sync);
  p.map_frame = private_node.param("map_frame", p.map_frame);
  p.queue_size = private_node.param("queue_size", p.queue_size);
  p.buffered_pairs = private_node.param("buffered_pairs", p.buffered_pairs);
  p.rate = private_node.param("rate", p.rate);
  p.cloud_cell = private_node.param("cloud_cell", p.cloud_cell);
  p.max_mesh_triangles = private_node.param("max_mesh_triangles", p.max_mesh_triangles);
  p.save_mesh = private_node.param("save_mesh", p.save_mesh);
  if (p.queue_size < 1 || p.buffered_pairs < 1 || !(p.rate > 0) || !(p.cloud_cell >= 0) ||
      p.max_mesh_triangles < 1) {
    throw std::invalid_argument(
        "~queue_size, ~buffered_pairs, ~rate and ~max_mesh_triangles must be > 0, ~cloud_cell >= "
        "0");
  }
  ros_parameters::RejectUnknownParameters(
      private_node, {"approximate_sync", "buffered_pairs", "calibration_file", "cloud_cell",
                     "config_file", "image_transport", "map_frame", "max_mesh_triangles",
                     "queue_size", "rate", "save_mesh", "use_camera_info"});
  return p;
}

}  // namespace dense_mapper

class DenseMapperNodelet : public nodelet::Nodelet {
 public:
  ~DenseMapperNodelet() override {
    input_.reset();  // no image callback runs on after this (StereoImageInput)
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stop_ = true;
    }
    wake_.notify_all();
    if (worker_.joinable()) worker_.join();
    SaveMeshAtShutdown();
  }

 private:
  // A keyframe with its pair, for the worker.
  struct Job {
    stereo_fabmap_slam::KeyframeConstPtr keyframe;
    ros_wiring::ImagePair pair;
  };

  void onInit() override;
  void Calibrate(const ros_input::MountedRig& rig);  // once; call with mutex_
  void OnPair(const sensor_msgs::ImageConstPtr& left, const sensor_msgs::ImageConstPtr& right);
  void OnKeyframe(const stereo_fabmap_slam::KeyframeConstPtr& keyframe);
  void OnGraph(const stereo_fabmap_slam::MapGraphConstPtr& graph);
  void Work();
  void Fuse(const Job& job, const Eigen::Isometry3d& T_map_odom,
            const std::map<std::uint64_t, Eigen::Isometry3d>& map_poses);
  void Publish();
  // ~save_mesh, when the graph shuts down (what the Recorder does for the run's files).
  void SaveMeshAtShutdown();
  template <typename Extract, typename Write>
  bool Save(const std::string& path, Extract extract, Write write,
            stereo_fabmap_slam::SavePly::Response* response);

  dense_mapper::DenseMapperParameters parameters_;

  std::mutex mutex_;  // what the callbacks hand the worker
  std::condition_variable wake_;
  std::optional<camera::StereoRectifier> rectifier_;          // set once (calibration)
  std::deque<ros_wiring::ImagePair> pairs_;                   // the latest pairs, by arrival
  std::deque<stereo_fabmap_slam::KeyframeConstPtr> waiting_;  // keyframes before their pair
  std::deque<Job> jobs_;
  stereo_fabmap_slam::MapGraphConstPtr graph_;
  bool graph_changed_ = false;
  bool stop_ = false;

  std::mutex volume_mutex_;  // the worker and the save services
  std::unique_ptr<dense::KeyframeVolume> volume_;
  bool changed_since_published_ = false;  // worker only
  std::vector<double> fuse_ms_;           // worker only: depth + fusion of the recent keyframes

  std::thread worker_;
  std::unique_ptr<ros_input::StereoImageInput> input_;
  ros::Subscriber keyframe_subscriber_, graph_subscriber_;
  ros::Publisher cloud_publisher_, mesh_publisher_;
  ros::ServiceServer save_mesh_service_, save_cloud_service_;
};

void DenseMapperNodelet::onInit() {
  ros::NodeHandle& node = getNodeHandle();
  try {
    parameters_ = dense_mapper::ReadParameters(getPrivateNodeHandle());
  } catch (const std::exception& error) {
    NODELET_FATAL_STREAM("bad configuration: " << error.what());
    throw;
  }
  const dense_mapper::DenseMapperParameters& p = parameters_;
  NODELET_INFO_STREAM("options in force:\n" << p.printed);
  if (!p.use_camera_info) {
    std::lock_guard<std::mutex> lock(mutex_);
    try {
      Calibrate(
          ros_input::RigFromCalibrationFile(p.calibration_file, p.rectification, std::nullopt));
    } catch (const std::exception& error) {
      NODELET_FATAL_STREAM("calibration: " << error.what());
      throw;
    }
  }
  // Latched: an rviz started later sees the map at once.
  cloud_publisher_ = node.advertise<sensor_msgs::PointCloud2>("dense_cloud", 1, true);
  mesh_publisher_ = node.advertise<visualization_msgs::Marker>("dense_mesh", 1, true);
  save_mesh_service_ = node.advertiseService<stereo_fabmap_slam::SavePly::Request,
                                             stereo_fabmap_slam::SavePly::Response>(
      "save_mesh", [this](auto& request, auto& response) {
        return Save(
            request.path, [](const dense::KeyframeVolume& volume) { return volume.ExtractMesh(); },
            [](const dense::Mesh& mesh, const std::string& path) {
              dense::WriteMeshPly(mesh, path);
              return mesh.vertices.size();
            },
            &response);
      });
  save_cloud_service_ = node.advertiseService<stereo_fabmap_slam::SavePly::Request,
                                              stereo_fabmap_slam::SavePly::Response>(
      "save_cloud", [this](auto& request, auto& response) {
        return Save(
            request.path, [](const dense::KeyframeVolume& volume) { return volume.ExtractCloud(); },
            [](const dense::Cloud& cloud, const std::string& path) {
              dense::WriteCloudPly(cloud, path);
              return cloud.points.size();
            },
            &response);
      });
  keyframe_subscriber_ = node.subscribe("keyframes", 100, &DenseMapperNodelet::OnKeyframe, this);
  graph_subscriber_ = node.subscribe("map_graph", 1, &DenseMapperNodelet::OnGraph, this);
  worker_ = std::thread(&DenseMapperNodelet::Work, this);
  input_ = std::make_unique<ros_input::StereoImageInput>(
      node, getPrivateNodeHandle(), p.queue_size, p.approximate_sync,
      [this](const auto& left, const auto& right) { OnPair(left, right); }, [](int) {});
  if (p.use_camera_info) {
    input_->SubscribeCameraInfo(node, p.queue_size, [this](const auto& left, const auto& right) {
      std::lock_guard<std::mutex> lock(mutex_);
      if (rectifier_) return;  // the first pair defines the rectification, as the tracker's
      try {
        Calibrate(ros_input::RigFromCameraInfo(*left, *right, std::nullopt));
      } catch (const std::exception& error) {
        NODELET_ERROR_STREAM_THROTTLE(2.0, "camera_info: " << error.what());
      }
    });
  }
  NODELET_INFO_STREAM("dense map of the keyframes from " << input_->Describe());
}

void DenseMapperNodelet::Calibrate(const ros_input::MountedRig& rig) {
  rectifier_.emplace(rig.rectifier);
  std::lock_guard<std::mutex> lock(volume_mutex_);
  volume_ = std::make_unique<dense::KeyframeVolume>(parameters_.depth, parameters_.fusion,
                                                    rectifier_->camera());
}

void DenseMapperNodelet::OnPair(const sensor_msgs::ImageConstPtr& left,
                                const sensor_msgs::ImageConstPtr& right) {
  std::lock_guard<std::mutex> lock(mutex_);
  // A keyframe that came first takes its pair at once; the rest wait for theirs.
  for (auto keyframe = waiting_.begin(); keyframe != waiting_.end(); ++keyframe) {
    if ((*keyframe)->header.stamp != left->header.stamp) continue;
    jobs_.push_back(Job{*keyframe, ros_wiring::ImagePair{left, right, 0}});
    waiting_.erase(keyframe);
    wake_.notify_one();
    return;
  }
  pairs_.push_back(ros_wiring::ImagePair{left, right, 0});
  while (pairs_.size() > static_cast<std::size_t>(parameters_.buffered_pairs)) pairs_.pop_front();
}

void DenseMapperNodelet::OnKeyframe(const stereo_fabmap_slam::KeyframeConstPtr& keyframe) {
  std::lock_guard<std::mutex> lock(mutex_);
  for (auto pair = pairs_.rbegin(); pair != pairs_.rend(); ++pair) {
    if (pair->left->header.stamp != keyframe->header.stamp) continue;
    jobs_.push_back(Job{keyframe, *pair});
    wake_.notify_one();
    return;
  }
  // Its pair has not come yet (or was missed: the waiting list is bounded like the pairs).
  waiting_.push_back(keyframe);
  while (waiting_.size() > static_cast<std::size_t>(parameters_.buffered_pairs)) {
    NODELET_WARN_STREAM("no stereo pair for keyframe " << waiting_.front()->id
                                                       << ": it stays out of the dense map");
    waiting_.pop_front();
  }
}

void DenseMapperNodelet::OnGraph(const stereo_fabmap_slam::MapGraphConstPtr& graph) {
  std::lock_guard<std::mutex> lock(mutex_);
  graph_ = graph;
  graph_changed_ = true;
  wake_.notify_one();
}

void DenseMapperNodelet::Work() {
  // Below the other stages: on a machine of two cores the tracker must not wait for the dense
  // map (Linux gives each thread its own nice value).
  if (setpriority(PRIO_PROCESS, static_cast<id_t>(syscall(SYS_gettid)), 10) != 0)
    NODELET_WARN("could not lower the dense mapping thread's priority");
  const auto period = std::chrono::duration<double>(1.0 / parameters_.rate);
  auto last_published = std::chrono::steady_clock::now();
  Eigen::Isometry3d T_map_odom = Eigen::Isometry3d::Identity();
  std::map<std::uint64_t, Eigen::Isometry3d> map_poses;
  // After a loop closes every map_graph moves most keyframes a little: fused again all at once
  // they kept the worker minutes behind the new keyframes on the demo's loop (rviz beside it).
  // So new keyframes come first, then at most this many moves (those that moved most), about a
  // keyframe period's work (70-100 ms each beside the tracker), until none is left.
  constexpr std::size_t kMovesPerRound = 4;
  bool moves_pending = false;
  while (true) {
    std::deque<Job> jobs;
    stereo_fabmap_slam::MapGraphConstPtr graph;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      wake_.wait_for(lock, moves_pending ? std::chrono::duration<double>(0) : period,
                     [this] { return stop_ || !jobs_.empty() || graph_changed_; });
      if (stop_) return;
      jobs.swap(jobs_);
      if (graph_changed_) graph = graph_;
      graph_changed_ = false;
    }
    if (graph) {
      T_map_odom = ros_conversions::FromTransformMessage(graph->map_to_odom);
      map_poses.clear();
      for (std::size_t i = 0; i < graph->keyframe_ids.size() && i < graph->keyframe_poses.size();
           ++i)
        map_poses[graph->keyframe_ids[i]] =
            ros_conversions::FromPoseMessage(graph->keyframe_poses[i]);
      moves_pending = true;
    }
    for (const Job& job : jobs) Fuse(job, T_map_odom, map_poses);
    if (moves_pending) {
      std::lock_guard<std::mutex> lock(volume_mutex_);
      const std::size_t moved = volume_ ? volume_->Move(map_poses, kMovesPerRound) : 0;
      moves_pending = moved == kMovesPerRound;
      if (moved > 0) {
        changed_since_published_ = true;
        NODELET_INFO_STREAM_THROTTLE(
            5.0, "keyframes moved by the map are fused again at their new poses ("
                     << volume_->Moving(map_poses) << " still to move)");
      }
    }
    if (changed_since_published_ && std::chrono::steady_clock::now() - last_published >= period) {
      Publish();
      last_published = std::chrono::steady_clock::now();
    }
  }
}

void DenseMapperNodelet::Fuse(const Job& job, const Eigen::Isometry3d& T_map_odom,
                              const std::map<std::uint64_t, Eigen::Isometry3d>& map_poses) {
  std::string refusal;
  const std::optional<pipeline::StereoPair> pair = ros_wiring::StereoPairOf(job.pair, &refusal);
  if (!pair) {
    NODELET_WARN_STREAM_THROTTLE(2.0, "keyframe " << job.keyframe->id << ": " << refusal);
    return;
  }
  cv::Mat left, right;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!rectifier_) return;  // not calibrated yet (camera_info)
    try {
      rectifier_->Rectify(pair->left, pair->right, &left, &right);
    } catch (const std::invalid_argument& error) {  // not of the calibrated size
      NODELET_WARN_STREAM_THROTTLE(2.0, "keyframe " << job.keyframe->id << ": " << error.what());
      return;
    }
  }
  // The map pose: the graph's, or the keyframe's odometry pose through the map's correction
  // until the graph has it.
  const auto in_map = map_poses.find(job.keyframe->id);
  const Eigen::Isometry3d T_map_camera =
      in_map != map_poses.end() ? in_map->second
                                : T_map_odom * ros_conversions::FromPoseMessage(job.keyframe->pose);
  dense::KeyframeVolume::Timing timing;
  std::lock_guard<std::mutex> lock(volume_mutex_);
  if (!volume_ || !volume_->Add(job.keyframe->id, left, right, T_map_camera, &timing)) return;
  changed_since_published_ = true;
  fuse_ms_.push_back(timing.depth_ms + timing.fusion_ms);
  if (fuse_ms_.size() == 20) {
    std::sort(fuse_ms_.begin(), fuse_ms_.end());
    NODELET_INFO(
        "%zu keyframes fused (depth + fusion: median %.1f ms over the last 20), %zu "
        "blocks, %.0f MB",
        volume_->keyframes(), fuse_ms_[10], volume_->fusion().blocks(),
        volume_->memory_bytes() / 1048576.0);
    fuse_ms_.clear();
  }
}

void DenseMapperNodelet::Publish() {
  const bool cloud_wanted = cloud_publisher_.getNumSubscribers() > 0;
  const bool mesh_wanted = mesh_publisher_.getNumSubscribers() > 0;
  if (!cloud_wanted && !mesh_wanted) return;  // latched later, when someone listens
  std::optional<dense::Cloud> cloud;
  std::optional<dense::Mesh> mesh;
  {
    std::lock_guard<std::mutex> lock(volume_mutex_);
    if (!volume_) return;
    if (cloud_wanted) cloud = volume_->ExtractCloud();
    if (mesh_wanted) mesh = volume_->ExtractMesh();
  }
  changed_since_published_ = false;
  const ros::Time stamp = ros::Time::now();
  if (cloud) {
    cloud_publisher_.publish(ros_visualization::DenseCloudMessage(*cloud, parameters_.cloud_cell,
                                                                  parameters_.map_frame, stamp));
  }
  if (mesh) {
    // Coarser until it fits: vertices merged per cube of twice the voxel, then doubled (the
    // demo's 40 s loop: 2.3 million triangles at 2 cm).
    const auto max_triangles = static_cast<std::size_t>(parameters_.max_mesh_triangles);
    for (double cell = 2.0 * parameters_.fusion.voxel_size; mesh->triangles.size() > max_triangles;
         cell *= 2.0) {
      *mesh = dense::SimplifiedMesh(*mesh, cell);
    }
    mesh_publisher_.publish(
        ros_visualization::DenseMeshMarker(*mesh, max_triangles, parameters_.map_frame, stamp));
  }
}

void DenseMapperNodelet::SaveMeshAtShutdown() {
  if (parameters_.save_mesh.empty()) return;
  std::lock_guard<std::mutex> lock(volume_mutex_);
  if (!volume_) return;
  try {
    const dense::Mesh mesh = volume_->ExtractMesh();
    dense::WriteMeshPly(mesh, parameters_.save_mesh);
    NODELET_INFO_STREAM("wrote " << parameters_.save_mesh << ": " << mesh.vertices.size()
                                 << " vertices of " << volume_->keyframes() << " keyframes");
  } catch (const std::exception& error) {
    NODELET_ERROR_STREAM("~save_mesh " << parameters_.save_mesh << ": " << error.what());
  }
}

template <typename Extract, typename Write>
bool DenseMapperNodelet::Save(const std::string& path, Extract extract, Write write,
                              stereo_fabmap_slam::SavePly::Response* response) {
  try {
    std::lock_guard<std::mutex> lock(volume_mutex_);
    if (!volume_) throw std::runtime_error("not calibrated yet: no camera_info came");
    response->vertices = static_cast<std::uint32_t>(write(extract(*volume_), path));
    response->success = true;
    response->message =
        "wrote " + path + " (" + std::to_string(volume_->keyframes()) + " keyframes)";
  } catch (const std::exception& error) {
    response->success = false;
    response->message = error.what();
  }
  NODELET_INFO_STREAM("save " << path << ": " << response->message);
  return true;
}

}  // namespace stereo_fabmap_slam

PLUGINLIB_EXPORT_CLASS(stereo_fabmap_slam::DenseMapperNodelet, nodelet::Nodelet)
