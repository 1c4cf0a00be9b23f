#include "stereo_fabmap_slam/map/map_file.h"

#include <set>

#include "stereo_fabmap_slam/io/binary_file.h"

namespace stereo_fabmap_slam::map {
namespace {

constexpr char kMagic[9] = "SFSMAP01";
constexpr std::uint32_t kVersion = 1;

struct PackedKeypoint {
  float x, y, size, angle, response;
  std::int32_t octave, class_id;
};
struct PackedPose {
  double m[12];  // rows of the 3 x 4 matrix [R | t]
};
struct PackedPoint {
  double x, y, z;
};

PackedPose Pack(const Eigen::Isometry3d& pose) {
  PackedPose packed;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 4; ++c) packed.m[r * 4 + c] = pose.matrix()(r, c);
  }
  return packed;
}

Eigen::Isometry3d Unpack(const PackedPose& packed, io::BinaryReader* reader) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 4; ++c) pose.matrix()(r, c) = packed.m[r * 4 + c];
  }
  const Eigen::Matrix3d rotation = pose.linear();
  if (!pose.matrix().allFinite() ||
      !(rotation.transpose() * rotation).isApprox(Eigen::Matrix3d::Identity(), 1e-6)) {
    reader->Fail("a pose is not a rigid transform");
  }
  return pose;
}

void PutMat(io::BinaryWriter* writer, const cv::Mat& mat) {
  writer->Put<std::int32_t>(mat.type());
  writer->Put<std::int32_t>(mat.rows);
  writer->Put<std::int32_t>(mat.cols);
  const cv::Mat continuous = mat.isContinuous() ? mat : mat.clone();
  writer->PutVector(std::vector<std::uint8_t>(
      continuous.data, continuous.data + continuous.total() * continuous.elemSize()));
}

cv::Mat GetMat(io::BinaryReader* reader) {
  const auto type = reader->Get<std::int32_t>();
  const auto rows = reader->Get<std::int32_t>();
  const auto cols = reader->Get<std::int32_t>();
  const std::vector<std::uint8_t> data = reader->GetVector<std::uint8_t>();
  if (rows == 0 && data.empty()) return cv::Mat();
  if ((type != CV_8U && type != CV_32F) || rows < 0 || cols < 1) {
    reader->Fail("bad descriptor matrix header");
  }
  cv::Mat mat(rows, cols, type);
  if (data.size() != mat.total() * mat.elemSize()) reader->Fail("descriptor data size");
  std::copy(data.begin(), data.end(), mat.data);
  return mat;
}

void PutKeyframe(io::BinaryWriter* writer, const SavedKeyframe& saved) {
  const Keyframe& k = saved.keyframe;
  writer->Put<std::int64_t>(k.id);
  writer->Put<double>(k.timestamp);
  writer->Put<std::uint8_t>(k.starts_new_segment ? 1 : 0);
  writer->Put(Pack(k.T_world_camera));
  writer->Put(Pack(saved.T_map_camera));
  std::vector<PackedKeypoint> keypoints;
  for (const cv::KeyPoint& p : k.features.keypoints) {
    keypoints.push_back({p.pt.x, p.pt.y, p.size, p.angle, p.response, p.octave, p.class_id});
  }
  writer->PutVector(keypoints);
  PutMat(writer, k.features.descriptors);
  writer->PutVector(k.features.u_right);
  std::vector<PackedPoint> points;
  for (const Eigen::Vector3d& p : k.features.points) points.push_back({p.x(), p.y(), p.z()});
  writer->PutVector(points);
  writer->PutVector(k.map_point_ids);
  writer->PutVector(saved.words);
}

