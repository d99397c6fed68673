#include "geometry/surface_projection.h"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Simple_cartesian.h>
#include <tbb/parallel_for.h>

#include <stdexcept>

namespace tolver {
namespace {

using Kernel = CGAL::Simple_cartesian<double>;
using Point = Kernel::Point_3;
using Triangle = Kernel::Triangle_3;
using Iterator = std::vector<Triangle>::const_iterator;
using Primitive = CGAL::AABB_triangle_primitive<Kernel, Iterator>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, Primitive>>;

Point cgal(const Eigen::Vector3d& v) { return Point(v.x(), v.y(), v.z()); }

}  // namespace

std::vector<SurfaceFoot> projectOntoMesh(const TriangleMesh& mesh,
                                         const std::vector<Eigen::Vector3d>& points_w) {
  if (mesh.faces.empty()) throw std::invalid_argument("projectOntoMesh: the mesh has no faces");
  std::vector<Triangle> tris;
  tris.reserve(mesh.faces.size());
  for (const Eigen::Vector3i& f : mesh.faces)
    tris.emplace_back(cgal(mesh.vertices[f[0]]), cgal(mesh.vertices[f[1]]),
                      cgal(mesh.vertices[f[2]]));
  Tree tree(tris.cbegin(), tris.cend());
  tree.accelerate_distance_queries();
  std::vector<SurfaceFoot> out(points_w.size());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, points_w.size(), 256),
                    [&](const tbb::blocked_range<size_t>& range) {
                      for (size_t i = range.begin(); i != range.end(); ++i) {
                        const auto hit = tree.closest_point_and_primitive(cgal(points_w[i]));
                        SurfaceFoot& s = out[i];
                        s.foot_w = Eigen::Vector3d(hit.first.x(), hit.first.y(), hit.first.z());
                        s.face = static_cast<int>(hit.second - tris.cbegin());
                        s.n_w = mesh.faceNormal(s.face);
                        const Eigen::Vector3d d = points_w[i] - s.foot_w;
                        s.distance = d.norm();
                        s.off_face = (d - d.dot(s.n_w) * s.n_w).norm() > 0.01 * s.distance &&
                                     s.distance > 1e-9;
                      }
                    });
  return out;
}

}  // namespace tolver
