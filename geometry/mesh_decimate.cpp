#include "geometry/mesh_decimate.h"

#include "geometry/openmesh_quiet.h"

// OpenMesh is kept inside this file (and mesh_repair.cpp): no header of this layer includes it.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <Eigen/Geometry>
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <OpenMesh/Tools/Decimater/DecimaterT.hh>
#include <OpenMesh/Tools/Decimater/ModNormalFlippingT.hh>
#include <OpenMesh/Tools/Decimater/ModQuadricT.hh>
#include <OpenMesh/Tools/Decimater/Observer.hh>
#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>

namespace tolver {
namespace {

struct Traits : OpenMesh::DefaultTraits {
  using Point = OpenMesh::Vec3d;
  using Normal = OpenMesh::Vec3d;
};
using Mesh = OpenMesh::TriMesh_ArrayKernelT<Traits>;

// The largest one-ring the link test below handles itself (a sampled surface's are about 6).
constexpr int kMaxRing = 48;

// The point of triangle (a, b, c) closest to p, as barycentric weights (Ericson, Real-Time
// Collision Detection, 5.1.5); false for a triangle of no area.
bool closestBarycentric(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                        const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                        std::array<double, 3>* w) {
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
  if (ab.cross(ac).squaredNorm() <= 1e-30 * std::max(ab.squaredNorm(), ac.squaredNorm()))
    return false;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return *w = {1, 0, 0}, true;
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return *w = {0, 1, 0}, true;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const double v = d1 / (d1 - d3);
    return *w = {1 - v, v, 0}, true;
  }
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return *w = {0, 0, 1}, true;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const double t = d2 / (d2 - d6);
    return *w = {1 - t, 0, t}, true;
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    const double t = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return *w = {0, 1 - t, t}, true;
  }
  const double denom = 1.0 / (va + vb + vc);
  const double v = vb * denom, t = vc * denom;
  return *w = {1 - v - t, v, t}, true;
}

// The bounds, kept per vertex at the cost of its one-ring (no list of removed points): each vertex
// carries the interval of the values of the original vertices it stands for, and a bound on
// their distance from the surface. A collapse of v0 into v1 re-triangulates v0's star with the
// vertices of its one-ring, so what v0 stood for (itself included) passes to each of them: the
// collapse is legal when every one of them shares v0's category, every interval merged with v0's
// stays within the value bound (then any value interpolated on a face of them lies within the
// bound of every value they stand for), and v0's own distance to the faces left, added to the
// distance bound it carried, stays within the distance bound.
template <class MeshT>
class ModDisplayBoundT : public OpenMesh::Decimater::ModBaseT<MeshT> {
 public:
  DECIMATING_MODULE(ModDisplayBoundT, MeshT, DisplayBound);

  explicit ModDisplayBoundT(MeshT& mesh) : Base(mesh, true), mesh_(Base::mesh()) {}

  void set(const std::vector<Eigen::Vector3d>* p, const std::vector<double>* value,
           const std::vector<int>* category, double max_distance, double max_difference) {
    p_ = p;
    category_ = category;
    max_distance_ = max_distance;
    max_difference_ = max_difference;
    if (lo_.empty()) {
      lo_ = *value;
      hi_ = *value;
      distance_.assign(value->size(), 0.0);
    }
  }

  // The category and value part of the bound alone (no distances): a cheap first refusal.
  bool sharesRing(const CollapseInfo& ci) const {
    const auto& C = *category_;
    const int v0 = ci.v0.idx();
    for (auto w : mesh_.vv_range(ci.v0)) {
      const int i = w.idx();
      if (C[i] != C[v0]) return false;
      if (std::max(hi_[i], hi_[v0]) - std::min(lo_[i], lo_[v0]) > max_difference_) return false;
    }
    return true;
  }

  float collapse_priority(const CollapseInfo& ci) override {
    return carried(ci) >= 0 ? static_cast<float>(Base::LEGAL_COLLAPSE)
                            : static_cast<float>(Base::ILLEGAL_COLLAPSE);
  }

  void preprocess_collapse(const CollapseInfo& ci) override {
    // The legality test just computed it when it passed this collapse last (the mesh unchanged
    // since: no collapse in between).
    const bool known = last_v0_ == ci.v0.idx() && last_v1_ == ci.v1.idx() && last_at_ == collapses_;
    const double d = known ? last_carried_ : carried(ci);
    ++collapses_;
    const int v0 = ci.v0.idx();
    for (auto w : mesh_.vv_range(ci.v0)) {
      const int i = w.idx();
      lo_[i] = std::min(lo_[i], lo_[v0]);
      hi_[i] = std::max(hi_[i], hi_[v0]);
      distance_[i] = std::max(distance_[i], d);
    }
  }

