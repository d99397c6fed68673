#include "geometry/mesh_repair.h"

#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/triangulate_hole.h>
#include <CGAL/Simple_cartesian.h>
#include <CGAL/Surface_mesh.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <numeric>
#include <unordered_map>

namespace tolver {
namespace {

// The largest hole filled, in border edges (MeshRepairReport notes the ones kept open).
constexpr size_t kMaxHoleEdges = 200;

using Kernel = CGAL::Simple_cartesian<double>;
using Point = Kernel::Point_3;
using SurfaceMesh = CGAL::Surface_mesh<Point>;
namespace PMP = CGAL::Polygon_mesh_processing;

std::string at(const Eigen::Vector3d& p) {
  char buf[96];
  std::snprintf(buf, sizeof buf, "(%.4f, %.4f, %.4f) mm", p.x(), p.y(), p.z());
  return buf;
}

uint64_t edgeKey(int a, int b) {
  return (static_cast<uint64_t>(std::min(a, b)) << 32) | static_cast<uint32_t>(std::max(a, b));
}

struct BitsHash {
  size_t operator()(const std::array<uint64_t, 3>& k) const {
    return std::hash<uint64_t>()(k[0] * 0x9E3779B97F4A7C15ull ^ (k[1] + 0x7F4A7C15ull) * 31 ^ k[2]);
  }
};

// Connected components of faces through shared edges; returns the component of each face.
int faceComponents(const std::vector<Eigen::Vector3i>& faces, std::vector<int>* comp) {
  std::vector<int> parent(faces.size());
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](int x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  std::unordered_map<uint64_t, int> first;
  for (int f = 0; f < static_cast<int>(faces.size()); ++f)
    for (int e = 0; e < 3; ++e) {
      auto [it, fresh] = first.try_emplace(edgeKey(faces[f][e], faces[f][(e + 1) % 3]), f);
      if (!fresh) parent[find(f)] = find(it->second);
    }
  comp->assign(faces.size(), -1);
  std::unordered_map<int, int> ids;
  for (int f = 0; f < static_cast<int>(faces.size()); ++f) {
    auto [it, fresh] = ids.try_emplace(find(f), static_cast<int>(ids.size()));
    (*comp)[f] = it->second;
  }
  return static_cast<int>(ids.size());
}

// A hole's border loop kept open (longer than the largest filled), for the coverage report.
struct OpenLoop {
  Eigen::Vector3d centre;
  double perimeter, area;
  int face;
};

// The mesh as it goes through the repair steps.
struct Repair {
  const TriangleMesh& input;
  MeshRepairReport rep;
  std::vector<Eigen::Vector3d> points;
  std::vector<int> remap;  // input vertex -> merged point
  int merged = 0;          // distinct positions
  Eigen::AlignedBox3d box;
  double diag = 0, max_hole = 0;
  std::vector<std::vector<size_t>> polygons;  // faces kept, as CGAL's polygon soup
  std::vector<int> groups;                    // per face
  std::vector<Point> cgal_points;
  std::vector<Eigen::Vector3i> faces;  // after orientation and hole filling
  std::vector<OpenLoop> open_loops;
};

// 1. Merge vertices at the same position (bit for bit; -0 is 0).
void mergeVertices(Repair& r) {
  std::unordered_map<std::array<uint64_t, 3>, int, BitsHash> by_position;
  r.remap.resize(r.input.vertices.size());
  for (size_t i = 0; i < r.input.vertices.size(); ++i) {
    std::array<uint64_t, 3> bits;
    for (int k = 0; k < 3; ++k) {
      const double c = r.input.vertices[i][k] == 0.0 ? 0.0 : r.input.vertices[i][k];  // -0 == 0
      std::memcpy(&bits[k], &c, sizeof c);
    }
    auto [it, fresh] = by_position.try_emplace(bits, static_cast<int>(r.points.size()));
    if (fresh) r.points.push_back(r.input.vertices[i]);
    r.remap[i] = it->second;
  }
  r.merged = static_cast<int>(by_position.size());
  for (const auto& p : r.points) r.box.extend(p);
  r.diag = r.box.diagonal().norm();
}

// 2. Degenerate (zero-area) and duplicate faces removed, with notes.
void removeDegenerateFaces(Repair& r) {
  const TriangleMesh& input = r.input;
  MeshRepairReport& rep = r.rep;
  const std::vector<Eigen::Vector3d>& points = r.points;
  const double diag = r.diag;
  std::map<std::array<int, 3>, int> seen;
  for (size_t f = 0; f < input.faces.size(); ++f) {
    Eigen::Vector3i t;
    for (int k = 0; k < 3; ++k) {
      const int v = input.faces[f][k];
      if (v < 0 || v >= static_cast<int>(input.vertices.size()))
        throw MeshDefect("face " + std::to_string(f) + " refers to vertex " + std::to_string(v) +
                             ", which does not exist",
                         Eigen::Vector3d::Zero());
      t[k] = r.remap[v];
    }
    const Eigen::Vector3d c = (points[t[0]] + points[t[1]] + points[t[2]]) / 3.0;
    const double twice_area =
        (points[t[1]] - points[t[0]]).cross(points[t[2]] - points[t[0]]).norm();
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2] || !(twice_area > 1e-14 * diag * diag)) {
      if (rep.degenerate_faces++ < 3)
        rep.notes.push_back("removed a degenerate (zero-area) face at " + at(c));
      continue;
    }
    std::array<int, 3> sorted = {t[0], t[1], t[2]};
    std::sort(sorted.begin(), sorted.end());
    if (!seen.emplace(sorted, static_cast<int>(f)).second) {
      if (rep.duplicate_faces++ < 3) rep.notes.push_back("removed a duplicate face at " + at(c));
      continue;
    }
    r.polygons.push_back(
        {static_cast<size_t>(t[0]), static_cast<size_t>(t[1]), static_cast<size_t>(t[2])});
    r.groups.push_back(input.face_group.empty() ? 0 : input.face_group[f]);
  }
  if (rep.degenerate_faces > 3)
    rep.notes.push_back("... " + std::to_string(rep.degenerate_faces) + " degenerate faces in all");
  if (rep.duplicate_faces > 3)
    rep.notes.push_back("... " + std::to_string(rep.duplicate_faces) + " duplicate faces in all");
  if (r.polygons.empty()) throw MeshDefect("every face of the mesh is degenerate", r.box.center());
}

