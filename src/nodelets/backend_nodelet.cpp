// Backend: keyframes in, windowed bundle adjustment in a worker thread it owns, keyframe_updates
// out. The bundle adjustment itself is backend::LocalBundleAdjuster.
#include <condition_variable>
#include <deque>
#include <memory>
#include <mutex>
#include <sstream>
#include <thread>

#include <nodelet/nodelet.h>
#include <ros/ros.h>
#include <pluginlib/class_list_macros.hpp>

#include "ros_conversions.h"
#include "stereo_fabmap_slam/backend/local_bundle_adjuster.h"
#include "stereo_fabmap_slam/pipeline/pipeline_options.h"

namespace stereo_fabmap_slam {

class BackendNodelet : public nodelet::Nodelet {
 public:
  ~BackendNodelet() override;

 private:
  void onInit() override;
  void OnKeyframe(const stereo_fabmap_slam::KeyframeConstPtr& keyframe);
  void Work();

  static constexpr std::size_t kMaxQueued = 50;

  backend::BundleAdjustmentOptions options_;
  ros::Subscriber keyframe_subscriber_;
  ros::Publisher update_publisher_;

  std::mutex mutex_;
  std::condition_variable wake_;
  std::deque<stereo_fabmap_slam::KeyframeConstPtr> queue_;  // bounded by kMaxQueued
  bool stopping_ = false;
  std::thread worker_;
};

void BackendNodelet::onInit() {
  ros::NodeHandle& private_node = getPrivateNodeHandle();
  try {
    std::string config_file;
    if (private_node.getParam("config_file", config_file) && !config_file.empty()) {
      options_ = pipeline::LoadPipelineOptions(config_file).backend;
    }
    ros_conversions::RosParameterReader reader(private_node, "backend");
    options_.Visit(reader);
    options_.Validate();
  } catch (const std::exception& error) {
    NODELET_FATAL_STREAM("bad configuration: " << error.what());
    throw;
  }
  std::ostringstream printed;
  io::OptionPrinter printer(printed, "backend");
  options_.Visit(printer);
  NODELET_INFO_STREAM("options in force:\n" << printed.str());

  update_publisher_ =
      getNodeHandle().advertise<stereo_fabmap_slam::KeyframeUpdate>("keyframe_updates", 100);
  worker_ = std::thread(&BackendNodelet::Work, this);
  keyframe_subscriber_ =
      getNodeHandle().subscribe("keyframes", 100, &BackendNodelet::OnKeyframe, this);
}

BackendNodelet::~BackendNodelet() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
  if (worker_.joinable()) worker_.join();
}

void BackendNodelet::OnKeyframe(const stereo_fabmap_slam::KeyframeConstPtr& keyframe) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (queue_.size() >= kMaxQueued) {
      // Never block the manager's callback thread: the oldest waiting keyframe gives way.
      NODELET_WARN_THROTTLE(5, "bundle adjustment falls behind: keyframe %lu dropped",
                            static_cast<unsigned long>(queue_.front()->id));
      queue_.pop_front();
    }
    queue_.push_back(keyframe);
  }
  wake_.notify_one();
}

void BackendNodelet::Work() {
  std::unique_ptr<backend::LocalBundleAdjuster> adjuster;
  while (true) {
    stereo_fabmap_slam::KeyframeConstPtr message;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      wake_.wait(lock, [&] { return stopping_ || !queue_.empty(); });
      if (stopping_) return;
      message = queue_.front();
      queue_.pop_front();
    }
    try {
      if (!adjuster) {
        adjuster = std::make_unique<backend::LocalBundleAdjuster>(
            options_, ros_conversions::CameraOfKeyframe(*message));
      }
      stereo_fabmap_slam::KeyframeUpdate update = ros_conversions::ToKeyframeUpdateMessage(
          adjuster->AddKeyframe(ros_conversions::FromKeyframeMessage(*message)));
      update.header = message->header;
      update_publisher_.publish(update);
    } catch (const std::exception& error) {
      NODELET_WARN_THROTTLE(5, "keyframe %lu skipped: %s", static_cast<unsigned long>(message->id),
                            error.what());
    }
  }
}

}  // namespace stereo_fabmap_slam

PLUGINLIB_EXPORT_CLASS(stereo_fabmap_slam::BackendNodelet, nodelet::Nodelet)
