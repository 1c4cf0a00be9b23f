#include "stereo_fabmap_slam/dense/mesh_simplification.h"

#include <utility>

#include "open3d_conversions.h"

namespace stereo_fabmap_slam::dense {

Mesh SimplifiedMesh(const Mesh& mesh, double cell) {
  if (mesh.triangles.empty()) return mesh;
  return FromOpen3d(std::move(*ToOpen3d(mesh).SimplifyVertexClustering(cell)));
}

}  // namespace stereo_fabmap_slam::dense
