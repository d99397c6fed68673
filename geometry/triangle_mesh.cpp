#include "geometry/triangle_mesh.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

namespace tolver {

double TriangleMesh::faceArea(int f) const {
  const Eigen::Vector3i& t = faces[f];
  return 0.5 * (vertices[t[1]] - vertices[t[0]]).cross(vertices[t[2]] - vertices[t[0]]).norm();
}

Eigen::Vector3d TriangleMesh::faceNormal(int f) const {
  const Eigen::Vector3i& t = faces[f];
  const Eigen::Vector3d n =
      (vertices[t[1]] - vertices[t[0]]).cross(vertices[t[2]] - vertices[t[0]]);
  const double len = n.norm();
  return len > 0 ? Eigen::Vector3d(n / len) : Eigen::Vector3d::Zero();
}

double TriangleMesh::area() const {
  double a = 0;
  for (int f = 0; f < static_cast<int>(faces.size()); ++f) a += faceArea(f);
  return a;
}

SurfaceSamples sampleSurface(const TriangleMesh& input, double spacing, double feature_angle) {
  TriangleMesh mesh = input;
  mesh.given_faces.clear();  // resampleFaces' own, below
  mesh.face_given.clear();
  const double target_vertices = mesh.area() / (std::sqrt(3.0) / 2.0 * spacing * spacing);
  if (static_cast<double>(mesh.vertices.size()) < 0.5 * target_vertices)
    resampleFaces(&mesh, spacing);
  else
    refineMesh(&mesh, spacing);
  const int nv = static_cast<int>(mesh.vertices.size());
  const int nf = static_cast<int>(mesh.faces.size());
  // In parallel over faces, then over vertices: each vertex's samples are its own (numbered by a
  // prefix sum of their counts), so the samples and their order are those of a loop over the
  // vertices in turn.
  std::vector<Eigen::Vector3d> fn(nf);
  std::vector<double> fa(nf);
  tbb::parallel_for(tbb::blocked_range<int>(0, nf, 4096), [&](const tbb::blocked_range<int>& r) {
    for (int f = r.begin(); f != r.end(); ++f) {
      // A face with no area to the last few digits (a refined face's points along one input
      // edge) has no normal: its angle at the middle point is pi, and its rounding noise must not
      // vote.
      const Eigen::Vector3i& t = mesh.faces[f];
      const Eigen::Vector3d e1 = mesh.vertices[t[1]] - mesh.vertices[t[0]];
      const Eigen::Vector3d e2 = mesh.vertices[t[2]] - mesh.vertices[t[0]];
      const Eigen::Vector3d n = e1.cross(e2);
      const double scale2 = std::max({e1.squaredNorm(), e2.squaredNorm(), (e2 - e1).squaredNorm()});
      const double len = n.norm();
      fn[f] = len > 1e-10 * scale2 ? Eigen::Vector3d(n / len) : Eigen::Vector3d::Zero();
      fa[f] = 0.5 * len;
    }
  });
  // Faces around each vertex (CSR).
  std::vector<int> start(nv + 1, 0), around(3 * nf);
  for (const auto& t : mesh.faces)
    for (int k = 0; k < 3; ++k) ++start[t[k] + 1];
  for (int v = 0; v < nv; ++v) start[v + 1] += start[v];
  {
    std::vector<int> fill(start.begin(), start.end() - 1);
    for (int f = 0; f < nf; ++f)
      for (int k = 0; k < 3; ++k) around[fill[mesh.faces[f][k]]++] = f;
  }

  // A vertex's faces in clusters of normals within the feature angle of the cluster's first
  // (a face of no normal joins the first): one sample per cluster. cluster[i]: the cluster of
  // the face around[i] at its vertex; first[v]: v's first sample.
  const double cos_feature = std::cos(feature_angle);
  std::vector<int> cluster(around.size()), first(nv + 1, 0);
  tbb::parallel_for(tbb::blocked_range<int>(0, nv, 4096), [&](const tbb::blocked_range<int>& r) {
    std::vector<Eigen::Vector3d> ref;
    for (int v = r.begin(); v != r.end(); ++v) {
      ref.clear();
      for (int i = start[v]; i < start[v + 1]; ++i) {
        const int f = around[i];
        int c = 0;
        for (; c < static_cast<int>(ref.size()); ++c)
          if (fn[f].dot(ref[c]) >= cos_feature || fn[f].isZero()) break;
        if (c == static_cast<int>(ref.size()))
          ref.push_back(fn[f].isZero() ? Eigen::Vector3d(Eigen::Vector3d::UnitZ()) : fn[f]);
        cluster[i] = c;
      }
      first[v + 1] = static_cast<int>(ref.size());
    }
  });
  for (int v = 0; v < nv; ++v) first[v + 1] += first[v];
  const int ns = first[nv];

  SurfaceSamples s;
  s.group_names = mesh.group_names;
  s.group_aliases = mesh.group_aliases;
  s.faces = mesh.faces;
  s.face_group = mesh.face_group;
  s.p_w.resize(ns);
  s.n_w.assign(ns, Eigen::Vector3d::Zero());
  s.area.assign(ns, 0.0);
  s.group.resize(ns);
  s.on_edge.assign(ns, 0);
  tbb::parallel_for(tbb::blocked_range<int>(0, nv, 4096), [&](const tbb::blocked_range<int>& r) {
    std::vector<int> ring;
    for (int v = r.begin(); v != r.end(); ++v) {
      int made = 0;  // clusters are numbered in the order of their first faces
      for (int i = start[v]; i < start[v + 1]; ++i) {
        const int f = around[i];
        const int si = first[v] + cluster[i];
        if (cluster[i] == made) {  // the cluster's first face
          s.p_w[si] = mesh.vertices[v];
          s.group[si] = mesh.face_group[f];
          ++made;
        }
        // Angle-weighted normal (the angle of face f at v).
        const Eigen::Vector3i& t = mesh.faces[f];
        const int k = t[0] == v ? 0 : (t[1] == v ? 1 : 2);
        const Eigen::Vector3d e1 = mesh.vertices[t[(k + 1) % 3]] - mesh.vertices[v];
        const Eigen::Vector3d e2 = mesh.vertices[t[(k + 2) % 3]] - mesh.vertices[v];
        const double angle = std::atan2(e1.cross(e2).norm(), e1.dot(e2));
        s.n_w[si] += angle * fn[f];
        s.area[si] += fa[f] / 3.0;
        s.faces[f][k] = si;
      }
      // On a sharp edge: a vertex split in several samples.
      if (first[v + 1] - first[v] > 1)
        for (int si = first[v]; si < first[v + 1]; ++si) s.on_edge[si] = 1;
      // On a border: an edge (v, u) in one face only, u then once among the corners next to v in
      // v's faces (twice for an edge inside the surface); the edge's other end finds it the same
      // way from its own faces. Every sample of v is then on the border.
      ring.clear();
      for (int i = start[v]; i < start[v + 1]; ++i) {
        const Eigen::Vector3i& t = mesh.faces[around[i]];
        const int k = t[0] == v ? 0 : (t[1] == v ? 1 : 2);
        ring.push_back(t[(k + 1) % 3]);
        ring.push_back(t[(k + 2) % 3]);
      }
      std::sort(ring.begin(), ring.end());
      bool border = false;
      for (size_t i = 0; i < ring.size() && !border;) {
        size_t j = i + 1;
        while (j < ring.size() && ring[j] == ring[i]) ++j;
        border = j - i == 1;
        i = j;
      }
      if (border)
        for (int si = first[v]; si < first[v + 1]; ++si) s.on_edge[si] = 1;
      for (int si = first[v]; si < first[v + 1]; ++si) {
        Eigen::Vector3d& n = s.n_w[si];
        const double len = n.norm();
        n = len > 0 ? Eigen::Vector3d(n / len) : Eigen::Vector3d::UnitZ();
      }
    }
  });
  // The given faces in samples: a corner's sample is the one its re-triangulated faces use there.
  if (!mesh.given_faces.empty() && mesh.face_given.size() == mesh.faces.size()) {
    s.given_faces.assign(mesh.given_faces.size(), Eigen::Vector3i::Constant(-1));
    for (int f = 0; f < nf; ++f) {
      const int g = mesh.face_given[f];
      for (int k = 0; k < 3; ++k)
        for (int j = 0; j < 3; ++j)
          if (mesh.faces[f][k] == mesh.given_faces[g][j]) s.given_faces[g][j] = s.faces[f][k];
    }
    s.face_given = mesh.face_given;
  }
  return s;
}

}  // namespace tolver
