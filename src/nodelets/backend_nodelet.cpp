// Backend: keyframes in, windowed bundle adjustment in a worker thread it owns, keyframe_updates
// out. The bundle adjustment itself is backend::LocalBundleAdjuster.
#include <condition_variable>
#include <deque>
#include <memory>
#include <mutex>
#include <thread>

#include <nodelet/nodelet.h>
#include <ros/ros.h>
#include <pluginlib/class_list_macros.hpp>

#include "parameter_reader.h"
#include "ros_conversions.h"
#include "stereo_fabmap_slam/backend/local_bundle_adjuster.h"

namespace stereo_fabmap_slam {

class BackendNodelet : public nodelet::Nodelet {
 public:
  ~BackendNodelet() override;

 private:
  void onInit() override;
  void OnKeyframe(const stereo_fabmap_slam::KeyframeConstPtr& keyframe);
  void Work();

  backend::BundleAdjustmentOptions options_;
  ros::Subscriber keyframe_subscriber_;
  ros::Publisher update_publisher_;

  std::mutex mutex_;
  std::condition_variable wake_;
  // Keyframes not yet adjusted. Never bounded by dropping: a keyframe missing from the map
  // would leave a hole in the graph. Under load the worker adjusts the newest of them together
  // and skips the optimisations in between (see Work()).
  std::deque<stereo_fabmap_slam::KeyframeConstPtr> queue_;
  bool stopping_ = false;
  std::thread worker_;
};

void BackendNodelet::onInit() {
  ros::NodeHandle& private_node = getPrivateNodeHandle();
  try {
    options_ = ros_parameters::ReadModuleOptions(private_node, options_);
  } catch (const std::exception& error) {
    NODELET_FATAL_STREAM("bad configuration: " << error.what());
    throw;
  }
  NODELET_INFO_STREAM("options in force:\n" << ros_parameters::PrintedOptions(options_));

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
    queue_.push_back(keyframe);
  }
  wake_.notify_one();
}

void BackendNodelet::Work() {
  std::unique_ptr<backend::LocalBundleAdjuster> adjuster;
  while (true) {
    std::deque<stereo_fabmap_slam::KeyframeConstPtr> waiting;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      wake_.wait(lock, [&] { return stopping_ || !queue_.empty(); });
      if (stopping_) return;
      waiting.swap(queue_);
    }
    if (waiting.size() > 1) {
      NODELET_WARN_THROTTLE(5,
                            "bundle adjustment falls behind: %zu keyframes added in one "
                            "optimisation",
                            waiting.size());
    }
    // Every keyframe enters the map; only the newest is followed by an optimisation, whose
    // window covers the others.
    while (!waiting.empty()) {
      const stereo_fabmap_slam::KeyframeConstPtr message = waiting.front();
      waiting.pop_front();
      const bool optimise = waiting.empty();
      try {
        if (!adjuster) {
          adjuster = std::make_unique<backend::LocalBundleAdjuster>(
              options_, ros_conversions::CameraOfKeyframe(*message));
        }
        const map::KeyframeUpdate update =
            adjuster->AddKeyframe(ros_conversions::FromKeyframeMessage(*message), optimise);
        if (!optimise) continue;
        stereo_fabmap_slam::KeyframeUpdate update_message =
            ros_conversions::ToKeyframeUpdateMessage(update);
        update_message.header = message->header;
        update_publisher_.publish(update_message);
      } catch (const std::exception& error) {
        NODELET_WARN_THROTTLE(5, "keyframe %lu skipped: %s",
                              static_cast<unsigned long>(message->id), error.what());
      }
    }
  }
}

}  // namespace stereo_fabmap_slam

PLUGINLIB_EXPORT_CLASS(stereo_fabmap_slam::BackendNodelet, nodelet::Nodelet)
