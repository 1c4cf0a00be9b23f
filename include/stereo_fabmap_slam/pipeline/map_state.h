#pragma once

#include <cstdint>
#include <map>
#include <vector>

#include <Eigen/Geometry>

#include "stereo_fabmap_slam/backend/pose_graph.h"

namespace stereo_fabmap_slam::pipeline {

// What the mapping stage knows of the map, as the tracking and place stages ask it. Offline the
// mapping stage answers itself (MappingStage); in the nodelet graph the other stages hold a
// MapSnapshot of its latest map_graph message. Either way the answers come from one place, the
// pose graph: no stage keeps a connectivity of its own.
//
// Words: a *segment* is a run of keyframes joined by odometry (a tracking loss, a reset, a loaded
// map and the end of localization mode start a new one); a *piece* is segments joined by loop
// and relocalization edges: a connected part of the map. *The map* is the piece of the map's
// first keyframe; a new segment is a piece of its own until a relocalization or a loop joins it.
class MapState {
 public:
  virtual ~MapState() = default;

  virtual bool empty() const = 0;  // no keyframe yet
  virtual bool Contains(std::int64_t id) const = 0;
  // Whether the keyframe belongs to the map (the piece of the map's first keyframe); false for
  // a keyframe the map does not hold.
  virtual bool InMap(std::int64_t id) const = 0;
  // T_map_camera; throws std::out_of_range for a keyframe the map does not hold.
  virtual Eigen::Isometry3d MapPose(std::int64_t id) const = 0;
  // Every keyframe's T_map_camera, by id.
  virtual std::map<std::int64_t, Eigen::Isometry3d> MapPoses() const = 0;
  // What tf map -> odom is: the pose graph's correction, or in localization mode the latest
  // relocalization's.
  virtual Eigen::Isometry3d MapToOdom() const = 0;
  // The loop and relocalization edges (odometry edges follow from the keyframes), for saving.
  virtual std::vector<backend::PoseGraphEdge> LoopEdges() const = 0;
};

// A copy of the mapping stage's answers at one moment: what a map_graph message carries.
struct MapSnapshot : MapState {
  struct Keyframe {
    Eigen::Isometry3d T_map_camera = Eigen::Isometry3d::Identity();
    bool in_map = false;
  };
  std::map<std::int64_t, Keyframe> keyframes;
  std::vector<backend::PoseGraphEdge> loop_edges;
  Eigen::Isometry3d T_map_odom = Eigen::Isometry3d::Identity();

  // The answers `map` gives now.
  static MapSnapshot Of(const MapState& map) {
    MapSnapshot snapshot;
    for (const auto& [id, pose] : map.MapPoses()) snapshot.keyframes[id] = {pose, map.InMap(id)};
    snapshot.loop_edges = map.LoopEdges();
    snapshot.T_map_odom = map.MapToOdom();
    return snapshot;
  }

  bool empty() const override { return keyframes.empty(); }
  bool Contains(std::int64_t id) const override { return keyframes.count(id) > 0; }
  bool InMap(std::int64_t id) const override {
    const auto it = keyframes.find(id);
    return it != keyframes.end() && it->second.in_map;
  }
  Eigen::Isometry3d MapPose(std::int64_t id) const override {
    return keyframes.at(id).T_map_camera;
  }
  std::map<std::int64_t, Eigen::Isometry3d> MapPoses() const override {
    std::map<std::int64_t, Eigen::Isometry3d> poses;
    for (const auto& [id, keyframe] : keyframes) poses.emplace(id, keyframe.T_map_camera);
    return poses;
  }
  Eigen::Isometry3d MapToOdom() const override { return T_map_odom; }
  std::vector<backend::PoseGraphEdge> LoopEdges() const override { return loop_edges; }
};

}  // namespace stereo_fabmap_slam::pipeline