// 3. Non-manifold edges cannot be repaired without guessing which sheet is the part: refused.
void refuseNonManifoldEdges(const Repair& r) {
  std::unordered_map<uint64_t, int> count;
  for (const auto& p : r.polygons)
    for (int e = 0; e < 3; ++e)
      ++count[edgeKey(static_cast<int>(p[e]), static_cast<int>(p[(e + 1) % 3]))];
  int bad = 0;
  uint64_t first = 0;
  int first_count = 0;
  for (const auto& [k, n] : count)
    if (n > 2 && bad++ == 0) {
      first = k;
      first_count = n;
    }
  if (bad > 0) {
    const Eigen::Vector3d a = r.points[first >> 32], b = r.points[first & 0xffffffffu];
    throw MeshDefect("non-manifold edge: " + std::to_string(first_count) +
                         " faces share the edge from " + at(a) + " to " + at(b) + " (" +
                         std::to_string(bad) + " such edges); repair the model in CAD",
                     0.5 * (a + b));
  }
}

// 4. Consistent orientation (CGAL), counting the faces it turned and the vertices it split.
void orientConsistently(Repair& r) {
  MeshRepairReport& rep = r.rep;
  std::vector<std::vector<size_t>>& polygons = r.polygons;
  std::vector<Point>& cgal_points = r.cgal_points;
  cgal_points.reserve(r.points.size());
  for (const auto& p : r.points) cgal_points.emplace_back(p.x(), p.y(), p.z());
  const auto before = polygons;
  const size_t points_before = cgal_points.size();
  PMP::orient_polygon_soup(cgal_points, polygons);
  rep.split_vertices = static_cast<int>(cgal_points.size() - points_before);
  for (size_t f = 0; f < polygons.size(); ++f) {
    // Same cyclic order? A reversed triangle reads its vertices backwards.
    const auto& a = before[f];
    const auto& b = polygons[f];
    int shift = 0;
    while (shift < 3 && b[shift] != a[0]) ++shift;
    if (shift < 3 && b[(shift + 1) % 3] != a[1]) ++rep.reoriented_faces;
  }
  if (rep.reoriented_faces > 0)
    rep.notes.push_back("turned " + std::to_string(rep.reoriented_faces) +
                        " faces to agree with their neighbours");
  if (rep.split_vertices > 0)
    rep.notes.push_back("split " + std::to_string(rep.split_vertices) +
                        " non-manifold vertices (surfaces touching at a point)");
}

