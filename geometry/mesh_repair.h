#pragma once
// Checks and repairs of an imported part mesh (CGAL Polygon Mesh Processing and OpenMesh where
// they apply; geometry/mesh_repair.cpp says what stays hand-written and why):
//   - vertices at the same position are merged (an STL file repeats them per face);
//   - degenerate faces (repeated vertex or zero area) and duplicate faces are removed;
//   - inconsistent orientation is made consistent (CGAL orient_polygon_soup) and each closed
//     component is turned to bound its volume (faces outward);
//   - holes whose border is shorter than max_hole_perimeter are filled (CGAL triangulate_hole);
//     longer borders are the edge of an open surface and are kept (reported);
//   - a non-manifold edge (three or more faces) cannot be repaired safely: refused;
//   - borders, holes and components are read from OpenMesh's half-edge mesh of the result.
#include <Eigen/Core>
#include <stdexcept>
#include <string>
#include <vector>

#include "geometry/triangle_mesh.h"

namespace tolver {

// A defect that cannot be repaired safely; where_w locates it (mm, part frame).
class MeshDefect : public std::runtime_error {
 public:
  MeshDefect(const std::string& what, const Eigen::Vector3d& where)
      : std::runtime_error(what), where_w(where) {}
  Eigen::Vector3d where_w;
};

struct MeshRepairOptions {
  double max_hole_perimeter = -1.0;  // mm; negative: 2 % of the bounding-box diagonal
};

// A border left open that is a hole in the part's surface (not the outer edge of a sheet): the
// area it spans is missing from the faces being checked.
struct MeshHole {
  Eigen::Vector3d centre_w = Eigen::Vector3d::Zero();
  double perimeter = 0, area = 0;  // mm, mm^2 (the area its border spans)
};

struct MeshRepairReport {
  int input_vertices = 0, input_faces = 0;
  int merged_vertices = 0;
  int degenerate_faces = 0;
  int duplicate_faces = 0;
  int reoriented_faces = 0;  // faces turned to agree with their neighbours or to face out
  int split_vertices = 0;    // non-manifold vertices split by orient_polygon_soup
  int holes_filled = 0, hole_faces_added = 0;
  int open_borders = 0;           // borders left open (an open surface's edges)
  double max_hole_perimeter = 0;  // mm: the borders filled were shorter than this
  // The open borders that are holes: every border of a component whose largest border spans
  // less than 0.3 of its surface (a solid with holes), else all but that largest one (a sheet
  // with holes in it).
  std::vector<MeshHole> holes;
  double hole_area = 0;  // mm^2, summed
  int components = 0;
  bool closed = false;             // every component closed after repair
  std::vector<std::string> notes;  // one line per repair made, with a location
};

// Throws MeshDefect when the mesh is empty or cannot be repaired safely.
TriangleMesh repairMesh(const TriangleMesh& input, const MeshRepairOptions& options,
                        MeshRepairReport* report);

}  // namespace tolver
