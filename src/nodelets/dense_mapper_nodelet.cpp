// DenseMapper: the dense mapping stage (dense::DenseMappingStage) in the nodelet graph, in a
// nodelet (and library) of its own so that tracking never waits for it and never loads Open3D.
// The stereo pairs (as the StereoTracker gets them), keyframes and map_graph in, pushed in
// arrival order to the dense mapping worker (dense::DenseMappingWorker, with a thread of its own
// below the others' priority: the driver run_dataset --dense runs too); the stage decides what is
// fused when. Here only wiring: dense_cloud (PointCloud2, thinned) and dense_mesh (a marker) sent
// when the worker offers the view (at most at ~rate) and someone listens; save_mesh and
// save_cloud write PLY files; ~save_mesh is written when the nodelet shuts down.
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>

#include <nodelet/nodelet.h>
#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>
#include <stereo_fabmap_slam/SavePly.h>
#include <visualization_msgs/Marker.h>
#include <pluginlib/class_list_macros.hpp>

#include "dense_messages.h"
#include "dense_wiring.h"
#include "stereo_fabmap_slam/dense/dense_mapping_worker.h"
#include "stereo_image_input.h"

namespace stereo_fabmap_slam {
class DenseMapperNodelet : public nodelet::Nodelet {
 public:
  ~DenseMapperNodelet() override {
    input_.reset();  // no image callback runs on after this (StereoImageInput)
    keyframe_subscriber_.shutdown();
    graph_subscriber_.shutdown();
    // Before the members its listeners use go (the publishers, the parameters): the thread is
    // joined, then the mesh saved.
    if (const std::shared_ptr<dense::DenseMappingWorker> worker = Worker()) worker->Stop();
  }

 private:
  void onInit() override;
  void Calibrate(const ros_input::MountedRig& rig);
  std::shared_ptr<dense::DenseMappingWorker> Worker();  // null until calibrated
  void Push(std::optional<dense::DenseInput> input);
  void Report(const dense::DenseStepReport& report);  // the worker's
  bool Publish(const dense::DenseMappingStage& stage);
  // `save` writes `path` from the stage and returns the vertices or points written.
  template <typename SaveTo>
  bool Save(const std::string& path, SaveTo save, stereo_fabmap_slam::SavePly::Response* response);

  ros_wiring::DenseMapperParameters parameters_;

  std::mutex worker_mutex_;  // set once, when the calibration is known
  std::shared_ptr<dense::DenseMappingWorker> worker_;

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
  // Latched: an rviz started later sees the map at once.
  cloud_publisher_ = node.advertise<sensor_msgs::PointCloud2>("dense_cloud", 1, true);
  mesh_publisher_ = node.advertise<visualization_msgs::Marker>("dense_mesh", 1, true);
  if (!p.use_camera_info) {
    try {
      Calibrate(
          ros_input::RigFromCalibrationFile(p.calibration_file, p.rectification, std::nullopt));
    } catch (const std::exception& error) {
      NODELET_FATAL_STREAM("calibration: " << error.what());
      throw;
    }
  }
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
      "keyframes", 100, [this](const stereo_fabmap_slam::KeyframeConstPtr& keyframe) {
        Push(ros_wiring::DenseInputOf(*keyframe));
      });
  graph_subscriber_ = node.subscribe<stereo_fabmap_slam::MapGraph>(
      "map_graph", 1, [this](const stereo_fabmap_slam::MapGraphConstPtr& graph) {
        Push(ros_wiring::DenseInputOf(*graph));
      });
  input_ = std::make_unique<ros_input::StereoImageInput>(
      node, getPrivateNodeHandle(), p.queue_size, p.approximate_sync,
      [this](const auto& left, const auto& right) {
        const std::shared_ptr<dense::DenseMappingWorker> worker = Worker();
        if (!worker) return;  // not calibrated yet (camera_info): of no use, not even copied
        std::string refusal;
        auto pair = ros_wiring::DenseInputOf(ros_wiring::ImagePair{left, right, 0}, &refusal);
        if (pair) worker->Push(std::move(*pair));
        if (!refusal.empty()) NODELET_WARN_STREAM_THROTTLE(2.0, "stereo pair: " << refusal);
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
  std::lock_guard<std::mutex> lock(worker_mutex_);
  if (worker_) return;  // the first calibration defines the rectification, as the tracker's
  const ros_wiring::DenseMapperParameters& p = parameters_;
  dense::DenseWorkerListener listener;
  listener.report = [this](const dense::DenseStepReport& report) { Report(report); };
  listener.view = [this](const dense::DenseMappingStage& stage) { return Publish(stage); };
  listener.failed = [this](const std::string& what) {
    NODELET_ERROR_STREAM_THROTTLE(10.0, "dense mapping: " << what);
  };
  listener.saved = [this](const std::string& message, bool success) {
    if (success) {
      NODELET_INFO_STREAM(message);
    } else {
      NODELET_ERROR_STREAM("~save_mesh " << message);
    }
  };
  worker_ = std::make_shared<dense::DenseMappingWorker>(p.mapping, p.depth, p.fusion, rig.rectifier,
                                                        p.worker, std::move(listener));
}

std::shared_ptr<dense::DenseMappingWorker> DenseMapperNodelet::Worker() {
  std::lock_guard<std::mutex> lock(worker_mutex_);
  return worker_;
}

void DenseMapperNodelet::Push(std::optional<dense::DenseInput> input) {
  const std::shared_ptr<dense::DenseMappingWorker> worker = Worker();
  if (worker && input) worker->Push(std::move(*input));
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

bool DenseMapperNodelet::Publish(const dense::DenseMappingStage& stage) {
  const bool cloud_wanted = cloud_publisher_.getNumSubscribers() > 0;
  const bool mesh_wanted = mesh_publisher_.getNumSubscribers() > 0;
  if (!cloud_wanted && !mesh_wanted) return false;  // latched later, when someone listens
  const auto max_triangles = static_cast<std::size_t>(parameters_.max_mesh_triangles);
  const ros::Time stamp = ros::Time::now();
  if (cloud_wanted) {
    cloud_publisher_.publish(ros_visualization::DenseCloudMessage(
        stage.volume().ExtractCloud(), parameters_.cloud_cell, parameters_.map_frame, stamp));
  }
  if (mesh_wanted) {
    mesh_publisher_.publish(ros_visualization::DenseMeshMarker(
        stage.ViewerMesh(max_triangles), max_triangles, parameters_.map_frame, stamp));
  }
  return true;
}

template <typename SaveTo>
bool DenseMapperNodelet::Save(const std::string& path, SaveTo save,
                              stereo_fabmap_slam::SavePly::Response* response) {
  try {
    const std::shared_ptr<dense::DenseMappingWorker> worker = Worker();
    if (!worker) throw std::runtime_error("not calibrated yet: no camera_info came");
    worker->WithStage([&](const dense::DenseMappingStage& stage) {
      response->vertices = static_cast<std::uint32_t>(save(stage, path));
      response->message =
          "wrote " + path + " (" + std::to_string(stage.volume().keyframes()) + " keyframes)";
    });
    response->success = true;
  } catch (const std::exception& error) {
    response->success = false;
    response->message = error.what();
  }
  NODELET_INFO_STREAM("save " << path << ": " << response->message);
  return true;
}

}  // namespace stereo_fabmap_slam

PLUGINLIB_EXPORT_CLASS(stereo_fabmap_slam::DenseMapperNodelet, nodelet::Nodelet)