// The border loops of the faces: vertex -> next vertex along the border (opposite to the face's
// edge), and the face of each border vertex's edge.
void borderLoops(const std::vector<Eigen::Vector3i>& faces, std::unordered_map<int, int>* next,
                 std::unordered_map<int, int>* border_face) {
  std::unordered_map<uint64_t, int> directed;  // directed edge -> face
  for (int f = 0; f < static_cast<int>(faces.size()); ++f)
    for (int e = 0; e < 3; ++e)
      directed[(static_cast<uint64_t>(faces[f][e]) << 32) |
               static_cast<uint32_t>(faces[f][(e + 1) % 3])] = f;
  for (const auto& [k, f] : directed) {
    const int a = static_cast<int>(k >> 32), b = static_cast<int>(k & 0xffffffffu);
    if (!directed.count((static_cast<uint64_t>(b) << 32) | static_cast<uint32_t>(a))) {
      (*next)[b] = a;
      (*border_face)[b] = f;
    }
  }
}

// 5. Holes: borders shorter than max_hole are filled (CGAL), the others kept and measured.
void fillHoles(Repair& r) {
  MeshRepairReport& rep = r.rep;
  const double max_hole = r.max_hole;
  rep.max_hole_perimeter = max_hole;
  std::vector<Eigen::Vector3i>& faces = r.faces;
  std::vector<Eigen::Vector3d>& points = r.points;
  std::vector<int>& groups = r.groups;
  const std::vector<Point>& cgal_points = r.cgal_points;
  for (const auto& p : r.polygons)
    faces.emplace_back(static_cast<int>(p[0]), static_cast<int>(p[1]), static_cast<int>(p[2]));
  points.clear();
  for (const auto& p : cgal_points) points.emplace_back(p.x(), p.y(), p.z());
  std::unordered_map<int, int> next, border_face;
  borderLoops(faces, &next, &border_face);
  if (next.empty()) return;
  SurfaceMesh sm;
  bool built = false;
  std::unordered_map<int, bool> visited;
  for (const auto& [v0, v1] : next) {
    if (visited[v0]) continue;
    std::vector<int> loop;
    double perimeter = 0;
    int v = v0;
    while (!visited[v] && next.count(v)) {
      visited[v] = true;
      loop.push_back(v);
      perimeter += (points[next[v]] - points[v]).norm();
      v = next[v];
    }
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();
    for (int u : loop) centre += points[u];
    centre /= static_cast<double>(loop.size());
    // A hole of more than kMaxHoleEdges edges is kept open: filling is cubic in its edges.
    if (v != v0 || perimeter > max_hole || loop.size() < 3 || loop.size() > kMaxHoleEdges) {
      ++rep.open_borders;
      if (v == v0 && loop.size() >= 3) {
        Eigen::Vector3d spanned = Eigen::Vector3d::Zero();
        for (size_t k = 0; k < loop.size(); ++k)
          spanned += points[loop[k]].cross(points[loop[(k + 1) % loop.size()]]);
        r.open_loops.push_back({centre, perimeter, 0.5 * spanned.norm(), border_face[loop[0]]});
      }
      continue;
    }
    if (!built) {
      std::vector<std::vector<size_t>> soup;
      for (const auto& t : faces) soup.push_back({size_t(t[0]), size_t(t[1]), size_t(t[2])});
      PMP::polygon_soup_to_polygon_mesh(cgal_points, soup, sm);
      built = true;
    }
    // The border halfedge from loop[0] to loop[1] (no face on its side).
    const auto h =
        CGAL::halfedge(SurfaceMesh::Vertex_index(loop[0]), SurfaceMesh::Vertex_index(loop[1]), sm);
    if (!h.second || !sm.is_border(h.first)) {
      ++rep.open_borders;
      continue;
    }
    std::vector<SurfaceMesh::Face_index> added;
    // Without the 3D Delaunay search space: with this inexact kernel its point location can walk
    // for ever on degenerate borders (a fuzzed 8 kB STL ran verify for minutes); the dynamic
    // programme over all triangulations is bounded, O(edges^3).
    PMP::triangulate_hole(sm, h.first, std::back_inserter(added),
                          CGAL::parameters::use_delaunay_triangulation(false));
    const int g = groups[border_face[loop[0]]];
    for (auto f : added) {
      Eigen::Vector3i t;
      int k = 0;
      for (auto v2 : CGAL::vertices_around_face(sm.halfedge(f), sm)) t[k++] = static_cast<int>(v2);
      faces.push_back(t);
      groups.push_back(g);
    }
    ++rep.holes_filled;
    rep.hole_faces_added += static_cast<int>(added.size());
    if (rep.holes_filled <= 3)
      rep.notes.push_back("filled a hole of " + std::to_string(loop.size()) + " edges at " +
                          at(centre));
  }
  if (rep.open_borders > 0)
    rep.notes.push_back("open surface: " + std::to_string(rep.open_borders) +
                        " borders kept (longer than " + std::to_string(max_hole) +
                        " mm or of more than " + std::to_string(kMaxHoleEdges) +
                        " edges); outward is the side the file's winding gives");
}