 private:
  // The distance bound v0's vertices would carry after the collapse; -1: the collapse breaks a
  // bound or a category.
  double carried(const CollapseInfo& ci) const {
    last_v0_ = ci.v0.idx();
    last_v1_ = ci.v1.idx();
    last_at_ = collapses_;
    return last_carried_ = carriedBound(ci);
  }
  double carriedBound(const CollapseInfo& ci) const {
    if (!sharesRing(ci)) return -1;
    const int v0 = ci.v0.idx();
    const auto& P = *p_;
    double nearest = INFINITY;
    for (auto f : mesh_.vf_range(ci.v0)) {
      if (f == ci.fl || f == ci.fr) continue;
      std::array<int, 3> v;
      int k = 0;
      for (auto fv : mesh_.fv_range(f)) v[k++] = (fv == ci.v0 ? ci.v1 : fv).idx();
      std::array<double, 3> w;
      if (!closestBarycentric(P[v0], P[v[0]], P[v[1]], P[v[2]], &w)) continue;
      const Eigen::Vector3d q = w[0] * P[v[0]] + w[1] * P[v[1]] + w[2] * P[v[2]];
      nearest = std::min(nearest, (q - P[v0]).norm());
    }
    const double d = distance_[v0] + nearest;
    return d <= max_distance_ ? d : -1;
  }

  Mesh& mesh_;
  const std::vector<Eigen::Vector3d>* p_ = nullptr;
  const std::vector<int>* category_ = nullptr;
  double max_distance_ = 0, max_difference_ = 0;
  std::vector<double> lo_, hi_, distance_;  // per vertex
  // The last bound computed, for the collapse of last_v0_ into last_v1_ after `last_at_`
  // collapses.
  mutable int last_v0_ = -1, last_v1_ = -1;
  mutable size_t last_at_ = 0;
  mutable double last_carried_ = -1;
  size_t collapses_ = 0;
};

// The decimater's progress: every 4096 collapses, the fraction of those wanted.
class DecimationProgress : public OpenMesh::Decimater::Observer {
 public:
  DecimationProgress(const std::function<void(double)>& report, size_t wanted)
      : Observer(4096),
        report_(report),
        wanted_(static_cast<double>(std::max<size_t>(wanted, 1))) {}
  void notify(size_t step) override {
    if (report_) report_(std::min(1.0, (done_before + static_cast<double>(step)) / wanted_));
  }
  double done_before = 0;

 private:
  const std::function<void(double)>& report_;
  double wanted_;
};

// OpenMesh's decimater with a first phase of multiple choices (Wu and Kobbelt, "Fast mesh
// decimation by multiple-choice techniques", 2002; OpenMesh's McDecimaterT, which draws from the
// process-wide rand()): each step draws 8 halfedges by its own generator, seeded per piece (the
// same mesh on any thread), and collapses the one of least quadric error among those every
// module allows. It keeps no heap: a collapse costs 8 evaluations instead of the heap's update of
// its whole neighbourhood (about 36). The heap decimater does the rest, where the choices grow
// rare. Both ask every module, so the bounds hold the same.
template <class MeshT, class Bound, class Quadric>
class SampledDecimaterT : public OpenMesh::Decimater::DecimaterT<MeshT> {
 public:
  using Base = OpenMesh::Decimater::DecimaterT<MeshT>;
  using CollapseInfo = typename Base::CollapseInfo;
  explicit SampledDecimaterT(MeshT& mesh)
      : OpenMesh::Decimater::BaseDecimaterT<MeshT>(mesh), Base(mesh), mesh_(mesh) {}

  // Up to `wanted` collapses, or fewer when a whole pass over the halfedges made none. Returns
  // the collapses made.
  size_t sampled(size_t wanted, const Bound& bound, Quadric& quadric, std::uint64_t seed) {
    if (!this->is_initialized()) return 0;
    std::uint64_t state = seed;
    auto next = [&state] {  // splitmix64
      std::uint64_t z = (state += 0x9E3779B97F4A7C15ull);
      z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
      z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
      return z ^ (z >> 31);
    };
    const std::uint64_t halfedges = mesh_.n_halfedges();
    if (halfedges == 0) return 0;
    size_t done = 0, done_at_pass = 0;
    for (std::uint64_t cursor = 0; done < wanted; cursor += kAdvance) {
      if (cursor >= halfedges) {  // a pass ends
        if (done == done_at_pass) break;
        done_at_pass = done;
        cursor = 0;
      }
      // The draws' quadric errors first (cheap), then the legality tests (the link condition,
      // the bounds, the normals: dear) in increasing error until one passes: the collapse of
      // least error among the legal draws, the first drawn among equal ones, as if every draw
      // had been tested.
      std::array<std::pair<float, int>, kDraws> draws;
      int drawn = 0;
      for (int k = 0; k < kDraws; ++k) {
        const typename MeshT::HalfedgeHandle h(
            static_cast<int>((cursor + next() % kWindow) % halfedges));
        if (mesh_.status(mesh_.edge_handle(h)).deleted()) continue;
        const CollapseInfo ci(mesh_, h);
        if (mesh_.status(ci.v0).locked() || !bound.sharesRing(ci)) continue;
        draws[drawn++] = {quadric.collapse_priority(ci), h.idx()};
      }
      std::stable_sort(draws.begin(), draws.begin() + drawn,
                       [](const auto& a, const auto& b) { return a.first < b.first; });
      typename MeshT::HalfedgeHandle best;
      for (int k = 0; k < drawn && !best.is_valid(); ++k) {
        const typename MeshT::HalfedgeHandle h(draws[k].second);
        const CollapseInfo ci(mesh_, h);
        if (legal(ci) &&
            this->collapse_priority(ci) != OpenMesh::Decimater::ModBaseT<MeshT>::ILLEGAL_COLLAPSE)
          best = h;
      }
      if (!best.is_valid()) continue;
      CollapseInfo ci(mesh_, best);
      this->preprocess_collapse(ci);
      mesh_.collapse(best);
      for (auto f : mesh_.vf_range(ci.v1))
        if (!mesh_.status(f).deleted()) mesh_.set_normal(f, mesh_.calc_face_normal(f));
      this->postprocess_collapse(ci);
      ++done;
      this->notify_observer(done);
    }
    return done;
  }

