#include "geometry/mesh_repair.h"

#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/triangulate_hole.h>
#include <CGAL/Simple_cartesian.h>
#include <CGAL/Surface_mesh.h>

#include <Eigen/Geometry>
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <numeric>
#include <unordered_map>

#include "geometry/openmesh_quiet.h"

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

// The topology (half-edges, borders, components) is OpenMesh's. What stays hand-written here:
// merging vertices bit for bit with the map from each input vertex (the faces' groups and the
// needle split below use it); the non-manifold edge check, which runs on the polygon soup because
// neither OpenMesh nor CGAL's Surface_mesh can hold such an edge (OpenMesh's add_face refuses it
// without saying where; CGAL's orient_polygon_soup would duplicate vertices and go on); the needle
// split (a T-junction's repair no library here does); the outward orientation of voids by ray
// parity (CGAL's orient_to_bound_a_volume needs a closed mesh, and the open ones are oriented by
// the file's winding).
struct OmTraits : OpenMesh::DefaultTraits {
  using Point = OpenMesh::Vec3d;
};
using OmMesh = OpenMesh::TriMesh_ArrayKernelT<OmTraits>;

// The faces as OpenMesh's half-edge mesh, face f as its face f. After orient_polygon_soup the
// faces form an oriented manifold OpenMesh takes face by face; a face it cannot take is refused
// with its place (OpenMesh's own message is silenced: quietOpenMesh).
OmMesh halfedgeMesh(const std::vector<Eigen::Vector3d>& points,
                    const std::vector<Eigen::Vector3i>& faces) {
  OmMesh m;
  m.reserve(points.size(), 3 * faces.size() / 2 + 16, faces.size());
  for (const Eigen::Vector3d& p : points) m.add_vertex(OmMesh::Point(p.x(), p.y(), p.z()));
  quietOpenMesh();
  for (const Eigen::Vector3i& f : faces) {
    const auto h = m.add_face(OmMesh::VertexHandle(f[0]), OmMesh::VertexHandle(f[1]),
                              OmMesh::VertexHandle(f[2]));
    if (!h.is_valid()) {
      const Eigen::Vector3d c = (points[f[0]] + points[f[1]] + points[f[2]]) / 3.0;
      throw MeshDefect("a face cannot join its neighbours (a non-manifold vertex or edge) at " +
                           at(c) + "; repair the model in CAD",
                       c);
    }
  }
  return m;
}