SavedKeyframe GetKeyframe(io::BinaryReader* reader) {
  SavedKeyframe saved;
  Keyframe& k = saved.keyframe;
  k.id = reader->Get<std::int64_t>();
  k.timestamp = reader->Get<double>();
  k.starts_new_segment = reader->Get<std::uint8_t>() != 0;
  k.T_world_camera = Unpack(reader->Get<PackedPose>(), reader);
  saved.T_map_camera = Unpack(reader->Get<PackedPose>(), reader);
  for (const PackedKeypoint& p : reader->GetVector<PackedKeypoint>()) {
    k.features.keypoints.emplace_back(cv::Point2f(p.x, p.y), p.size, p.angle, p.response, p.octave,
                                      p.class_id);
  }
  k.features.descriptors = GetMat(reader);
  k.features.u_right = reader->GetVector<float>();
  for (const PackedPoint& p : reader->GetVector<PackedPoint>()) {
    k.features.points.emplace_back(p.x, p.y, p.z);
  }
  k.map_point_ids = reader->GetVector<std::int64_t>();
  saved.words = reader->GetVector<int>();
  const std::size_t n = k.features.keypoints.size();
  if (static_cast<std::size_t>(k.features.descriptors.rows) != n ||
      k.features.u_right.size() != n || k.features.points.size() != n ||
      k.map_point_ids.size() != n) {
    reader->Fail("keyframe " + std::to_string(k.id) + " has features of unequal counts");
  }
  return saved;
}

}  // namespace

void SaveMapFile(const std::string& path, const SavedMap& map) {
  io::BinaryWriter writer;
  writer.Put<std::uint64_t>(map.vocabulary_fingerprint);
  writer.Put<std::int32_t>(map.camera.size.width);
  writer.Put<std::int32_t>(map.camera.size.height);
  for (const double value :
       {map.camera.fx, map.camera.fy, map.camera.cx, map.camera.cy, map.camera.baseline}) {
    writer.Put<double>(value);
  }
  writer.Put<std::uint64_t>(map.keyframes.size());
  for (const SavedKeyframe& keyframe : map.keyframes) PutKeyframe(&writer, keyframe);
  writer.Put<std::uint64_t>(map.edges.size());
  for (const SavedEdge& saved : map.edges) {
    writer.Put<std::int64_t>(saved.edge.query_id);
    writer.Put<std::int64_t>(saved.edge.match_id);
    writer.Put(Pack(saved.edge.T_match_query));
    for (int k = 0; k < 36; ++k) writer.Put<double>(saved.edge.information.data()[k]);
    writer.Put<std::int32_t>(saved.edge.inliers);
    writer.Put<double>(saved.edge.probability);
    writer.Put<std::uint8_t>(saved.relocalization ? 1 : 0);
  }
  io::WriteBinaryFile(path, kMagic, kVersion, writer.bytes());
}

SavedMap LoadMapFile(const std::string& path) {
  io::BinaryReader reader = io::ReadBinaryFile(path, kMagic, kVersion);
  SavedMap map;
  map.vocabulary_fingerprint = reader.Get<std::uint64_t>();
  map.camera.size.width = reader.Get<std::int32_t>();
  map.camera.size.height = reader.Get<std::int32_t>();
  map.camera.fx = reader.Get<double>();
  map.camera.fy = reader.Get<double>();
  map.camera.cx = reader.Get<double>();
  map.camera.cy = reader.Get<double>();
  map.camera.baseline = reader.Get<double>();
  const auto keyframes = reader.Get<std::uint64_t>();
  std::set<std::int64_t> ids;
  for (std::uint64_t i = 0; i < keyframes; ++i) {
    map.keyframes.push_back(GetKeyframe(&reader));
    const std::int64_t id = map.keyframes.back().keyframe.id;
    if (!ids.empty() && id <= *ids.rbegin()) reader.Fail("keyframe ids out of order");
    ids.insert(id);
  }
  const auto edges = reader.Get<std::uint64_t>();
  for (std::uint64_t i = 0; i < edges; ++i) {
    SavedEdge saved;
    saved.edge.query_id = reader.Get<std::int64_t>();
    saved.edge.match_id = reader.Get<std::int64_t>();
    saved.edge.T_match_query = Unpack(reader.Get<PackedPose>(), &reader);
    for (int k = 0; k < 36; ++k) saved.edge.information.data()[k] = reader.Get<double>();
    saved.edge.inliers = reader.Get<std::int32_t>();
    saved.edge.probability = reader.Get<double>();
    saved.relocalization = reader.Get<std::uint8_t>() != 0;
    if (ids.count(saved.edge.query_id) == 0 || ids.count(saved.edge.match_id) == 0) {
      reader.Fail("an edge joins an unknown keyframe");
    }
    map.edges.push_back(saved);
  }
  reader.ExpectEnd();
  return map;
}

}  // namespace stereo_fabmap_slam::map