// 6. Closed components bound their volume: their faces turned outward (positive signed
// volume); which open borders are holes in the surface (MeshRepairReport::holes).
void orientOutwards(Repair& r) {
  MeshRepairReport& rep = r.rep;
  std::vector<Eigen::Vector3i>& faces = r.faces;
  const std::vector<Eigen::Vector3d>& points = r.points;
  const std::vector<OpenLoop>& open_loops = r.open_loops;
  std::vector<int> comp;
  rep.components = faceComponents(faces, &comp);
  std::vector<double> volume(rep.components, 0.0);
  std::vector<char> open(rep.components, 0);
  {
    std::unordered_map<uint64_t, int> count;
    for (const auto& t : faces)
      for (int e = 0; e < 3; ++e) ++count[edgeKey(t[e], t[(e + 1) % 3])];
    for (int f = 0; f < static_cast<int>(faces.size()); ++f) {
      const auto& t = faces[f];
      volume[comp[f]] += points[t[0]].dot(points[t[1]].cross(points[t[2]])) / 6.0;
      for (int e = 0; e < 3; ++e)
        if (count[edgeKey(t[e], t[(e + 1) % 3])] == 1) open[comp[f]] = 1;
    }
  }
  rep.closed = std::none_of(open.begin(), open.end(), [](char c) { return c != 0; });
  // Which open borders are holes in the surface (see MeshRepairReport::holes).
  {
    std::vector<double> surface(rep.components, 0.0), largest(rep.components, 0.0);
    for (int f = 0; f < static_cast<int>(faces.size()); ++f) {
      const auto& t = faces[f];
      surface[comp[f]] +=
          0.5 * (points[t[1]] - points[t[0]]).cross(points[t[2]] - points[t[0]]).norm();
    }
    for (const OpenLoop& l : open_loops)
      largest[comp[l.face]] = std::max(largest[comp[l.face]], l.area);
    for (const OpenLoop& l : open_loops) {
      const int c = comp[l.face];
      const bool sheet = largest[c] >= 0.3 * surface[c];
      if (sheet && l.area == largest[c]) continue;  // the sheet's outer edge
      rep.holes.push_back({l.centre, l.perimeter, l.area});
      rep.hole_area += l.area;
    }
    if (!rep.holes.empty())
      rep.notes.push_back(std::to_string(rep.holes.size()) + " holes in the surface left open (" +
                          std::to_string(static_cast<int>(std::round(rep.hole_area))) +
                          " mm2 not covered by the mesh; the first at " +
                          at(rep.holes.front().centre_w) + ")");
  }
  int turned = 0;
  for (int f = 0; f < static_cast<int>(faces.size()); ++f)
    if (!open[comp[f]] && volume[comp[f]] < 0) {
      std::swap(faces[f][1], faces[f][2]);
      ++turned;
    }
  if (turned > 0) {
    rep.reoriented_faces += turned;
    rep.notes.push_back("turned " + std::to_string(turned) +
                        " faces of closed components inside out to face outwards");
  }
}

}  // namespace

TriangleMesh repairMesh(const TriangleMesh& input, const MeshRepairOptions& options,
                        MeshRepairReport* report) {
  Repair r{input, {}, {}, {}, 0, {}, 0, 0, {}, {}, {}, {}, {}};
  r.rep.input_vertices = static_cast<int>(input.vertices.size());
  r.rep.input_faces = static_cast<int>(input.faces.size());
  if (input.faces.empty()) throw MeshDefect("the mesh has no faces", Eigen::Vector3d::Zero());
  for (const auto& v : input.vertices)
    if (!v.allFinite()) throw MeshDefect("a vertex coordinate is not a finite number", v);
  mergeVertices(r);
  r.max_hole = options.max_hole_perimeter >= 0 ? options.max_hole_perimeter : 0.02 * r.diag;
  removeDegenerateFaces(r);
  refuseNonManifoldEdges(r);
  orientConsistently(r);
  fillHoles(r);
  orientOutwards(r);
  TriangleMesh out;
  out.vertices = std::move(r.points);
  out.faces = std::move(r.faces);
  out.face_group = std::move(r.groups);
  out.group_names =
      input.group_names.empty() ? std::vector<std::string>{"part"} : input.group_names;
  r.rep.merged_vertices = r.rep.input_vertices - r.merged;
  if (report) *report = r.rep;
  return out;
}

}  // namespace tolver
