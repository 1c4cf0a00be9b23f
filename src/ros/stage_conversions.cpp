#include "stage_conversions.h"

#include <stdexcept>

#include "ros_conversions.h"

namespace stereo_fabmap_slam::ros_conversions {
namespace {

std::uint8_t StateCode(odometry::TrackingState state) {
  switch (state) {
    case odometry::TrackingState::kOk:
      return stereo_fabmap_slam::TrackedFrame::OK;
    case odometry::TrackingState::kWeak:
      return stereo_fabmap_slam::TrackedFrame::WEAK;
    case odometry::TrackingState::kLost:
      break;
  }
  return stereo_fabmap_slam::TrackedFrame::LOST;
}

odometry::TrackingState StateOfCode(std::uint8_t code) {
  if (code == stereo_fabmap_slam::TrackedFrame::OK) return odometry::TrackingState::kOk;
  if (code == stereo_fabmap_slam::TrackedFrame::WEAK) return odometry::TrackingState::kWeak;
  return odometry::TrackingState::kLost;
}

relocalization::RelocalizationStatus StatusOfName(const std::string& name) {
  using relocalization::RelocalizationStatus;
  for (const RelocalizationStatus status :
       {RelocalizationStatus::kSuccess, RelocalizationStatus::kEmptyMap,
        RelocalizationStatus::kNoCandidate, RelocalizationStatus::kTooFewMatches,
        RelocalizationStatus::kRansacFailed, RelocalizationStatus::kVerificationFailed}) {
    if (name == relocalization::RelocalizationStatusName(status)) return status;
  }
  return RelocalizationStatus::kNoCandidate;
}

std::uint8_t EdgeTypeCode(backend::PoseGraphEdgeType type) {
  switch (type) {
    case backend::PoseGraphEdgeType::kLoop:
      return stereo_fabmap_slam::MapGraphEdge::LOOP;
    case backend::PoseGraphEdgeType::kRelocalization:
      return stereo_fabmap_slam::MapGraphEdge::RELOCALIZATION;
    case backend::PoseGraphEdgeType::kOdometry:
      break;
  }
  return stereo_fabmap_slam::MapGraphEdge::ODOMETRY;
}

backend::PoseGraphEdgeType EdgeTypeOfCode(std::uint8_t code) {
  if (code == stereo_fabmap_slam::MapGraphEdge::LOOP) return backend::PoseGraphEdgeType::kLoop;
  if (code == stereo_fabmap_slam::MapGraphEdge::RELOCALIZATION) {
    return backend::PoseGraphEdgeType::kRelocalization;
  }
  return backend::PoseGraphEdgeType::kOdometry;
}

}  // namespace

stereo_fabmap_slam::KeyframeUpdate ToMappedKeyframeMessage(const pipeline::MappedKeyframe& mapped) {
  stereo_fabmap_slam::KeyframeUpdate message = ToKeyframeUpdateMessage(mapped.update);
  message.header.stamp.fromSec(mapped.timestamp);
  message.keyframe_id = static_cast<std::uint64_t>(mapped.keyframe_id);
  message.in_map_graph = mapped.in_map_graph;
  message.starts_new_segment = mapped.starts_new_segment;
  return message;
}

pipeline::MappedKeyframe FromMappedKeyframeMessage(
    const stereo_fabmap_slam::KeyframeUpdate& message) {
  pipeline::MappedKeyframe mapped;
  mapped.update = FromKeyframeUpdateMessage(message);
  mapped.keyframe_id = static_cast<std::int64_t>(message.keyframe_id);
  mapped.timestamp = ToSeconds(message.header.stamp);
  mapped.in_map_graph = message.in_map_graph;
  mapped.starts_new_segment = message.starts_new_segment;
  return mapped;
}

stereo_fabmap_slam::MapGraph ToMapGraphMessage(const pipeline::MappingStage& mapping) {
  stereo_fabmap_slam::MapGraph message;
  const backend::PoseGraph& graph = mapping.pose_graph();
  for (const auto& [id, pose] : graph.MapPoses()) {
    message.keyframe_ids.push_back(static_cast<std::uint64_t>(id));
    message.keyframe_poses.push_back(ToPoseMessage(pose));
    message.keyframe_in_map.push_back(graph.InMap(id));
  }
  for (const backend::PoseGraphEdge& edge : graph.Edges()) {
    stereo_fabmap_slam::MapGraphEdge edge_message;
    edge_message.from_id = static_cast<std::uint64_t>(edge.from);
    edge_message.to_id = static_cast<std::uint64_t>(edge.to);
    edge_message.type = EdgeTypeCode(edge.type);
    edge_message.T_from_to = ToPoseMessage(edge.T_from_to);
    for (int r = 0; r < 6; ++r) {
      for (int c = 0; c < 6; ++c) edge_message.information[r * 6 + c] = edge.information(r, c);
    }
    message.edges.push_back(edge_message);
  }
  message.map_to_odom = ToTransformMessage(mapping.MapToOdom());
  message.last_closed_keyframe_id = mapping.last_closed_keyframe();
  message.relocalization_edges_received = mapping.relocalization_edges_received();
  return message;
}

pipeline::MapSnapshot FromMapGraphMessage(const stereo_fabmap_slam::MapGraph& message) {
  const std::size_t n = message.keyframe_ids.size();
  if (message.keyframe_poses.size() != n || message.keyframe_in_map.size() != n) {
    throw std::invalid_argument("MapGraph message: arrays of different lengths");
  }
  pipeline::MapSnapshot snapshot;
  for (std::size_t i = 0; i < n; ++i) {
    snapshot.keyframes[static_cast<std::int64_t>(message.keyframe_ids[i])] = {
        FromPoseMessage(message.keyframe_poses[i]), static_cast<bool>(message.keyframe_in_map[i])};
  }
  for (const stereo_fabmap_slam::MapGraphEdge& edge_message : message.edges) {
    backend::PoseGraphEdge edge;
    edge.type = EdgeTypeOfCode(edge_message.type);
    if (edge.type == backend::PoseGraphEdgeType::kOdometry) continue;
    edge.from = static_cast<std::int64_t>(edge_message.from_id);
    edge.to = static_cast<std::int64_t>(edge_message.to_id);
    edge.T_from_to = FromPoseMessage(edge_message.T_from_to);
    for (int r = 0; r < 6; ++r) {
      for (int c = 0; c < 6; ++c) edge.information(r, c) = edge_message.information[r * 6 + c];
    }
    snapshot.loop_edges.push_back(edge);
  }
  snapshot.T_map_odom = FromTransformMessage(message.map_to_odom);
  return snapshot;
}

stereo_fabmap_slam::MapLoaded ToMapLoadedMessage(const std::string& path,
                                                 const pipeline::LoadedMap& loaded) {
  stereo_fabmap_slam::MapLoaded message;
  message.header.stamp = ros::Time::now();
  message.path = path;
  message.keyframes = loaded.keyframes;
  message.next_keyframe_id = static_cast<std::uint64_t>(loaded.next_keyframe_id);
  message.next_point_id = static_cast<std::uint64_t>(loaded.next_point_id);
  return message;
}

stereo_fabmap_slam::PlaceResult ToPlaceResultMessage(const pipeline::PlaceResult& result) {
  stereo_fabmap_slam::PlaceResult message;
  message.header.stamp.fromSec(result.timestamp);
  message.keyframe_id = static_cast<std::uint64_t>(result.keyframe_id);
  const place_recognition::LoopDetection& detection = result.detection;
  message.new_place_probability = detection.new_place_probability;
  message.places_compared = detection.places_compared;
  for (const place_recognition::LoopCandidate& candidate : detection.candidates) {
    message.candidate_ids.push_back(static_cast<std::uint64_t>(candidate.keyframe_id));
    message.candidate_probabilities.push_back(candidate.probability);
    message.candidate_inliers.push_back(candidate.inliers);
    message.candidate_verified.push_back(candidate.verified);
    message.candidate_accepted.push_back(candidate.accepted);
    message.candidate_reasons.push_back(candidate.reason);
  }
  message.loop_found = detection.loop.has_value();
  if (detection.loop) message.loop = ToLoopEdgeMessage(*detection.loop);
  message.detection_ms = result.detection_ms;
  return message;
}

pipeline::PlaceResult FromPlaceResultMessage(const stereo_fabmap_slam::PlaceResult& message) {
  const std::size_t n = message.candidate_ids.size();
  if (message.candidate_probabilities.size() != n || message.candidate_inliers.size() != n ||
      message.candidate_verified.size() != n || message.candidate_accepted.size() != n ||
      message.candidate_reasons.size() != n) {
    throw std::invalid_argument("PlaceResult message: arrays of different lengths");
  }
  pipeline::PlaceResult result;
  result.keyframe_id = static_cast<std::int64_t>(message.keyframe_id);
  result.timestamp = ToSeconds(message.header.stamp);
  place_recognition::LoopDetection& detection = result.detection;
  detection.query_id = result.keyframe_id;
  detection.new_place_probability = message.new_place_probability;
  detection.places_compared = message.places_compared;
  for (std::size_t i = 0; i < n; ++i) {
    place_recognition::LoopCandidate candidate;
    candidate.keyframe_id = static_cast<std::int64_t>(message.candidate_ids[i]);
    candidate.probability = message.candidate_probabilities[i];
    candidate.inliers = message.candidate_inliers[i];
    candidate.verified = message.candidate_verified[i];
    candidate.accepted = message.candidate_accepted[i];
    candidate.reason = message.candidate_reasons[i];
    detection.candidates.push_back(candidate);
  }
  if (message.loop_found) detection.loop = FromLoopEdgeMessage(message.loop);
  result.detection_ms = message.detection_ms;
  return result;
}

stereo_fabmap_slam::TrackedFrame ToTrackedFrameMessage(const pipeline::FrameRecord& frame,
                                                       const pipeline::InputCounts& counts,
                                                       const std::string& frame_id) {
  stereo_fabmap_slam::TrackedFrame message = RefusedFrameMessage(frame.timestamp, counts, frame_id);
  message.tracked = true;
  message.state = StateCode(frame.state);
  message.pose = ToPoseMessage(frame.T_world_camera);
  message.reference_keyframe_id = frame.reference_keyframe;
  message.T_keyframe_camera = ToPoseMessage(frame.T_keyframe_camera);
  message.is_keyframe = frame.is_keyframe;
  message.inliers = frame.inliers;
  message.note = frame.note;
  message.on_map = frame.on_map;
  message.relocalization = frame.relocalization.value_or("");
  message.relocalized = frame.relocalized;
  message.has_map_pose = frame.T_map_camera.has_value();
  if (frame.T_map_camera) message.map_pose = ToPoseMessage(*frame.T_map_camera);
  const pipeline::FrameTiming& t = frame.timing;
  message.rectification_ms = t.rectification_ms;
  message.detection_ms = t.detection_ms;
  message.description_ms = t.description_ms;
  message.stereo_ms = t.stereo_ms;
  message.tracking_ms = t.tracking_ms;
  message.place_description_ms = t.place_description_ms;
  message.relocalization_ms = t.relocalization_ms;
  return message;
}

stereo_fabmap_slam::TrackedFrame RefusedFrameMessage(double timestamp,
                                                     const pipeline::InputCounts& counts,
                                                     const std::string& frame_id) {
  stereo_fabmap_slam::TrackedFrame message;
  message.header.stamp.fromSec(timestamp);
  message.header.frame_id = frame_id;
  message.reference_keyframe_id = -1;
  message.pose = ToPoseMessage(Eigen::Isometry3d::Identity());
  message.T_keyframe_camera = message.pose;
  message.map_pose = message.pose;
  message.pairs_received = counts.received;
  message.pairs_refused = counts.refused;
  message.pairs_skipped = counts.skipped;
  return message;
}

pipeline::FrameRecord FromTrackedFrameMessage(const stereo_fabmap_slam::TrackedFrame& message) {
  pipeline::FrameRecord frame;
  frame.timestamp = ToSeconds(message.header.stamp);
  frame.state = StateOfCode(message.state);
  frame.T_world_camera = FromPoseMessage(message.pose);
  frame.reference_keyframe = message.reference_keyframe_id;
  frame.T_keyframe_camera = FromPoseMessage(message.T_keyframe_camera);
  frame.is_keyframe = message.is_keyframe;
  frame.inliers = message.inliers;
  frame.note = message.note;
  frame.on_map = message.on_map;
  if (!message.relocalization.empty()) frame.relocalization = message.relocalization;
  frame.relocalized = message.relocalized;
  if (message.has_map_pose) frame.T_map_camera = FromPoseMessage(message.map_pose);
  pipeline::FrameTiming& t = frame.timing;
  t.rectification_ms = message.rectification_ms;
  t.detection_ms = message.detection_ms;
  t.description_ms = message.description_ms;
  t.stereo_ms = message.stereo_ms;
  t.tracking_ms = message.tracking_ms;
  t.place_description_ms = message.place_description_ms;
  t.relocalization_ms = message.relocalization_ms;
  return frame;
}

stereo_fabmap_slam::RelocalizeFrame::Request ToRelocalizeFrameRequest(
    const pipeline::RelocalizationRequest& request, const geometry::StereoCamera& camera,
    const std::string& frame_id) {
  map::Keyframe frame;
  frame.timestamp = request.timestamp;
  frame.T_world_camera = request.T_odom_camera;
  frame.features = request.features;
  frame.map_point_ids.assign(frame.features.size(), -1);
  frame.place_descriptors = request.place_descriptors;
  stereo_fabmap_slam::RelocalizeFrame::Request message;
  message.frame = ToKeyframeMessage(frame, camera, frame_id);
  message.mode = request.scope == pipeline::RelocalizationRequest::Scope::kMap
                     ? stereo_fabmap_slam::RelocalizeFrame::Request::RECOVER
                     : stereo_fabmap_slam::RelocalizeFrame::Request::ANYWHERE;
  message.reference_keyframe_id = request.reference_keyframe;
  message.T_reference_camera = ToPoseMessage(request.T_reference_camera);
  message.add_edge = request.add_edge;
  message.has_expected_pose = request.expected_T_map_camera.has_value();
  if (request.expected_T_map_camera)
    message.expected_T_map_camera = ToPoseMessage(*request.expected_T_map_camera);
  message.from_user = request.from_user;
  message.describe_ms = request.describe_ms;
  return message;
}

pipeline::RelocalizationRequest FromRelocalizeFrameRequest(
    const stereo_fabmap_slam::RelocalizeFrame::Request& message) {
  map::Keyframe frame = FromKeyframeMessage(message.frame);
  pipeline::RelocalizationRequest request;
  request.timestamp = frame.timestamp;
  request.features = std::move(frame.features);
  request.place_descriptors = frame.place_descriptors;
  request.scope = message.mode == stereo_fabmap_slam::RelocalizeFrame::Request::RECOVER
                      ? pipeline::RelocalizationRequest::Scope::kMap
                      : pipeline::RelocalizationRequest::Scope::kAnywhere;
  request.reference_keyframe = message.reference_keyframe_id;
  request.T_reference_camera = FromPoseMessage(message.T_reference_camera);
  request.T_odom_camera = frame.T_world_camera;
  request.add_edge = message.add_edge;
  if (message.has_expected_pose)
    request.expected_T_map_camera = FromPoseMessage(message.expected_T_map_camera);
  request.from_user = message.from_user;
  request.describe_ms = message.describe_ms;
  return request;
}

stereo_fabmap_slam::RelocalizeFrame::Response ToRelocalizeFrameResponse(
    const pipeline::RelocalizationAnswer& answer) {
  stereo_fabmap_slam::RelocalizeFrame::Response message;
  const relocalization::Relocalization& found = answer.result;
  message.success = found.success();
  message.already_joined = answer.already_joined;
  message.status = relocalization::RelocalizationStatusName(found.status);
  message.message = found.reason;
  message.keyframe_id = found.keyframe_id;
  message.T_keyframe_camera = ToPoseMessage(found.T_keyframe_camera);
  message.map_pose_known = answer.map_pose_known;
  message.T_map_camera = ToPoseMessage(answer.T_map_camera);
  message.matches = found.matches;
  message.inliers = found.inliers;
  message.inlier_cells = found.inlier_cells;
  message.candidates = found.candidates;
  message.probability = found.probability;
  message.time_ms = answer.ms;
  message.has_agreement = answer.agrees.has_value();
  message.agrees = answer.agrees.value_or(false);
  message.edge_added = answer.edge.has_value();
  if (answer.edge) {
    message.edge = ToLoopEdgeMessage(*answer.edge);
    message.edge.relocalization = true;
  }
  return message;
}

pipeline::RelocalizationAnswer FromRelocalizeFrameResponse(
    const stereo_fabmap_slam::RelocalizeFrame::Response& message) {
  pipeline::RelocalizationAnswer answer;
  relocalization::Relocalization& found = answer.result;
  found.status = StatusOfName(message.status);
  found.reason = message.message;
  found.keyframe_id = message.keyframe_id;
  found.T_keyframe_camera = FromPoseMessage(message.T_keyframe_camera);
  found.matches = message.matches;
  found.inliers = message.inliers;
  found.inlier_cells = message.inlier_cells;
  found.candidates = message.candidates;
  found.probability = message.probability;
  answer.already_joined = message.already_joined;
  answer.map_pose_known = message.map_pose_known;
  answer.T_map_camera = FromPoseMessage(message.T_map_camera);
  answer.ms = message.time_ms;
  if (message.has_agreement) answer.agrees = message.agrees;
  if (message.edge_added) answer.edge = FromLoopEdgeMessage(message.edge);
  return answer;
}

}  // namespace stereo_fabmap_slam::ros_conversions
