// DenseMapper: the dense mapping stage (dense::DenseMappingStage) in the nodelet graph, in a
// nodelet (and library) of its own so that tracking never waits for it and never loads Open3D.
// The stereo pairs (as the StereoTracker gets them), keyframes and map_graph in, queued in
// arrival order for a worker thread it owns at a lower priority; the stage decides what is fused
// when. dense_cloud (PointCloud2, thinned) and dense_mesh (a marker) out at ~rate when someone
// listens; save_mesh and save_cloud write PLY files.
#include <chrono>
#include <cstdint>
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
#include <stereo_fabmap_slam/SavePly.h>
#include <visualization_msgs/Marker.h>
#include <pluginlib/class_list_macros.hpp>

#include "dense_messages.h"
#include "dense_wiring.h"
#include "stereo_fabmap_slam/dense/dense_mapping_stage.h"
#include "stereo_image_input.h"

namespace stereo_fabmap_slam {
class DenseMapperNodelet : public nodelet::Nodelet {
 public:
  ~DenseMapperNodelet() override {
    input_.reset();  // no image callback runs on after this (StereoImageInput)
    inputs_.Stop();
    if (worker_.joinable()) worker_.join();
    SaveMeshAtShutdown();
  }

 private:
  void onInit() override;
  void Calibrate(const ros_input::MountedRig& rig);
  void Work();
  void Report(const dense::DenseStepReport& report);  // the worker's
  void Publish();
  // ~save_mesh, when the graph shuts down (what the Recorder does for the run's files).
  void SaveMeshAtShutdown();
  // `save` writes `path` from the stage and returns the vertices or points written.
  template <typename SaveTo>
  bool Save(const std::string& path, SaveTo save, stereo_fabmap_slam::SavePly::Response* response);

  ros_wiring::DenseMapperParameters parameters_;

  // The worker's, and the save services' (set once, when the calibration is known).
  std::mutex stage_mutex_;
  std::optional<dense::DenseMappingStage> stage_;
  ros_wiring::DenseMapperQueue inputs_;  // in the order they arrived: the stage takes them so

