#pragma once
// Measured points onto the nominal surface: each point's closest point on a triangle mesh (CGAL's
// AABB tree, kept inside surface_projection.cpp), the face it lies on and that face's outward
// normal. A CMM point p_w measured on the machined part then deviates from the nominal by
// (p_w - foot_w) . n_w, the signed normal deviation inspection software reports (positive:
// material left outside the nominal surface).
#include <Eigen/Core>
#include <vector>

#include "geometry/triangle_mesh.h"

namespace tolver {

struct SurfaceFoot {
  Eigen::Vector3d foot_w = Eigen::Vector3d::Zero();  // the closest point of the mesh, mm
  Eigen::Vector3d n_w = Eigen::Vector3d::UnitZ();    // the outward unit normal of its face
  int face = -1;
  double distance = 0.0;  // |p - foot|, mm
  // The foot on a face's edge or corner with the point off the face's normal line by more than
  // 1 % of the distance (the point lies beyond a sharp edge): its normal deviation is ambiguous.
  bool off_face = false;
};

// mesh must have at least one face. Parallel over the points.
std::vector<SurfaceFoot> projectOntoMesh(const TriangleMesh& mesh,
                                         const std::vector<Eigen::Vector3d>& points_w);

}  // namespace tolver