 private:
  // BaseDecimaterT::is_collapse_legal, its topology test (TriConnectivity::is_collapse_ok)
  // written without the heap: OpenMesh 9's builds and sorts vectors of the one-rings at every
  // call (with its allocations, a fifth of a verify's CPU went there). The classic link
  // condition, as OpenMesh 8 tested it: the one-rings of v0 and v1 meet only in the vertices
  // opposite the edge. A ring larger than kRing goes to OpenMesh's.
  bool legal(const CollapseInfo& ci) {
    if (mesh_.status(ci.v0).locked() || !collapseOk(ci)) return false;
    if (ci.vl.is_valid() && ci.vr.is_valid() && mesh_.find_halfedge(ci.vl, ci.vr).is_valid() &&
        mesh_.valence(ci.vl) == 3 && mesh_.valence(ci.vr) == 3)
      return false;
    if (mesh_.status(ci.v0).feature() && !mesh_.status(mesh_.edge_handle(ci.v0v1)).feature())
      return false;
    if (mesh_.is_boundary(ci.v0) &&
        (!mesh_.is_boundary(ci.v1) || (ci.vl.is_valid() && ci.vr.is_valid())))
      return false;
    return mesh_.cw_rotated_halfedge_handle(mesh_.cw_rotated_halfedge_handle(ci.v0v1)) != ci.v0v1;
  }
  bool collapseOk(const CollapseInfo& ci) {
    const auto v0v1 = ci.v0v1, v1v0 = ci.v1v0;
    if (mesh_.status(mesh_.edge_handle(v0v1)).deleted()) return false;
    const auto v0 = ci.v0, v1 = ci.v1;
    if (mesh_.status(v0).deleted() || mesh_.status(v1).deleted()) return false;
    // A face of the mesh is a triangle: a side is one when it is not the boundary.
    const bool left = !mesh_.is_boundary(v0v1), right = !mesh_.is_boundary(v1v0);
    const auto l = mesh_.to_vertex_handle(mesh_.next_halfedge_handle(v0v1));
    const auto r = mesh_.to_vertex_handle(mesh_.next_halfedge_handle(v1v0));
    auto bothBoundary = [&](typename MeshT::HalfedgeHandle h) {  // the triangle's other edges
      const auto h1 = mesh_.next_halfedge_handle(h), h2 = mesh_.next_halfedge_handle(h1);
      return mesh_.is_boundary(mesh_.opposite_halfedge_handle(h1)) &&
             mesh_.is_boundary(mesh_.opposite_halfedge_handle(h2));
    };
    if ((left && bothBoundary(v0v1)) || (right && bothBoundary(v1v0))) return false;
    if (l == r && left && right) return false;
    if (mesh_.is_boundary(v0) && mesh_.is_boundary(v1) && left && right) return false;
    std::array<int, kRing> ring1;
    int n1 = 0;
    for (auto w : mesh_.vv_range(v1)) {
      if (n1 == kRing) return mesh_.is_collapse_ok(v0v1);
      ring1[n1++] = w.idx();
    }
    for (auto w : mesh_.vv_range(v0)) {
      if ((w == l && left) || (w == r && right)) continue;
      if (std::find(ring1.begin(), ring1.begin() + n1, w.idx()) != ring1.begin() + n1) return false;
    }
    return true;
  }
  static constexpr int kRing = kMaxRing;
  // Each step draws kDraws halfedges from the kWindow that start at a cursor advancing kAdvance
  // a step through the halfedges (the sampler's order is spatial: the draws stay in cache).
  static constexpr int kDraws = 8;
  static constexpr std::uint64_t kWindow = 64, kAdvance = 8;
  MeshT& mesh_;
};

}  // namespace

