#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "stereo_fabmap_slam/backend/backend_options.h"
#include "stereo_fabmap_slam/camera/stereo_rectifier.h"
#include "stereo_fabmap_slam/pipeline/mapping_stage.h"
#include "stereo_fabmap_slam/pipeline/place_service.h"
#include "stereo_fabmap_slam/pipeline/run_record.h"
#include "stereo_fabmap_slam/pipeline/serial_worker.h"
#include "stereo_fabmap_slam/pipeline/slam_mode.h"
#include "stereo_fabmap_slam/pipeline/stereo_front_end.h"
#include "stereo_fabmap_slam/pipeline/tracking_stage.h"
#include "stereo_fabmap_slam/relocalization/relocalization_options.h"

namespace stereo_fabmap_slam::pipeline {

// A view checked against the map (StereoSlam::Relocalize).
struct RelocalizationOutput {
  relocalization::Relocalization result;
  // The frame's camera in map (the keyframe's map pose times the relocalized relative pose);
  // meaningful on success.
  Eigen::Isometry3d T_map_camera = Eigen::Isometry3d::Identity();
  double ms = 0;             // place words, candidates, verification
  double extraction_ms = 0;  // rectification and stereo features of the pair
};

// The whole SLAM frame by frame, through the three stages the nodelets run apart
// (docs/architecture.md): the tracking stage; on a keyframe the mapping stage (bundle
// adjustment, whose update goes straight back to the tracker, and the pose graph) and, with loop
// closing, the place stage, which makes the keyframe a place; a relocalization the tracking
// stage asks for; then the keyframe's loop detection, whose loop the mapping stage closes. By
// default in one thread, in that order: the same input gives the same output. With concurrent
// mapping (EnableConcurrentMapping) a keyframe's mapping and loop detection run on a second
// thread while tracking goes on, as in the nodelet graph: the tracker follows the bundle
// adjustment's update and sees the map (a MapSnapshot) when they are done, not before its next
// frame, so the output depends on timing. The clock (milliseconds) is only read to fill the
// timings.
class StereoSlam {
 public:
  using Clock = StereoFrontEnd::Clock;

  StereoSlam(const FrontEndOptions& front_end_options,
             const backend::BundleAdjustmentOptions& bundle_adjustment_options,
             const camera::StereoRectifier& rectifier, Clock clock);

  // Turns loop closing and relocalization on (before the first frame). The front end must make
  // place descriptors (FrontEndOptions::place_features). After a tracking loss every n-th frame
  // (relocalizer_options.attempt_every_n_frames) is relocalized against the map until one is
  // found; its relocalization edge joins the new segment to the map.
  void EnableLoopClosing(place_recognition::LoopDetector detector,
                         const backend::PoseGraphOptions& pose_graph_options,
                         const relocalization::RelocalizerOptions& relocalizer_options = {},
                         const backend::GlobalRefinementOptions& refinement_options = {});
  // Runs the mapping and place stages' keyframe work on a thread of its own from now on (before
  // the first frame). At most `queued_keyframes` keyframes wait for it; a tracker further ahead
  // waits. A frame that asks for a relocalization waits until the keyframes before it are
  // mapped, and is processed in order. Until Synchronize(), the accessors of the map, the
  // record and the stages below (and SaveMap, Relocalize) see it as the last finished keyframe
  // left it, or are not safe to call while a keyframe is being mapped: call Synchronize() first.
  void EnableConcurrentMapping(std::size_t queued_keyframes = 4);
  // Waits until every keyframe so far is mapped and passes their results on (the tracker, the
  // record). Nothing to do without concurrent mapping.
  void Synchronize();
  // The map as the last finished keyframe left it (a snapshot with concurrent mapping; the
  // mapping stage itself otherwise): safe to read between frames in either case.
  std::shared_ptr<const MapState> LatestMap() const;

  // The whole map refined by bundle adjustment in the map frame (MappingStage::RefineGlobally),
  // after the keyframes so far are mapped. Loop closing must be on.
  backend::GlobalRefinementSummary RefineMap(const backend::GlobalRefinementOptions& options);

