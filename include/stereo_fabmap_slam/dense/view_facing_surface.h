#pragma once

#include <vector>

#include <Eigen/Geometry>

#include "stereo_fabmap_slam/dense/depth_fusion.h"
#include "stereo_fabmap_slam/geometry/stereo_camera.h"

namespace stereo_fabmap_slam::dense {

// Keeps the parts of a fused surface that face a view which saw them, and drops the rest.
//
// Why: marching cubes meshes every sign change of the signed distance, but a surface the
// cameras measured has free space (+) on the cameras' side and the band behind it (-) on the
// far side. Behind a wall, beyond the band (nothing is updated there), a voxel takes only the
// updates of depths measured too far (a mismatch on a repeated texture): free space, +. Where
// that meets the band's -, marching cubes makes a second surface a band's depth (8 cm) behind
// the first, facing away from every camera. A ray caster (KinectFusion's) keeps only the + to
// - crossings along its rays for the same reason; this is that test for the whole mesh.
// Measured on the hall loop (docs/benchmarks.md): 7 % of the vertices go, 16 % of those more
// than 5 cm from the exact surface and 6 % of those within it (not looked into; folds of a noisy
// surface, whose small triangles face away, would do it), and the completeness of the walls
// moves by 0.2 %. Most vertices behind the hall's outer walls stay (18,877 -> 15,770): they
// face the cameras, a surface the fused depths put there, which this test cannot tell from a
// real one.
//
// A triangle (its normal from its winding) or a point (its normal) is kept when some view sees
// its position in the image, in front of the camera within `max_depth`, from the side its
// normal points to.
class ViewFacingSurface {
 public:
  // `views`: the rectified left cameras' poses in the surface's frame (T_world_camera).
  ViewFacingSurface(std::vector<Eigen::Isometry3d> views, const geometry::StereoCamera& camera,
                    double max_depth);

  Mesh Keep(const Mesh& mesh) const;     // the triangles kept, and the vertices they use
  Cloud Keep(const Cloud& cloud) const;  // the points kept (a cloud without normals as it is)

  // Whether a view sees `point` from the side `normal` points to. `hint`: the view to try first
  // (the one that saw the last point, as neighbouring points are seen by the same views), set
  // to the one that sees this one.
  bool Faces(const Eigen::Vector3d& point, const Eigen::Vector3d& normal, std::size_t* hint) const;

 private:
  bool Sees(std::size_t view, const Eigen::Vector3d& point, const Eigen::Vector3d& normal) const;

  std::vector<Eigen::Isometry3d> T_camera_world_;
  std::vector<Eigen::Vector3d> centres_;
  geometry::StereoCamera camera_;
  double max_depth_;
};

}  // namespace stereo_fabmap_slam::dense