namespace {

// The halfedge mesh of `faces` (each of three distinct vertices, all already in `mesh` as its
// first vertices) built directly, without add_face: OpenMesh's add_face looks up and relinks the
// halfedges around each corner (a fifth of a piece's decimation at a million samples went there).
// The edges are made in add_face's order (faces in turn, a face's edges from its first corner),
// so the mesh is the one add_face makes. False when the faces are not a manifold with a
// consistent orientation (an edge of three faces, or of two the same way round, a vertex whose
// faces are not one fan): the caller then clears the mesh and builds it with add_face, which keeps
// what it cannot take aside.
bool buildManifold(Mesh& mesh, const std::vector<Eigen::Vector3i>& faces, size_t vertices) {
  const size_t nf = faces.size();
  // The face edges out of each vertex (CSR): where each goes, and which it is (3 t + k: face
  // t's edge k runs from its corner k to corner k + 1).
  struct Out {
    int to, edge;
  };
  std::vector<int> first(vertices + 1, 0);
  std::vector<Out> out(3 * nf);
  for (const Eigen::Vector3i& f : faces)
    for (int k = 0; k < 3; ++k) ++first[f[k] + 1];
  for (size_t v = 0; v < vertices; ++v) first[v + 1] += first[v];
  {
    std::vector<int> fill(first.begin(), first.end() - 1);
    for (size_t t = 0; t < nf; ++t)
      for (int k = 0; k < 3; ++k)
        out[fill[faces[t][k]]++] = {faces[t][(k + 1) % 3], static_cast<int>(3 * t) + k};
  }
  // Each face edge's halfedge: a new edge's first halfedge, or the opposite of the face edge
  // made before it that runs the other way.
  std::vector<int> he(3 * nf, -1);
  int edges = 0;
  for (size_t t = 0; t < nf; ++t)
    for (int k = 0; k < 3; ++k) {
      const int a = faces[t][k], b = faces[t][(k + 1) % 3];
      int opposite = -1, others = 0, same = 0;
      for (int q = first[b]; q < first[b + 1]; ++q)
        if (out[q].to == a) opposite = out[q].edge, ++others;
      for (int q = first[a]; q < first[a + 1]; ++q) same += out[q].to == b;
      if (others > 1 || same > 1) return false;  // an edge of three faces, or two the same way
      if (opposite >= 0 && opposite < static_cast<int>(3 * t))
        he[3 * t + k] = he[opposite] ^ 1;
      else
        he[3 * t + k] = 2 * edges++;
    }
  mesh.resize(vertices, static_cast<size_t>(edges), nf);
  for (size_t t = 0; t < nf; ++t)
    for (int k = 0; k < 3; ++k) {
      const int h = he[3 * t + k];
      if (h % 2 == 0) {  // the edge's first halfedge runs a -> b
        mesh.set_vertex_handle(Mesh::HalfedgeHandle(h), Mesh::VertexHandle(faces[t][(k + 1) % 3]));
        mesh.set_vertex_handle(Mesh::HalfedgeHandle(h + 1), Mesh::VertexHandle(faces[t][k]));
      }
    }
  for (size_t t = 0; t < nf; ++t) {
    const Mesh::FaceHandle f(static_cast<int>(t));
    for (int k = 0; k < 3; ++k) {
      const Mesh::HalfedgeHandle h(he[3 * t + k]);
      mesh.set_next_halfedge_handle(h, Mesh::HalfedgeHandle(he[3 * t + (k + 1) % 3]));
      mesh.set_face_handle(h, f);
    }
    mesh.set_halfedge_handle(f, Mesh::HalfedgeHandle(he[3 * t + 2]));  // as add_face does
  }
  // The border: each vertex at most one halfedge out along it (else its faces are two fans), the
  // next of a border halfedge the one out of its end.
  std::vector<int> border_out(vertices, -1);
  for (int h = 0; h < 2 * edges; ++h) {
    const Mesh::HalfedgeHandle hh(h);
    if (mesh.face_handle(hh).is_valid()) continue;
    const int from = mesh.to_vertex_handle(mesh.opposite_halfedge_handle(hh)).idx();
    if (border_out[from] >= 0) return false;
    border_out[from] = h;
  }
  for (int h = 0; h < 2 * edges; ++h) {
    const Mesh::HalfedgeHandle hh(h);
    if (mesh.face_handle(hh).is_valid()) continue;
    const int next = border_out[mesh.to_vertex_handle(hh).idx()];
    if (next < 0) return false;
    mesh.set_next_halfedge_handle(hh, Mesh::HalfedgeHandle(next));
  }
  // Each vertex's halfedge out: along the border when it is on it (OpenMesh's rule); then its
  // faces, walked around it, must be all its faces (one fan).
  for (size_t v = 0; v < vertices; ++v) {
    const int count = first[v + 1] - first[v];
    if (count == 0) continue;
    const Mesh::HalfedgeHandle start(border_out[v] >= 0 ? border_out[v] : he[out[first[v]].edge]);
    mesh.set_halfedge_handle(Mesh::VertexHandle(static_cast<int>(v)), start);
    int seen = 0;
    Mesh::HalfedgeHandle h = start;
    do {
      seen += mesh.face_handle(h).is_valid();
      h = mesh.next_halfedge_handle(mesh.opposite_halfedge_handle(h));  // the next out of v
    } while (h != start && seen <= count);
    if (seen != count) return false;
  }
  return true;
}

// One piece, decimated by one OpenMesh decimater (the arrays are the piece's own).
DecimatedMesh decimatePiece(const std::vector<Eigen::Vector3d>& p,
                            const std::vector<Eigen::Vector3i>& faces,
                            const std::vector<double>& value, const std::vector<int>& category,
                            const std::vector<char>& locked, const DecimateOptions& options) {
  DecimatedMesh out;
  out.max_vertices = options.max_vertices;
  if (p.size() <= static_cast<size_t>(std::max(options.max_vertices, 3))) {
    // It fits as sampled.
    out.vertex.resize(p.size());
    for (size_t i = 0; i < p.size(); ++i) out.vertex[i] = static_cast<int>(i);
    for (const Eigen::Vector3i& f : faces)
      if (f[0] != f[1] && f[1] != f[2] && f[0] != f[2]) out.faces.push_back(f);
    return out;  // bounds 0: nothing moved
  }
  Mesh mesh;
  mesh.reserve(p.size(), 3 * faces.size() / 2 + 16, faces.size());
  std::vector<Mesh::VertexHandle> vh(p.size());
  for (size_t i = 0; i < p.size(); ++i)
    vh[i] = mesh.add_vertex(Mesh::Point(p[i].x(), p[i].y(), p[i].z()));
  std::vector<Eigen::Vector3i> as_given, proper;
  proper.reserve(faces.size());
  for (const Eigen::Vector3i& f : faces)
    (f[0] == f[1] || f[1] == f[2] || f[0] == f[2] ? as_given : proper).push_back(f);
  if (!buildManifold(mesh, proper, p.size())) {
    // OpenMesh reports a face it cannot add (a non-manifold edge): silenced (quietOpenMesh),
    // the face is kept as given and its vertices locked.
    mesh.clear();
    for (size_t i = 0; i < p.size(); ++i)
      vh[i] = mesh.add_vertex(Mesh::Point(p[i].x(), p[i].y(), p[i].z()));
    as_given.clear();
    quietOpenMesh();
    for (const Eigen::Vector3i& f : faces) {
      const bool repeated = f[0] == f[1] || f[1] == f[2] || f[0] == f[2];
      Mesh::FaceHandle h;
      if (!repeated) h = mesh.add_face(vh[f[0]], vh[f[1]], vh[f[2]]);
      if (!h.is_valid()) as_given.push_back(f);
    }
  }
  mesh.request_vertex_status();
  mesh.request_edge_status();
  mesh.request_face_status();
  mesh.request_face_normals();
  mesh.update_face_normals();
  for (size_t i = 0; i < p.size(); ++i)
    if (locked[i] || mesh.is_boundary(vh[i])) mesh.status(vh[i]).set_locked(true);
  // A hub, a vertex of more than kMaxRing neighbours (a fan: the CL-only surface of a spiral
  // program had a centre of 73 000 triangles), stays with its ring as it is: a collapse at it
  // costs its whole ring in OpenMesh's link test, which sorts it, and the 3D view of that
  // program took more than 5 minutes. Its ring locked, no collapse reaches or leaves it.
  for (size_t i = 0; i < p.size(); ++i) {
    if (mesh.valence(vh[i]) <= static_cast<unsigned>(kMaxRing)) continue;
    mesh.status(vh[i]).set_locked(true);
    for (auto w : mesh.vv_range(vh[i])) mesh.status(w).set_locked(true);
  }
  for (const Eigen::Vector3i& f : as_given)
    for (int k = 0; k < 3; ++k) mesh.status(vh[f[k]]).set_locked(true);

  using Decimater =
      SampledDecimaterT<Mesh, ModDisplayBoundT<Mesh>, OpenMesh::Decimater::ModQuadricT<Mesh>>;
  Decimater decimater(mesh);
  OpenMesh::Decimater::ModQuadricT<Mesh>::Handle quadric;
  OpenMesh::Decimater::ModNormalFlippingT<Mesh>::Handle flipping;
  ModDisplayBoundT<Mesh>::Handle bound;
  decimater.add(bound);
  decimater.add(flipping);
  decimater.add(quadric);
  decimater.module(quadric).unset_max_err();  // the order only; the bound decides
  decimater.module(flipping).set_max_normal_deviation(30.0);
  // The modules that can refuse go first: OpenMesh asks them in order and stops at a refusal.
  double distance = options.max_distance_mm, difference = options.max_value_difference;
  // A field that varies more over a vertex's neighbourhood than the bound (a scallop's texture)
  // cannot go down to the budget within it, and every round below costs a pass over the whole
  // mesh. The start: the median range of the values over the rings a vertex would be merged
  // with (its 1-ring, or its 2-ring when the budget keeps less than a quarter), on every 64th
  // vertex. The bounds met are the ones returned either way.
  {
    const double keep = static_cast<double>(options.max_vertices) / p.size();
    std::vector<double> range;
    std::vector<int> ring;
    for (size_t i = 0; i < p.size(); i += 64) {
      ring.assign(1, static_cast<int>(i));
      for (int depth = 0; depth < (keep < 0.25 ? 2 : 1); ++depth) {
        const size_t n = ring.size();
        for (size_t k = 0; k < n; ++k)
          for (auto w : mesh.vv_range(vh[ring[k]]))
            if (category[w.idx()] == category[i]) ring.push_back(w.idx());
      }
      double lo = value[i], hi = value[i];
      for (int v : ring) lo = std::min(lo, value[v]), hi = std::max(hi, value[v]);
      range.push_back(hi - lo);
    }
    if (!range.empty()) {
      std::nth_element(range.begin(), range.begin() + range.size() / 2, range.end());
      for (const double start = range[range.size() / 2]; difference < start; difference *= 2) {
        distance *= 2;
        out.relaxed = true;
      }
    }
  }
  decimater.module(bound).set(&p, &value, &category, distance, difference);
  if (!decimater.initialize()) throw std::logic_error("decimateForDisplay: decimater setup");
  // Only as far as the budget: the surface stays as sampled where it fits.
  const size_t budget = static_cast<size_t>(std::max(options.max_vertices, 3));
  auto kept = [&] {
    size_t n = 0;
    for (const auto& v : vh) n += !mesh.status(v).deleted();
    return n;
  };
  // decimate_to counts the deleted vertices OpenMesh keeps until garbage collection: the
  // collapses still wanted are counted here.
  DecimationProgress progress(options.progress, p.size() - budget);
  decimater.set_observer(&progress);
  // Multiple choices first, then the heap for what they leave (decimate(0) would go as far as
  // the bounds allow: not called for nothing).
  auto collapse = [&](size_t n, std::uint64_t seed) {
    decimater.sampled(n, decimater.module(bound), decimater.module(quadric), seed);
    progress.done_before = static_cast<double>(p.size() - kept());
    if (kept() > budget) decimater.decimate(kept() - budget);
  };
  const std::uint64_t seed = 0x746f6c766572ull ^ static_cast<std::uint64_t>(p.size());
  collapse(kept() - budget, seed);
  for (size_t left = kept(), round = 0; round < 12 && left > budget; ++round, left = kept()) {
    distance *= 2;
    difference *= 2;
    out.relaxed = true;
    decimater.module(bound).set(&p, &value, &category, distance, difference);
    progress.done_before = static_cast<double>(p.size() - left);
    collapse(left - budget, seed + round + 1);
  }
  decimater.set_observer(nullptr);
  out.max_distance_mm = distance;
  out.max_value_difference = difference;

  // Surviving vertices in their original order, then the faces.
  std::vector<int> index(p.size(), -1);
  for (size_t i = 0; i < p.size(); ++i)
    if (!mesh.status(vh[i]).deleted()) {
      index[i] = static_cast<int>(out.vertex.size());
      out.vertex.push_back(static_cast<int>(i));
    }
  out.faces.reserve(mesh.n_faces() + as_given.size());
  for (auto f : mesh.faces()) {
    if (mesh.status(f).deleted()) continue;
    Eigen::Vector3i t;
    int k = 0;
    for (auto v : mesh.fv_range(f)) t[k++] = index[v.idx()];
    out.faces.push_back(t);
  }
  for (const Eigen::Vector3i& f : as_given) {
    if (f[0] == f[1] || f[1] == f[2] || f[0] == f[2]) continue;  // no area: nothing to show
    out.faces.emplace_back(index[f[0]], index[f[1]], index[f[2]]);
    ++out.faces_kept_as_given;
  }
  return out;
}

}  // namespace

