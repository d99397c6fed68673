#include "geometry/triangle_mesh.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdint>

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
  const double target_vertices = mesh.area() / (std::sqrt(3.0) / 2.0 * spacing * spacing);
  if (static_cast<double>(mesh.vertices.size()) < 0.5 * target_vertices)
    resampleFaces(&mesh, spacing);
  else
    refineMesh(&mesh, spacing);
  const int nv = static_cast<int>(mesh.vertices.size());
  const int nf = static_cast<int>(mesh.faces.size());
  std::vector<Eigen::Vector3d> fn(nf);
  std::vector<double> fa(nf);
  for (int f = 0; f < nf; ++f) {
    // A face with no area to the last few digits (a refined face's points along one input edge)
    // has no normal: its angle at the middle point is pi, and its rounding noise must not vote.
    const Eigen::Vector3i& t = mesh.faces[f];
    const Eigen::Vector3d e1 = mesh.vertices[t[1]] - mesh.vertices[t[0]];
    const Eigen::Vector3d e2 = mesh.vertices[t[2]] - mesh.vertices[t[0]];
    const Eigen::Vector3d n = e1.cross(e2);
    const double scale2 = std::max({e1.squaredNorm(), e2.squaredNorm(), (e2 - e1).squaredNorm()});
    const double len = n.norm();
    fn[f] = len > 1e-10 * scale2 ? Eigen::Vector3d(n / len) : Eigen::Vector3d::Zero();
    fa[f] = 0.5 * len;
  }
  // Faces around each vertex (CSR).
  std::vector<int> start(nv + 1, 0), around(3 * nf);
  for (const auto& t : mesh.faces)
    for (int k = 0; k < 3; ++k) ++start[t[k] + 1];
  for (int v = 0; v < nv; ++v) start[v + 1] += start[v];
  std::vector<int> fill(start.begin(), start.end() - 1);
  for (int f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) around[fill[mesh.faces[f][k]]++] = f;

  const double cos_feature = std::cos(feature_angle);
  SurfaceSamples s;
  s.group_names = mesh.group_names;
  s.group_aliases = mesh.group_aliases;
  s.faces = mesh.faces;
  s.face_group = mesh.face_group;
  std::vector<Eigen::Vector3d> cluster_ref;
  std::vector<int> cluster_sample;
  for (int v = 0; v < nv; ++v) {
    cluster_ref.clear();
    cluster_sample.clear();
    for (int i = start[v]; i < start[v + 1]; ++i) {
      const int f = around[i];
      int c = 0;
      for (; c < static_cast<int>(cluster_ref.size()); ++c)
        if (fn[f].dot(cluster_ref[c]) >= cos_feature || fn[f].isZero()) break;
      if (c == static_cast<int>(cluster_ref.size())) {
        cluster_ref.push_back(fn[f].isZero() ? Eigen::Vector3d(Eigen::Vector3d::UnitZ()) : fn[f]);
        cluster_sample.push_back(static_cast<int>(s.p_w.size()));
        s.p_w.push_back(mesh.vertices[v]);
        s.n_w.push_back(Eigen::Vector3d::Zero());
        s.area.push_back(0.0);
        s.group.push_back(mesh.face_group[f]);
      }
      const int si = cluster_sample[c];
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
  }
  // Samples on sharp edges (a vertex split in several) and on borders.
  s.on_edge.assign(s.p_w.size(), 0);
  {
    // A border edge (v, u) is in one face only: u is then once among the corners next to v in
    // v's faces (twice for an edge inside the surface).
    std::vector<char> border(nv, 0);
    std::vector<int> ring;
    for (int v = 0; v < nv; ++v) {
      ring.clear();
      for (int i = start[v]; i < start[v + 1]; ++i) {
        const Eigen::Vector3i& t = mesh.faces[around[i]];
        const int k = t[0] == v ? 0 : (t[1] == v ? 1 : 2);
        ring.push_back(t[(k + 1) % 3]);
        ring.push_back(t[(k + 2) % 3]);
      }
      std::sort(ring.begin(), ring.end());
      for (size_t i = 0; i < ring.size();) {
        size_t j = i + 1;
        while (j < ring.size() && ring[j] == ring[i]) ++j;
        if (j - i == 1) border[v] = border[ring[i]] = 1;
        i = j;
      }
    }
    for (int f = 0; f < nf; ++f)
      for (int k = 0; k < 3; ++k) {
        const int v = mesh.faces[f][k];
        if (border[v]) s.on_edge[s.faces[f][k]] = 1;
      }
    // A vertex that produced more than one sample lies on a sharp edge.
    std::vector<int> first_sample(nv, -1);
    for (int f = 0; f < nf; ++f)
      for (int k = 0; k < 3; ++k) {
        const int v = mesh.faces[f][k], si = s.faces[f][k];
        if (first_sample[v] < 0)
          first_sample[v] = si;
        else if (first_sample[v] != si)
          s.on_edge[si] = s.on_edge[first_sample[v]] = 1;
      }
  }
  for (auto& n : s.n_w) {
    const double len = n.norm();
    n = len > 0 ? Eigen::Vector3d(n / len) : Eigen::Vector3d::UnitZ();
  }
  return s;
}

}  // namespace tolver
