// refineMesh (geometry/triangle_mesh.h) by CGAL's isotropic remeshing: edges split, collapsed
// and flipped, vertices relaxed tangentially and projected back onto the input surface, with the
// sharp edges (dihedral angle above 30 deg) and the borders between regions kept in place.
#include <CGAL/Polygon_mesh_processing/detect_features.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/remesh.h>
#include <CGAL/Simple_cartesian.h>
#include <CGAL/Surface_mesh.h>

#include <vector>

#include "geometry/triangle_mesh.h"

namespace tolver {

void refineMesh(TriangleMesh* mesh, double max_edge) {
  if (!(max_edge > 0) || mesh->faces.empty()) return;
  using Kernel = CGAL::Simple_cartesian<double>;
  using Mesh = CGAL::Surface_mesh<Kernel::Point_3>;
  namespace PMP = CGAL::Polygon_mesh_processing;
  std::vector<Kernel::Point_3> points;
  for (const auto& v : mesh->vertices) points.emplace_back(v.x(), v.y(), v.z());
  std::vector<std::vector<size_t>> polygons;
  for (const auto& t : mesh->faces) polygons.push_back({size_t(t[0]), size_t(t[1]), size_t(t[2])});
  Mesh sm;
  PMP::polygon_soup_to_polygon_mesh(points, polygons, sm);
  if (sm.number_of_faces() != mesh->faces.size()) return;  // not a polygon mesh: keep it as it is
  auto patch = sm.add_property_map<Mesh::Face_index, int>("f:patch", 0).first;
  for (auto f : sm.faces()) patch[f] = mesh->face_group[f.idx()];
  auto constrained = sm.add_property_map<Mesh::Edge_index, bool>("e:constrained", false).first;
  PMP::detect_sharp_edges(sm, 30.0, constrained);
  for (auto e : sm.edges()) {
    const auto h = sm.halfedge(e);
    if (sm.is_border(e) || patch[sm.face(h)] != patch[sm.face(sm.opposite(h))])
      constrained[e] = true;
  }
  // Target edge length max_edge (the remesher keeps edges between 4/5 and 4/3 of it).
  PMP::isotropic_remeshing(faces(sm), max_edge, sm,
                           CGAL::parameters::number_of_iterations(1)
                               .edge_is_constrained_map(constrained)
                               .face_patch_map(patch)
                               .number_of_relaxation_steps(0));
  sm.collect_garbage();
  mesh->vertices.resize(sm.number_of_vertices());
  for (auto v : sm.vertices()) {
    const auto& p = sm.point(v);
    mesh->vertices[v.idx()] = Eigen::Vector3d(p.x(), p.y(), p.z());
  }
  mesh->faces.clear();
  mesh->face_group.clear();
  for (auto f : sm.faces()) {
    Eigen::Vector3i t;
    int k = 0;
    for (auto v : CGAL::vertices_around_face(sm.halfedge(f), sm))
      t[k++] = static_cast<int>(v.idx());
    mesh->faces.push_back(t);
    mesh->face_group.push_back(patch[f]);
  }
}

}  // namespace tolver
