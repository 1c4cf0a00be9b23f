#include "dense_wiring.h"

#include <cstdint>
#include <map>
#include <optional>
#include <stdexcept>

#include "parameter_reader.h"
#include "ros_conversions.h"

namespace stereo_fabmap_slam::ros_wiring {

DenseMapperParameters ReadDenseMapperParameters(const ros::NodeHandle& private_node) {
  DenseMapperParameters p;
  p.rectification = ros_parameters::ReadModuleOptions(private_node, p.rectification);
  p.depth = ros_parameters::ReadModuleOptions(private_node, p.depth);
  p.fusion = ros_parameters::ReadModuleOptions(private_node, p.fusion);
  p.mapping = ros_parameters::ReadModuleOptions(private_node, p.mapping);
  p.printed = ros_parameters::PrintedOptions(p.rectification) +
              ros_parameters::PrintedOptions(p.depth) + ros_parameters::PrintedOptions(p.fusion) +
              ros_parameters::PrintedOptions(p.mapping);
  p.use_camera_info = private_node.param("use_camera_info", p.use_camera_info);
  if (!p.use_camera_info && !private_node.getParam("calibration_file", p.calibration_file)) {
    throw std::invalid_argument("set ~calibration_file or ~use_camera_info");
  }
  p.approximate_sync = private_node.param("approximate_sync", p.approximate_sync);
  p.map_frame = private_node.param("map_frame", p.map_frame);
  p.queue_size = private_node.param("queue_size", p.queue_size);
  p.worker.view_rate = private_node.param("rate", p.worker.view_rate);
  p.cloud_cell = private_node.param("cloud_cell", p.cloud_cell);
  p.max_mesh_triangles = private_node.param("max_mesh_triangles", p.max_mesh_triangles);
  p.worker.save_mesh_at_stop = private_node.param("save_mesh", p.worker.save_mesh_at_stop);
  if (p.queue_size < 1 || !(p.worker.view_rate > 0) || !(p.cloud_cell >= 0) ||
      p.max_mesh_triangles < 1) {
    throw std::invalid_argument(
        "~queue_size, ~rate and ~max_mesh_triangles must be > 0, ~cloud_cell >= 0");
  }
  ros_parameters::RejectUnknownParameters(
      private_node,
      {"approximate_sync", "calibration_file", "cloud_cell", "config_file", "image_transport",
       "map_frame", "max_mesh_triangles", "queue_size", "rate", "save_mesh", "use_camera_info"});
  return p;
}

std::optional<dense::DenseInput> DenseInputOf(const ImagePair& pair, std::string* refusal) {
  const std::optional<pipeline::StereoPair> images = StereoPairOf(pair, refusal);
  if (!images) return std::nullopt;
  return dense::DenseStereoPair{static_cast<std::int64_t>(pair.left->header.stamp.toNSec()),
                                images->left.clone(), images->right.clone()};
}

dense::DenseInput DenseInputOf(const stereo_fabmap_slam::Keyframe& keyframe) {
  return dense::DenseKeyframe{keyframe.id,
                              static_cast<std::int64_t>(keyframe.header.stamp.toNSec()),
                              ros_conversions::FromPoseMessage(keyframe.pose)};
}

dense::DenseInput DenseInputOf(const stereo_fabmap_slam::MapGraph& graph) {
  dense::DenseMapUpdate map;
  map.T_map_odom = ros_conversions::FromTransformMessage(graph.map_to_odom);
  for (std::size_t i = 0; i < graph.keyframe_ids.size() && i < graph.keyframe_poses.size(); ++i) {
    map.keyframe_poses[graph.keyframe_ids[i]] =
        ros_conversions::FromPoseMessage(graph.keyframe_poses[i]);
  }
  return map;
}

}  // namespace stereo_fabmap_slam::ros_wiring