DecimatedMesh decimateForDisplay(const std::vector<Eigen::Vector3d>& p,
                                 const std::vector<Eigen::Vector3i>& faces,
                                 const std::vector<double>& value, const std::vector<int>& category,
                                 const std::vector<char>& locked, const DecimateOptions& options) {
  if (value.size() != p.size() || category.size() != p.size() || locked.size() != p.size())
    throw std::invalid_argument("decimateForDisplay: one value, category and lock per vertex");
  // Slabs along the longest axis, one per 100 000 vertices (at most 8), each decimated by its own
  // decimater to its share of the budget, the slabs in parallel; the faces across a seam are kept
  // as they are, their vertices locked. One piece: the whole mesh. Not one per core: a slab's
  // arrays then stay in cache, and eight slabs on two cores balance, so 1.06 M samples went down
  // to 120 000 in 2.0-2.1 s where two slabs took 2.7-3.0 s; and the mesh shown is the same on any
  // machine.
  const size_t n = p.size();
  const size_t budget = static_cast<size_t>(std::max(options.max_vertices, 3));
  const size_t automatic = std::clamp<size_t>(n / 100000, 1, 8);
  const size_t pieces = n <= budget          ? 1
                        : options.pieces > 0 ? static_cast<size_t>(options.pieces)
                                             : automatic;
  if (pieces == 1) return decimatePiece(p, faces, value, category, locked, options);
  Eigen::AlignedBox3d box;
  for (const Eigen::Vector3d& q : p) box.extend(q);
  int axis = 0;
  box.diagonal().maxCoeff(&axis);
  // Piece j: the vertices of ranks [first(j), first(j + 1)) along the axis (ties by index), rank
  // k's piece floor(k pieces / n); the ranks' boundaries selected, not the whole order sorted.
  std::vector<std::pair<double, int>> key(n);
  for (size_t i = 0; i < n; ++i) key[i] = {p[i][axis], static_cast<int>(i)};
  auto first = [&](size_t j) { return (j * n + pieces - 1) / pieces; };
  auto select = [&](auto&& self, size_t j0, size_t j1) -> void {  // the ranks of first(j0 .. j1)
    if (j1 - j0 < 2) return;
    const size_t jm = (j0 + j1) / 2;
    std::nth_element(key.begin() + first(j0), key.begin() + first(jm), key.begin() + first(j1));
    self(self, j0, jm);
    self(self, jm, j1);
  };
  select(select, 0, pieces);
  std::vector<int> piece_of(n);
  for (size_t j = 0; j < pieces; ++j)
    for (size_t k = first(j); k < first(j + 1); ++k) piece_of[key[k].second] = static_cast<int>(j);
  std::vector<char> lock(locked);
  std::vector<Eigen::Vector3i> seam;
  std::vector<std::vector<Eigen::Vector3i>> piece_faces(pieces);
  for (const Eigen::Vector3i& f : faces) {
    const int a = piece_of[f[0]];
    if (piece_of[f[1]] == a && piece_of[f[2]] == a) {
      piece_faces[a].push_back(f);
    } else {
      seam.push_back(f);
      for (int k = 0; k < 3; ++k) lock[f[k]] = 1;
    }
  }
  std::vector<std::vector<int>> global(pieces);  // each piece's vertices, ascending
  for (size_t i = 0; i < n; ++i) global[piece_of[i]].push_back(static_cast<int>(i));
  std::vector<int> local(n);
  for (const auto& g : global)
    for (size_t k = 0; k < g.size(); ++k) local[g[k]] = static_cast<int>(k);
  std::vector<DecimatedMesh> result(pieces);
  std::vector<std::atomic<double>> done(pieces);
  for (auto& d : done) d = 0;
  tbb::parallel_for(size_t(0), pieces, [&](size_t k) {
    const std::vector<int>& g = global[k];
    std::vector<Eigen::Vector3d> pk(g.size());
    std::vector<double> vk(g.size());
    std::vector<int> ck(g.size());
    std::vector<char> lk(g.size());
    for (size_t j = 0; j < g.size(); ++j) {
      pk[j] = p[g[j]];
      vk[j] = value[g[j]];
      ck[j] = category[g[j]];
      lk[j] = lock[g[j]];
    }
    std::vector<Eigen::Vector3i> fk;
    fk.reserve(piece_faces[k].size());
    for (const Eigen::Vector3i& f : piece_faces[k])
      fk.emplace_back(local[f[0]], local[f[1]], local[f[2]]);
    DecimateOptions o = options;
    o.max_vertices = static_cast<int>(budget * g.size() / n);
    o.progress = [&, k](double f) {
      done[k] = f;
      double mean = 0;
      for (const auto& d : done) mean += d;
      if (options.progress) options.progress(mean / static_cast<double>(pieces));
    };
    result[k] = decimatePiece(pk, fk, vk, ck, lk, o);
  });
  // The pieces' vertices in their original order, their faces, then the seam's.
  DecimatedMesh out;
  out.max_vertices = options.max_vertices;
  std::vector<int> index(n, -1);
  for (size_t k = 0; k < pieces; ++k)
    for (int v : result[k].vertex) index[global[k][v]] = 0;
  for (size_t i = 0; i < n; ++i)
    if (index[i] == 0) {
      index[i] = static_cast<int>(out.vertex.size());
      out.vertex.push_back(static_cast<int>(i));
    }
  for (size_t k = 0; k < pieces; ++k) {
    const DecimatedMesh& r = result[k];
    for (const Eigen::Vector3i& f : r.faces)
      out.faces.emplace_back(index[global[k][r.vertex[f[0]]]], index[global[k][r.vertex[f[1]]]],
                             index[global[k][r.vertex[f[2]]]]);
    out.max_distance_mm = std::max(out.max_distance_mm, r.max_distance_mm);
    out.max_value_difference = std::max(out.max_value_difference, r.max_value_difference);
    out.relaxed = out.relaxed || r.relaxed;
    out.faces_kept_as_given += r.faces_kept_as_given;
  }
  for (const Eigen::Vector3i& f : seam)
    if (f[0] != f[1] && f[1] != f[2] && f[0] != f[2])
      out.faces.emplace_back(index[f[0]], index[f[1]], index[f[2]]);
  return out;
}