// Connected components of faces through shared edges (OpenMesh's face-face circulator); returns
// the component of each face.
int faceComponents(const OmMesh& m, std::vector<int>* comp) {
  comp->assign(m.n_faces(), -1);
  int n = 0;
  std::vector<OmMesh::FaceHandle> stack;
  for (auto f : m.faces()) {
    if ((*comp)[f.idx()] >= 0) continue;
    (*comp)[f.idx()] = n;
    stack.push_back(f);
    while (!stack.empty()) {
      const auto g = stack.back();
      stack.pop_back();
      for (auto h : m.ff_range(g))
        if ((*comp)[h.idx()] < 0) {
          (*comp)[h.idx()] = n;
          stack.push_back(h);
        }
    }
    ++n;
  }
  return n;
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
// A zero-area face whose three points lie on a line (a tessellator's sliver along a straight
// edge: OCCT's BRepMesh leaves them on cones) hides a T-junction: its middle point lies on the
// long edge of the face beyond it. Removing the sliver alone leaves a slit (an open border of no
// area); splitting that face at the middle point closes it, as the sliver meant.
void splitAtNeedles(Repair& r, const std::vector<Eigen::Vector3i>& needles) {
  if (needles.empty()) return;
  std::map<std::pair<size_t, size_t>, std::vector<size_t>> faces_of;  // undirected edge
  auto key = [](size_t a, size_t b) { return std::make_pair(std::min(a, b), std::max(a, b)); };
  auto index = [&](size_t f) {
    for (int k = 0; k < 3; ++k)
      faces_of[key(r.polygons[f][k], r.polygons[f][(k + 1) % 3])].push_back(f);
  };
  auto unindex = [&](size_t f) {
    for (int k = 0; k < 3; ++k) {
      auto& v = faces_of[key(r.polygons[f][k], r.polygons[f][(k + 1) % 3])];
      v.erase(std::remove(v.begin(), v.end(), f), v.end());
    }
  };
  for (size_t f = 0; f < r.polygons.size(); ++f) index(f);
  std::vector<char> done(needles.size(), 0);
  for (bool progress = true; progress;) {
    progress = false;
    for (size_t n = 0; n < needles.size(); ++n) {
      if (done[n]) continue;
      const Eigen::Vector3i& t = needles[n];
      // The middle point: the one between the other two along their line.
      int m = 0;
      for (int k = 0; k < 3; ++k) {
        const Eigen::Vector3d& p = r.points[t[k]];
        const Eigen::Vector3d& a = r.points[t[(k + 1) % 3]];
        const Eigen::Vector3d& c = r.points[t[(k + 2) % 3]];
        if ((p - a).dot(p - c) < 0) m = k;
      }
      const size_t b = t[m], a = t[(m + 1) % 3], c = t[(m + 2) % 3];
      const auto it = faces_of.find(key(a, c));
      if (it == faces_of.end() || it->second.size() != 1) continue;
      const size_t f = it->second.front();
      std::vector<size_t> poly = r.polygons[f];
      int k = 0;  // poly[k] -> poly[k+1] is the edge {a, c}
      while (key(poly[k], poly[(k + 1) % 3]) != key(a, c)) ++k;
      const size_t u = poly[k], v = poly[(k + 1) % 3], w = poly[(k + 2) % 3];
      if (w == b) continue;
      unindex(f);
      r.polygons[f] = {u, b, w};
      index(f);
      r.polygons.push_back({b, v, w});
      r.groups.push_back(r.groups[f]);
      index(r.polygons.size() - 1);
      done[n] = 1;
      progress = true;
    }
  }
}

void removeDegenerateFaces(Repair& r) {
  const TriangleMesh& input = r.input;
  MeshRepairReport& rep = r.rep;
  const std::vector<Eigen::Vector3d>& points = r.points;
  const double diag = r.diag;
  std::map<std::array<int, 3>, int> seen;
  std::vector<Eigen::Vector3i> needles;  // zero-area faces of three distinct points on a line
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
      if (t[0] != t[1] && t[1] != t[2] && t[0] != t[2]) needles.push_back(t);
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
  splitAtNeedles(r, needles);
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
  // The border loops: OpenMesh's boundary half-edges, each loop followed once.
  const OmMesh om = halfedgeMesh(points, faces);
  std::vector<char> visited(om.n_halfedges(), 0);
  SurfaceMesh sm;
  bool built = false;
  for (auto h0 : om.halfedges()) {
    if (!om.is_boundary(h0) || visited[h0.idx()]) continue;
    std::vector<int> loop;
    double perimeter = 0;
    for (auto h = h0; !visited[h.idx()]; h = om.next_halfedge_handle(h)) {
      visited[h.idx()] = 1;
      loop.push_back(om.from_vertex_handle(h).idx());
      perimeter += (points[om.to_vertex_handle(h).idx()] - points[loop.back()]).norm();
    }
    const int border_face = om.face_handle(om.opposite_halfedge_handle(h0)).idx();
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();
    for (int u : loop) centre += points[u];
    centre /= static_cast<double>(loop.size());
    // A hole of more than kMaxHoleEdges edges is kept open: filling is cubic in its edges.
    if (perimeter > max_hole || loop.size() < 3 || loop.size() > kMaxHoleEdges) {
      ++rep.open_borders;
      if (loop.size() >= 3) {
        Eigen::Vector3d spanned = Eigen::Vector3d::Zero();
        for (size_t k = 0; k < loop.size(); ++k)
          spanned += points[loop[k]].cross(points[loop[(k + 1) % loop.size()]]);
        r.open_loops.push_back({centre, perimeter, 0.5 * spanned.norm(), border_face});
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
    const int g = groups[border_face];
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

// How many closed components enclose each closed component (ray parity from one of its
// vertices); 0 for open ones, and for all when the rays would cost more than a bounded budget
// (then every closed component is taken as an outer one, as before voids were told apart).
std::vector<int> nestingDepth(const std::vector<Eigen::Vector3i>& faces,
                              const std::vector<Eigen::Vector3d>& points,
                              const std::vector<int>& comp, const std::vector<char>& open) {
  const int n = static_cast<int>(open.size());
  std::vector<int> depth(n, 0);
  std::vector<Eigen::AlignedBox3d> box(n);
  std::vector<std::vector<int>> of(n);  // each component's faces
  for (int f = 0; f < static_cast<int>(faces.size()); ++f) {
    of[comp[f]].push_back(f);
    for (int k = 0; k < 3; ++k) box[comp[f]].extend(points[faces[f][k]]);
  }
  std::vector<std::pair<int, int>> tests;  // (component, enclosing candidate)
  double work = 0;
  for (int c = 0; c < n; ++c)
    for (int d = 0; d < n && !open[c]; ++d)
      if (d != c && !open[d] && box[d].contains(box[c])) {
        tests.push_back({c, d});
        work += 3.0 * static_cast<double>(of[d].size());
      }
  if (tests.empty() || work > 5e7) return depth;
  // A direction no face of a CAD model is likely to hold edge-on.
  const Eigen::Vector3d dir = Eigen::Vector3d(1.0, 0.3137, 0.1731).normalized();
  // Three rays, from the centroids of three of its faces, vote: one that starts on a point where
  // the shells touch, or grazes an edge, is outvoted.
  auto inside = [&](const Eigen::Vector3d& o, int d) {
    int crossings = 0;
    for (int f : of[d]) {
      const Eigen::Vector3d& a = points[faces[f][0]];
      const Eigen::Vector3d e1 = points[faces[f][1]] - a, e2 = points[faces[f][2]] - a;
      const Eigen::Vector3d q = dir.cross(e2);
      const double det = e1.dot(q);
      if (std::abs(det) < 1e-300) continue;
      const Eigen::Vector3d t = o - a;
      const double u = t.dot(q) / det;
      if (u < 0 || u > 1) continue;
      const Eigen::Vector3d r = t.cross(e1);
      const double v = dir.dot(r) / det;
      if (v < 0 || u + v > 1) continue;
      if (e2.dot(r) / det > 0) ++crossings;
    }
    return crossings % 2 == 1;
  };
  for (const auto& [c, d] : tests) {
    int votes = 0;
    for (size_t k : {size_t(0), of[c].size() / 2, of[c].size() - 1}) {
      const Eigen::Vector3i& t = faces[of[c][k]];
      votes += inside((points[t[0]] + points[t[1]] + points[t[2]]) / 3.0, d);
    }
    const int crossings = votes >= 2;
    depth[c] += crossings % 2;
  }
  return depth;
}

// 6. Closed components bound their volume: their faces turned outward (positive signed
// volume); which open borders are holes in the surface (MeshRepairReport::holes).
void orientOutwards(Repair& r) {
  MeshRepairReport& rep = r.rep;
  std::vector<Eigen::Vector3i>& faces = r.faces;
  const std::vector<Eigen::Vector3d>& points = r.points;
  const std::vector<OpenLoop>& open_loops = r.open_loops;
  std::vector<int> comp;
  const OmMesh om = halfedgeMesh(points, faces);
  rep.components = faceComponents(om, &comp);
  std::vector<double> volume(rep.components, 0.0);
  std::vector<char> open(rep.components, 0);
  for (auto f : om.faces()) {
    const auto& t = faces[f.idx()];
    volume[comp[f.idx()]] += points[t[0]].dot(points[t[1]].cross(points[t[2]])) / 6.0;
    if (om.is_boundary(f)) open[comp[f.idx()]] = 1;  // an edge of it has no face beyond
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
  // A closed component inside another bounds a void (a solid's inner shell, as STEP files
  // carry them): its faces look into the void, so its signed volume is negative.
  const std::vector<int> depth = nestingDepth(faces, points, comp, open);
  int turned = 0, voids = 0;
  for (int c = 0; c < rep.components; ++c) voids += !open[c] && depth[c] % 2 == 1;
  for (int f = 0; f < static_cast<int>(faces.size()); ++f) {
    const int c = comp[f];
    if (!open[c] && (volume[c] < 0) != (depth[c] % 2 == 1)) {
      std::swap(faces[f][1], faces[f][2]);
      ++turned;
    }
  }
  if (turned > 0) {
    rep.reoriented_faces += turned;
    rep.notes.push_back("turned " + std::to_string(turned) +
                        " faces of closed components inside out to face outwards" +
                        (voids > 0 ? std::string(" (of voids: into the void)") : std::string()));
  }
  if (voids > 0)
    rep.notes.push_back(std::to_string(voids) +
                        " closed components lie inside another: kept as voids of the part");
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
  out.group_aliases = input.group_aliases;
  r.rep.merged_vertices = r.rep.input_vertices - r.merged;
  if (report) *report = r.rep;
  return out;
}

}  // namespace tolver