  void SetMode(SlamMode mode);
  SlamMode mode() const { return mapping_.mode(); }
  // The map (keyframes, words, pose graph) to a file, and back, with the answers the ROS
  // services give (PlaceService: whole paths, refusals in words). Loading replaces the map after
  // checking the file, its vocabulary, camera and graph (a refused file leaves the running map as
  // it was). After a load the odometry goes on in a segment of its own until a relocalization
  // finds it in the loaded map. Loop closing must be on.
  MapFileAnswer SaveMap(const std::string& path) const;
  MapFileAnswer LoadMap(const std::string& path);

  // Raw (unrectified) mono8 images of one stereo pair; `frames_skipped` stereo pairs were passed
  // over since the last one processed (a caller that cannot keep up: Tracker::Track). A pair the
  // input monitor refuses is not recorded; the result is then nullopt.
  const FrameRecord* ProcessFrame(double timestamp, const cv::Mat& left_raw,
                                  const cv::Mat& right_raw, int frames_skipped = 0);

  // Relocalizes a stereo pair against the whole map without tracking it or changing anything
  // (the relocalize service's check of a view). Loop closing must be on.
  RelocalizationOutput Relocalize(const cv::Mat& left_raw, const cv::Mat& right_raw) const;

  // What the input monitor said of the last pair (refused, a gap, time going backwards).
  const std::vector<InputEvent>& last_input_events() const { return last_events_; }
  const RunRecord& record() const { return record_; }
  const std::vector<FrameRecord>& frames() const { return record_.frames(); }
  // The map's state (null without loop closing): poses, pieces, edges.
  const MapState* map_state() const { return place_ ? &mapping_ : nullptr; }
  const MappingStage& mapping() const { return mapping_; }
  const PlaceStage* place() const { return place_ ? place_->stage() : nullptr; }
  const TrackingStage& tracking() const { return tracking_; }
  io::Trajectory MapTrajectory() const { return record_.MapTrajectory(map_state()); }
  io::Trajectory OdometryTrajectory() const { return record_.OdometryTrajectory(); }
  io::Trajectory KeyframeTrajectory() const { return record_.KeyframeTrajectory(map_state()); }
  double KeyframeTime(std::int64_t id) const { return record_.KeyframeTime(id); }
  std::size_t keyframe_count() const { return record_.keyframes(); }
  int descriptor_norm() const { return tracking_.front_end().descriptor_norm(); }
  double max_match_distance() const { return tracking_.front_end().max_match_distance(); }

 private:
  // What the mapping and place stages made of one keyframe (concurrent mapping).
  struct MappingResult {
    std::size_t frame_index = 0;  // in record_
    MappedKeyframe mapped;
    std::optional<PlaceResult> place;
    double loop_pose_graph_ms = 0;  // closing the loop place found
  };
  // The mapping stage's and (with loop closing) the place stage's keyframe work before loop
  // detection.
  MappedKeyframe MapKeyframe(const map::Keyframe& keyframe);
  // A keyframe's whole mapping on the worker thread.
  void RunMappingJob(const map::Keyframe& keyframe, std::size_t frame_index);
  // On the caller's thread: the finished keyframes' results to the tracker and the record.
  void TakeMappingResults();
  void PublishSnapshot();  // the worker idle or running the caller

  Clock clock_;
  TrackingStage tracking_;
  MappingStage mapping_;
  backend::BundleAdjustmentOptions bundle_adjustment_options_;
  std::optional<PlaceService> place_;
  RunRecord record_;
  std::uint64_t arrival_ = 0;  // pairs seen, skipped ones included
  std::vector<InputEvent> last_events_;
  // Concurrent mapping: the results the worker finished and the map it left, under the mutex.
  mutable std::mutex results_mutex_;
  std::vector<MappingResult> finished_;
  std::shared_ptr<const MapSnapshot> snapshot_;
  // Last: destroyed first, so that its thread ends before the stages it uses.
  std::unique_ptr<SerialWorker> worker_;
};

}  // namespace stereo_fabmap_slam::pipeline