DecimatedMesh coarseForDisplay(const std::vector<Eigen::Vector3d>& p,
                               const std::vector<Eigen::Vector3i>& faces,
                               const std::vector<Eigen::Vector3i>& given_faces,
                               const std::vector<int>& face_given, const std::vector<double>& value,
                               const std::vector<int>& category, const std::vector<char>& locked,
                               const DecimateOptions& options) {
  const size_t n = p.size(), ng = given_faces.size();
  if (ng == 0 || face_given.size() != faces.size() || value.size() != n || category.size() != n ||
      (!locked.empty() && locked.size() != n))
    return {};
  // Each given face's faces: [first[g], first[g + 1]) of `order` (a counting sort).
  std::vector<int> first(ng + 1, 0), order(faces.size());
  for (const int g : face_given) {
    if (g < 0 || g >= static_cast<int>(ng)) return {};
    ++first[g + 1];
  }
  for (size_t g = 0; g < ng; ++g) first[g + 1] += first[g];
  {
    std::vector<int> fill(first.begin(), first.end() - 1);
    for (size_t f = 0; f < faces.size(); ++f) order[fill[face_given[f]]++] = static_cast<int>(f);
  }
  // Whether each given face carries the map.
  std::vector<char> whole(ng, 0);
  const double dmax = options.max_distance_mm, vmax = options.max_value_difference;
  tbb::parallel_for(
      tbb::blocked_range<size_t>(0, ng, 256), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t g = r.begin(); g != r.end(); ++g) {
          const Eigen::Vector3i& c = given_faces[g];
          if ((c.array() < 0).any() || (c.array() >= static_cast<int>(n)).any()) continue;
          if (category[c[0]] != category[c[1]] || category[c[0]] != category[c[2]]) continue;
          const Eigen::Vector3d& a = p[c[0]];
          const Eigen::Vector3d e1 = p[c[1]] - a, e2 = p[c[2]] - a;
          const Eigen::Vector3d normal = e1.cross(e2);
          const double area2 = normal.squaredNorm();
          if (!(area2 > 1e-24 * std::max(e1.squaredNorm(), e2.squaredNorm()))) continue;  // no area
          const Eigen::Vector3d unit = normal / std::sqrt(area2);
          bool ok = true;
          for (int q = first[g]; q < first[g + 1] && ok; ++q)
            for (int k = 0; k < 3 && ok; ++k) {
              const int i = faces[order[q]][k];
              const Eigen::Vector3d d = p[i] - a;
              // Barycentric weights of the point's projection (Ericson 3.4), its distance off the
              // plane.
              const double w1 = d.cross(e2).dot(normal) / area2,
                           w2 = e1.cross(d).dot(normal) / area2;
              const double w0 = 1.0 - w1 - w2;
              const double inside = 1e-9;
              ok = category[i] == category[c[0]] && std::abs(d.dot(unit)) <= dmax &&
                   w0 >= -inside && w1 >= -inside && w2 >= -inside &&
                   std::abs(w0 * value[c[0]] + w1 * value[c[1]] + w2 * value[c[2]] - value[i]) <=
                       vmax;
            }
          whole[g] = ok;
        }
      });
  // The given faces drawn as they are; the rest, as sampled, decimated to what the budget
  // leaves (their own mesh: the samples they use; its border, where it meets a given face drawn
  // whole, stays).
  const size_t budget = static_cast<size_t>(std::max(options.max_vertices, 3));
  std::vector<Eigen::Vector3i> given, rest;
  for (size_t g = 0; g < ng; ++g) {
    if (whole[g]) {
      given.push_back(given_faces[g]);
      continue;
    }
    for (int q = first[g]; q < first[g + 1]; ++q) rest.push_back(faces[order[q]]);
  }
  std::vector<int> local(n, -1);
  std::vector<int> rest_vertex;  // the rest's samples, ascending
  for (const Eigen::Vector3i& f : rest)
    for (int k = 0; k < 3; ++k) local[f[k]] = 0;
  for (size_t i = 0; i < n; ++i)
    if (local[i] == 0) {
      local[i] = static_cast<int>(rest_vertex.size());
      rest_vertex.push_back(static_cast<int>(i));
    }
  std::vector<char> used(n, 0);
  size_t given_only = 0;  // samples of the given faces drawn whole and of no other face
  for (const Eigen::Vector3i& f : given)
    for (int k = 0; k < 3; ++k)
      if (local[f[k]] < 0 && !used[f[k]]) used[f[k]] = 1, ++given_only;
  // At most half of the budget for the faces drawn whole: the rest keeps at least the other half
  // (a part given as fine as the spacing is decimated whole, as before).
  if (2 * given_only > budget) return {};
  DecimatedMesh rest_mesh;
  if (!rest.empty()) {
    std::vector<Eigen::Vector3d> pk(rest_vertex.size());
    std::vector<double> vk(rest_vertex.size());
    std::vector<int> ck(rest_vertex.size());
    std::vector<char> lk(rest_vertex.size());
    for (size_t j = 0; j < rest_vertex.size(); ++j) {
      const int i = rest_vertex[j];
      pk[j] = p[i];
      vk[j] = value[i];
      ck[j] = category[i];
      lk[j] = locked.empty() ? 0 : locked[i];
    }
    for (Eigen::Vector3i& f : rest) f = Eigen::Vector3i(local[f[0]], local[f[1]], local[f[2]]);
    DecimateOptions o = options;
    o.max_vertices = static_cast<int>(budget - given_only);
    rest_mesh = decimateForDisplay(pk, rest, vk, ck, lk, o);
  }
  // The samples used, in their order, and the faces in them.
  DecimatedMesh out;
  out.max_vertices = options.max_vertices;
  for (const int j : rest_mesh.vertex) used[rest_vertex[j]] = 1;
  for (const Eigen::Vector3i& f : given)  // on the rest's border, which stays: and in any case
    for (int k = 0; k < 3; ++k) used[f[k]] = 1;
  std::vector<int> index(n, -1);
  for (size_t i = 0; i < n; ++i)
    if (used[i]) {
      index[i] = static_cast<int>(out.vertex.size());
      out.vertex.push_back(static_cast<int>(i));
    }
  out.faces.reserve(given.size() + rest_mesh.faces.size());
  for (const Eigen::Vector3i& f : given)
    out.faces.emplace_back(index[f[0]], index[f[1]], index[f[2]]);
  for (const Eigen::Vector3i& f : rest_mesh.faces) {
    Eigen::Vector3i t;
    for (int k = 0; k < 3; ++k) t[k] = index[rest_vertex[rest_mesh.vertex[f[k]]]];
    out.faces.push_back(t);
  }
  out.given_faces_drawn = static_cast<int>(given.size());
  out.max_distance_mm = std::max(dmax, rest_mesh.max_distance_mm);
  out.max_value_difference = std::max(vmax, rest_mesh.max_value_difference);
  out.relaxed = rest_mesh.relaxed;
  out.faces_kept_as_given = rest_mesh.faces_kept_as_given;
  return out;
}

}  // namespace tolver