  std::thread worker_;
  std::unique_ptr<ros_input::StereoImageInput> input_;
  ros::Subscriber keyframe_subscriber_, graph_subscriber_;
  ros::Publisher cloud_publisher_, mesh_publisher_;
  ros::ServiceServer save_mesh_service_, save_cloud_service_;
};

void DenseMapperNodelet::onInit() {
  ros::NodeHandle& node = getNodeHandle();
  try {
    parameters_ = ros_wiring::ReadDenseMapperParameters(getPrivateNodeHandle());
  } catch (const std::exception& error) {
    NODELET_FATAL_STREAM("bad configuration: " << error.what());
    throw;
  }
  const ros_wiring::DenseMapperParameters& p = parameters_;
  NODELET_INFO_STREAM("options in force:\n" << p.printed);
  if (!p.use_camera_info) {
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
            request.path,
            [](const dense::DenseMappingStage& stage, const std::string& path) {
              return stage.SaveMesh(path).vertices.size();
            },
            &response);
      });
  save_cloud_service_ = node.advertiseService<stereo_fabmap_slam::SavePly::Request,
                                              stereo_fabmap_slam::SavePly::Response>(
      "save_cloud", [this](auto& request, auto& response) {
        return Save(
            request.path,
            [](const dense::DenseMappingStage& stage, const std::string& path) {
              return stage.SaveCloud(path);
            },
            &response);
      });
  keyframe_subscriber_ = node.subscribe<stereo_fabmap_slam::Keyframe>(
      "keyframes", 100,
      [this](const stereo_fabmap_slam::KeyframeConstPtr& keyframe) { inputs_.Push(keyframe); });
  graph_subscriber_ = node.subscribe<stereo_fabmap_slam::MapGraph>(
      "map_graph", 1,
      [this](const stereo_fabmap_slam::MapGraphConstPtr& graph) { inputs_.Push(graph); });
  worker_ = std::thread(&DenseMapperNodelet::Work, this);
  input_ = std::make_unique<ros_input::StereoImageInput>(
      node, getPrivateNodeHandle(), p.queue_size, p.approximate_sync,
      [this](const auto& left, const auto& right) {
        inputs_.Push(ros_wiring::ImagePair{left, right, 0});
      },
      [](int) {});
  if (p.use_camera_info) {
    input_->SubscribeCameraInfo(node, p.queue_size, [this](const auto& left, const auto& right) {
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
  std::lock_guard<std::mutex> lock(stage_mutex_);
  if (stage_) return;  // the first calibration defines the rectification, as the tracker's
  const ros_wiring::DenseMapperParameters& p = parameters_;
  stage_.emplace(p.mapping, p.depth, p.fusion, rig.rectifier);
}

void DenseMapperNodelet::Work() {
  // Below the other stages: on a machine of two cores the tracker must not wait for the dense
  // map (Linux gives each thread its own nice value).
  if (setpriority(PRIO_PROCESS, static_cast<id_t>(syscall(SYS_gettid)), 10) != 0)
    NODELET_WARN("could not lower the dense mapping thread's priority");
  const auto period = std::chrono::duration<double>(1.0 / parameters_.rate);
  auto last_published = std::chrono::steady_clock::now();
  bool busy = false;  // the stage has work left: take what came meanwhile and go on at once
  while (const auto inputs = inputs_.TakeAll(busy ? std::chrono::duration<double>(0) : period)) {
    bool changed = false;  // since the view was last sent
    {
      std::lock_guard<std::mutex> lock(stage_mutex_);
      if (!stage_) continue;  // not calibrated yet (camera_info): what came is of no use
      for (const ros_wiring::DenseMapperInput& input : *inputs) {
        const std::string refusal = ros_wiring::PassToStage(input, &*stage_);
        if (!refusal.empty()) NODELET_WARN_STREAM_THROTTLE(2.0, "stereo pair: " << refusal);
      }
      try {
        Report(stage_->Step());
      } catch (const std::exception& error) {  // Open3D out of memory: the map stays as it was
        NODELET_ERROR_STREAM_THROTTLE(10.0, "dense mapping: " << error.what());
      }
      busy = stage_->busy();
      changed = stage_->view_changed();
    }
    if (changed && std::chrono::steady_clock::now() - last_published >= period) {
      Publish();
      last_published = std::chrono::steady_clock::now();
    }
  }
}

void DenseMapperNodelet::Report(const dense::DenseStepReport& report) {
  for (const std::string& left_out : report.left_out)
    NODELET_WARN_STREAM(left_out << ": it stays out of the dense map");
  if (report.moved > 0) {
    NODELET_INFO_STREAM_THROTTLE(5.0,
                                 "keyframes moved by the map are fused again at their new "
                                 "poses ("
                                     << report.still_moving << " still to move)");
  }
  if (const auto& progress = report.progress) {
    NODELET_INFO(
        "%zu keyframes fused (depth + fusion: median %.1f ms over the last %zu), %zu "
        "blocks, %.0f MB",
        progress->keyframes, progress->recent_fuse_median_ms,
        dense::DenseStepReport::Progress::kEvery, progress->blocks, progress->megabytes);
  }
}

void DenseMapperNodelet::Publish() {
  const bool cloud_wanted = cloud_publisher_.getNumSubscribers() > 0;
  const bool mesh_wanted = mesh_publisher_.getNumSubscribers() > 0;
  if (!cloud_wanted && !mesh_wanted) return;  // latched later, when someone listens
  const auto max_triangles = static_cast<std::size_t>(parameters_.max_mesh_triangles);
  std::optional<dense::Cloud> cloud;
  std::optional<dense::Mesh> mesh;
  {
    std::lock_guard<std::mutex> lock(stage_mutex_);
    if (!stage_) return;
    if (cloud_wanted) cloud = stage_->volume().ExtractCloud();
    if (mesh_wanted) mesh = stage_->ViewerMesh(max_triangles);
    stage_->ViewSent();
  }
  const ros::Time stamp = ros::Time::now();
  if (cloud) {
    cloud_publisher_.publish(ros_visualization::DenseCloudMessage(*cloud, parameters_.cloud_cell,
                                                                  parameters_.map_frame, stamp));
  }
  if (mesh) {
    mesh_publisher_.publish(
        ros_visualization::DenseMeshMarker(*mesh, max_triangles, parameters_.map_frame, stamp));
  }
}

void DenseMapperNodelet::SaveMeshAtShutdown() {
  if (parameters_.save_mesh.empty()) return;
  std::lock_guard<std::mutex> lock(stage_mutex_);
  if (!stage_) return;
  try {
    const dense::Mesh mesh = stage_->SaveMesh(parameters_.save_mesh);
    NODELET_INFO_STREAM("wrote " << parameters_.save_mesh << ": " << mesh.vertices.size()
                                 << " vertices of " << stage_->volume().keyframes()
                                 << " keyframes");
  } catch (const std::exception& error) {
    NODELET_ERROR_STREAM("~save_mesh " << parameters_.save_mesh << ": " << error.what());
  }
}

template <typename SaveTo>
bool DenseMapperNodelet::Save(const std::string& path, SaveTo save,
                              stereo_fabmap_slam::SavePly::Response* response) {
  try {
    std::lock_guard<std::mutex> lock(stage_mutex_);
    if (!stage_) throw std::runtime_error("not calibrated yet: no camera_info came");
    response->vertices = static_cast<std::uint32_t>(save(*stage_, path));
    response->success = true;
    response->message =
        "wrote " + path + " (" + std::to_string(stage_->volume().keyframes()) + " keyframes)";
  } catch (const std::exception& error) {
    response->success = false;
    response->message = error.what();
  }
  NODELET_INFO_STREAM("save " << path << ": " << response->message);
  return true;
}

}  // namespace stereo_fabmap_slam

PLUGINLIB_EXPORT_CLASS(stereo_fabmap_slam::DenseMapperNodelet, nodelet::Nodelet)
