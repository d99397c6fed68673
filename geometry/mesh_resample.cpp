// resampleFaces (geometry/triangle_mesh.h): each face re-triangulated at the spacing on its own
// plane, by a constrained Delaunay triangulation (CGAL) of
//   - its three edges' points, each edge cut into ceil(length / (4/3 spacing)) equal pieces, the
//     same points for both faces on an edge (computed from the edge's lower vertex index, so the
//     mesh stays conforming), the edges' chain being the constraint; and
//   - an equilateral lattice of the spacing inside it, rows parallel to its first edge, kept half
//     a spacing or more from its edges (the edge points stand for that strip).
// Both are jittered (deterministically) so that the samples are no regular grid.
// Faces are independent: they are triangulated in parallel and assembled in face order, so the
// result does not depend on the threads.
#include <CGAL/Constrained_Delaunay_triangulation_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_face_base_with_info_2.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <deque>
#include <unordered_map>
#include <utility>
#include <vector>

#include "geometry/triangle_mesh.h"

namespace tolver {

namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Vb = CGAL::Triangulation_vertex_base_with_info_2<int, K>;
struct FaceInfo {
  int nesting = -1;  // 0 outside the face's boundary, 1 inside
};
using Fbb = CGAL::Triangulation_face_base_with_info_2<FaceInfo, K>;
using Fb = CGAL::Constrained_triangulation_face_base_2<K, Fbb>;
using Tds = CGAL::Triangulation_data_structure_2<Vb, Fb>;
using Cdt =
    CGAL::Constrained_Delaunay_triangulation_2<K, Tds, CGAL::No_constraint_intersection_tag>;

// One face's share of the result: its lattice points (3D) and its triangles, whose indices are
// global for vertices and edge points (>= 0) and -1 - i for its own lattice point i.
struct FacePiece {
  std::vector<Eigen::Vector3d> inner;
  std::vector<Eigen::Vector3i> triangles;
};

// Marks the faces inside the constrained boundary: breadth first from the infinite face, the
// nesting level growing by one across a constraint (CGAL's polygon triangulation example).
void markInside(Cdt& cdt) {
  std::deque<std::pair<Cdt::Face_handle, int>> queue{{cdt.infinite_face(), 0}};
  while (!queue.empty()) {
    const auto [f, level] = queue.front();
    queue.pop_front();
    if (f->info().nesting != -1) continue;
    f->info().nesting = level;
    for (int i = 0; i < 3; ++i) {
      const Cdt::Face_handle n = f->neighbor(i);
      if (n->info().nesting != -1) continue;
      if (cdt.is_constrained(Cdt::Edge(f, i)))
        queue.emplace_back(n, level + 1);
      else
        queue.emplace_front(n, level);
    }
  }
}

// A deterministic pseudo-random number in [-1, 1) from a key (splitmix64's finaliser): the jitter
// that keeps the samples from being a regular grid. A regular grid aliases with the regular
// marks of a finish (scallops at the step-over): sampled on the CAD's 1 mm grid, a 1 mm
// step-over's RMS came out 4.16 um where a fine sampling gives 5.59.
double jitter(uint64_t key) {
  key += 0x9e3779b97f4a7c15ULL;
  key = (key ^ (key >> 30)) * 0xbf58476d1ce4e5b9ULL;
  key = (key ^ (key >> 27)) * 0x94d049bb133111ebULL;
  key ^= key >> 31;
  return static_cast<double>(key >> 11) * 0x1.0p-52 - 1.0;
}
constexpr double kJitter = 0.3;  // of a piece along an edge, of the spacing inside a face

// A fan over the boundary cycle: combinatorially a triangulation of the disk, for a face with no
// area (its triangles have none either) or one the triangulation refused.
void fan(const std::vector<int>& cycle, FacePiece* piece) {
  piece->inner.clear();
  piece->triangles.clear();
  for (size_t i = 1; i + 1 < cycle.size(); ++i)
    piece->triangles.emplace_back(cycle[0], cycle[i], cycle[i + 1]);
}

}  // namespace

