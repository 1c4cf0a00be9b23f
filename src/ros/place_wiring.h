#pragma once

// The LoopDetector nodelet's plumbing, apart from the nodelet so that it stays wiring only and
// this is unit-tested: its parameters, the pairing of each keyframe with the Backend's answer to
// it (two topics, either may come first), and the services' answers.

#include <condition_variable>
#include <cstdint>
#include <deque>
#include <map>
#include <mutex>
#include <optional>
#include <string>

#include <ros/node_handle.h>
#include <stereo_fabmap_slam/DetectLoop.h>
#include <stereo_fabmap_slam/Keyframe.h>
#include <stereo_fabmap_slam/KeyframeUpdate.h>
#include <stereo_fabmap_slam/MapFile.h>

#include "stereo_fabmap_slam/features/feature_factory.h"
#include "stereo_fabmap_slam/map/map_file.h"
#include "stereo_fabmap_slam/pipeline/map_state.h"
#include "stereo_fabmap_slam/pipeline/place_service.h"
#include "stereo_fabmap_slam/pipeline/place_stage.h"
#include "stereo_fabmap_slam/place_recognition/loop_detector.h"
#include "stereo_fabmap_slam/place_recognition/place_recognition_options.h"
#include "stereo_fabmap_slam/relocalization/relocalization_options.h"

namespace stereo_fabmap_slam::ros_wiring {

struct PlaceParameters {
  features::DescriptorKind descriptor;  // the odometry's (the keyframes' features)
  place_recognition::PlaceRecognitionOptions place;
  place_recognition::LoopDetectorOptions detection;
  relocalization::RelocalizerOptions relocalizer;
  std::string map_file;          // "" or a map to load at start
  std::string save_map_at_exit;  // "" or where to save the map when the node shuts down
  std::string mode = "mapping";  // as given; checked at start
  std::string printed;           // the options in force, for the start-up log
};
// Every ~parameter of the LoopDetector, and its vocabulary loaded once, so that a missing or
// damaged file stops start-up; throws std::exception naming what is wrong.
PlaceParameters ReadPlaceParameters(const ros::NodeHandle& private_node);

// Pairs each keyframe (from the tracker) with the Backend's answer to it (keyframe_updates, one
// per keyframe, in order), which may arrive first: the place stage takes a keyframe only with
// the bundle adjustment's answer. A keyframe the Backend never answers (it was not running) is
// dropped once a later answer comes; an answer whose keyframe never came (this nodelet was not
// running) is handed over without it once a later keyframe came.
class KeyframePairing {
 public:
  struct Pair {
    stereo_fabmap_slam::KeyframeConstPtr keyframe;  // null: it never came
    stereo_fabmap_slam::KeyframeUpdateConstPtr update;
  };
  void AddKeyframe(const stereo_fabmap_slam::KeyframeConstPtr& keyframe);
  void AddUpdate(const stereo_fabmap_slam::KeyframeUpdateConstPtr& update);
  // Waits for the next pair, in the order of the answers; nullopt when stopping.
  std::optional<Pair> Take();
  void Stop();

 private:
  std::optional<Pair> Ready();  // call with mutex_

  std::mutex mutex_;
  std::condition_variable changed_;
  std::map<std::uint64_t, stereo_fabmap_slam::KeyframeConstPtr> keyframes_;
  std::deque<stereo_fabmap_slam::KeyframeUpdateConstPtr> updates_;
  std::uint64_t newest_keyframe_ = 0;
  bool any_keyframe_ = false;
  bool stopping_ = false;
};

// The place service whose stage loads the parameters' vocabulary for the map's camera.
pipeline::PlaceService MakePlaceService(const PlaceParameters& parameters);

// The save_map and load_map services' answer.
void FillMapFileResponse(const pipeline::MapFileAnswer& answer,
                         stereo_fabmap_slam::MapFile::Response* response);

// The detect_loop service's answer.
void FillDetectLoopResponse(const place_recognition::LoopDetection& detection,
                            stereo_fabmap_slam::DetectLoop::Response* response);

}  // namespace stereo_fabmap_slam::ros_wiring
