#include "dense_wiring.h"

#include <cstdint>
#include <map>
#include <optional>

#include "ros_conversions.h"

namespace stereo_fabmap_slam::ros_wiring {

std::string PassToStage(const DenseMapperInput& input, dense::DenseMappingStage* stage) {
  if (const auto* pair = std::get_if<ImagePair>(&input)) {
    std::string refusal;
    const std::optional<pipeline::StereoPair> images = StereoPairOf(*pair, &refusal);
    if (!images) return refusal;
    stage->AddPair(
        dense::DenseStereoPair{static_cast<std::int64_t>(pair->left->header.stamp.toNSec()),
                               images->left.clone(), images->right.clone()});
    return "";
  }
  if (const auto* keyframe = std::get_if<stereo_fabmap_slam::KeyframeConstPtr>(&input)) {
    stage->AddKeyframe(dense::DenseKeyframe{
        (*keyframe)->id, static_cast<std::int64_t>((*keyframe)->header.stamp.toNSec()),
        ros_conversions::FromPoseMessage((*keyframe)->pose)});
    return "";
  }
  const stereo_fabmap_slam::MapGraph& graph =
      *std::get<stereo_fabmap_slam::MapGraphConstPtr>(input);
  std::map<std::uint64_t, Eigen::Isometry3d> poses;
  for (std::size_t i = 0; i < graph.keyframe_ids.size() && i < graph.keyframe_poses.size(); ++i)
    poses[graph.keyframe_ids[i]] = ros_conversions::FromPoseMessage(graph.keyframe_poses[i]);
  stage->SetMap(ros_conversions::FromTransformMessage(graph.map_to_odom), std::move(poses));
  return "";
}

}  // namespace stereo_fabmap_slam::ros_wiring