void resampleFaces(TriangleMesh* mesh, double spacing) {
  if (!(spacing > 0) || mesh->faces.empty()) return;
  const int nv = static_cast<int>(mesh->vertices.size());
  const int nf = static_cast<int>(mesh->faces.size());
  const double piece_max = spacing * 4.0 / 3.0;
  // The edges, each once, and their points.
  std::unordered_map<uint64_t, int> edge_id;
  edge_id.reserve(3 * static_cast<size_t>(nf) / 2 + 1);
  std::vector<int> first_point{nv};  // edge e's inner points are first_point[e] ...
  std::vector<int> pieces;           // ... in pieces[e] - 1 of them, from its lower vertex
  std::vector<Eigen::Vector3i> face_edges(nf);
  std::vector<Eigen::Vector3d>& V = mesh->vertices;
  for (int f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) {
      int a = mesh->faces[f][k], b = mesh->faces[f][(k + 1) % 3];
      if (a > b) std::swap(a, b);
      const auto [it, inserted] =
          edge_id.try_emplace((static_cast<uint64_t>(a) << 32) | static_cast<uint32_t>(b),
                              static_cast<int>(pieces.size()));
      if (inserted) {
        const double n = std::ceil((V[b] - V[a]).norm() / piece_max);
        const int p = n >= 1 && n < 1e7 ? static_cast<int>(n) : 1;  // the budget bounds the sizes
        pieces.push_back(p);
        first_point.push_back(first_point.back() + p - 1);
      }
      face_edges[f][k] = it->second;
    }
  const int edge_points = first_point.back() - nv;
  V.resize(static_cast<size_t>(nv) + edge_points);
  for (const auto& [key, e] : edge_id) {
    const int a = static_cast<int>(key >> 32), b = static_cast<int>(key & 0xffffffffu);
    for (int j = 1; j < pieces[e]; ++j) {
      const double t =
          (j + kJitter * jitter(key * 0x100000001b3ULL + static_cast<uint64_t>(j))) / pieces[e];
      V[first_point[e] + j - 1] = V[a] + t * (V[b] - V[a]);
    }
  }

  std::vector<FacePiece> result(nf);
  const double row = spacing * std::sqrt(3.0) / 2.0;
  tbb::parallel_for(tbb::blocked_range<int>(0, nf, 16), [&](const tbb::blocked_range<int>& r) {
    std::vector<int> cycle;
    std::vector<std::pair<K::Point_2, int>> lattice;
    for (int f = r.begin(); f != r.end(); ++f) {
      const Eigen::Vector3i& t = mesh->faces[f];
      FacePiece& piece = result[f];
      // The boundary cycle, counter-clockwise as the face.
      cycle.clear();
      for (int k = 0; k < 3; ++k) {
        const int a = t[k], b = t[(k + 1) % 3], e = face_edges[f][k];
        cycle.push_back(a);
        const int inner = pieces[e] - 1;
        for (int j = 0; j < inner; ++j)
          cycle.push_back(first_point[e] + (a < b ? j : inner - 1 - j));
      }
      const Eigen::Vector3d& p0 = V[t[0]];
      const Eigen::Vector3d e1 = V[t[1]] - p0, e2 = V[t[2]] - p0;
      const Eigen::Vector3d normal = e1.cross(e2);
      const double scale2 =
          std::max({e1.squaredNorm(), e2.squaredNorm(), (V[t[2]] - V[t[1]]).squaredNorm()});
      if (cycle.size() == 3) {  // nothing to add: the face as it is
        piece.triangles.push_back(t);
        continue;
      }
      if (!(normal.norm() > 1e-12 * scale2)) {
        fan(cycle, &piece);
        continue;
      }
      // The face's plane: u along its first edge, v = n x u, so counter-clockwise in (u, v) is
      // counter-clockwise seen from the normal's side.
      const Eigen::Vector3d u = e1.normalized();
      const Eigen::Vector3d v = normal.normalized().cross(u);
      auto to2d = [&](const Eigen::Vector3d& p) {
        return K::Point_2((p - p0).dot(u), (p - p0).dot(v));
      };
      // The lattice: rows parallel to the first edge (y = 0), the third corner at y = ymax.
      const Eigen::Vector2d c1(e1.dot(u), 0.0), c2(e2.dot(u), e2.dot(v));
      lattice.clear();
      const double margin = 0.5 * spacing;
      // Inward unit normals of the three edges (2D), for the distance to each edge.
      const Eigen::Vector2d corner[3] = {Eigen::Vector2d::Zero(), c1, c2};
      Eigen::Vector2d inward[3];
      for (int k = 0; k < 3; ++k) {
        const Eigen::Vector2d d = (corner[(k + 1) % 3] - corner[k]).normalized();
        inward[k] = Eigen::Vector2d(-d.y(), d.x());
      }
      const double xmin = std::min({0.0, c1.x(), c2.x()}), xmax = std::max({0.0, c1.x(), c2.x()});
      for (int j = 1; j * row < c2.y() - margin; ++j) {
        const double y = j * row;
        const double x0 = (j % 2) * 0.5 * spacing;
        for (double x = xmin + std::fmod(x0 - xmin, spacing) - spacing; x <= xmax; x += spacing) {
          const uint64_t key = (static_cast<uint64_t>(f) << 24) ^ (static_cast<uint64_t>(j) << 12) ^
                               static_cast<uint64_t>((x - xmin) / spacing + 1.5);
          const Eigen::Vector2d q(x + kJitter * spacing * jitter(2 * key),
                                  y + kJitter * spacing * jitter(2 * key + 1));
          bool inside = true;
          for (int k = 0; k < 3 && inside; ++k) inside = (q - corner[k]).dot(inward[k]) >= margin;
          if (!inside) continue;
          piece.inner.push_back(p0 + q.x() * u + q.y() * v);
          lattice.emplace_back(K::Point_2(q.x(), q.y()),
                               -1 - static_cast<int>(piece.inner.size() - 1));
        }
      }
      try {
        Cdt cdt;
        std::vector<Cdt::Vertex_handle> boundary;
        boundary.reserve(cycle.size());
        for (int g : cycle) {
          const Cdt::Vertex_handle h = cdt.insert(to2d(V[g]));
          h->info() = g;
          boundary.push_back(h);
        }
        for (size_t i = 0; i < boundary.size(); ++i)
          cdt.insert_constraint(boundary[i], boundary[(i + 1) % boundary.size()]);
        cdt.insert(lattice.begin(), lattice.end());
        if (cdt.number_of_vertices() != cycle.size() + lattice.size())
          throw std::runtime_error("merged");
        markInside(cdt);
        for (auto fh : cdt.finite_face_handles())
          if (fh->info().nesting % 2 == 1)
            piece.triangles.emplace_back(fh->vertex(0)->info(), fh->vertex(1)->info(),
                                         fh->vertex(2)->info());
      } catch (const std::exception&) {  // points merged or constraints crossing: a sliver
        fan(cycle, &piece);
      }
    }
  });

  // Assembly in face order, in parallel: each face's points and triangles go where a prefix sum
  // of the counts puts them (the same mesh as a loop over the faces in turn).
  std::vector<size_t> point_at(static_cast<size_t>(nf) + 1, V.size()), face_at(nf + 1, 0);
  for (int f = 0; f < nf; ++f) {
    point_at[f + 1] = point_at[f] + result[f].inner.size();
    face_at[f + 1] = face_at[f] + result[f].triangles.size();
  }
  V.resize(point_at[nf]);
  std::vector<Eigen::Vector3i> faces(face_at[nf]);
  std::vector<int> groups(face_at[nf]);
  tbb::parallel_for(tbb::blocked_range<int>(0, nf, 64), [&](const tbb::blocked_range<int>& r) {
    for (int f = r.begin(); f != r.end(); ++f) {
      const int base = static_cast<int>(point_at[f]);
      std::copy(result[f].inner.begin(), result[f].inner.end(), V.begin() + point_at[f]);
      size_t at = face_at[f];
      for (Eigen::Vector3i tri : result[f].triangles) {
        for (int k = 0; k < 3; ++k)
          if (tri[k] < 0) tri[k] = base + (-1 - tri[k]);
        faces[at] = tri;
        groups[at++] = mesh->face_group[f];
      }
    }
  });
  std::vector<int> given(face_at[nf]);
  for (int f = 0; f < nf; ++f)
    std::fill(given.begin() + face_at[f], given.begin() + face_at[f + 1], f);
  mesh->given_faces = std::move(mesh->faces);
  mesh->face_given = std::move(given);
  mesh->faces = std::move(faces);
  mesh->face_group = std::move(groups);
}

}  // namespace tolver
