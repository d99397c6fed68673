#include "geometry/triangle_mesh.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <unordered_map>

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

void refineMesh(TriangleMesh* mesh, double max_edge) {
  if (!(max_edge > 0)) return;
  const double limit2 = max_edge * max_edge;
  auto& V = mesh->vertices;
  for (int pass = 0; pass < 64; ++pass) {
    std::unordered_map<uint64_t, int> mid;
    auto key = [](int a, int b) {
      return (static_cast<uint64_t>(std::min(a, b)) << 32) | static_cast<uint32_t>(std::max(a, b));
    };
    auto midpoint = [&](int a, int b) -> int {
      if ((V[a] - V[b]).squaredNorm() <= limit2) return -1;
      auto [it, fresh] = mid.try_emplace(key(a, b), static_cast<int>(V.size()));
      if (fresh) V.push_back(0.5 * (V[a] + V[b]));
      return it->second;
    };
    std::vector<Eigen::Vector3i> faces;
    std::vector<int> groups;
    faces.reserve(mesh->faces.size() * 2);
    groups.reserve(mesh->faces.size() * 2);
    bool split = false;
    for (size_t f = 0; f < mesh->faces.size(); ++f) {
      const Eigen::Vector3i t = mesh->faces[f];
      const int g = mesh->face_group[f];
      int m[3];
      int count = 0;
      for (int e = 0; e < 3; ++e) count += (m[e] = midpoint(t[e], t[(e + 1) % 3])) >= 0;
      auto add = [&](int a, int b, int c) {
        faces.emplace_back(a, b, c);
        groups.push_back(g);
      };
      if (count == 0) {
        add(t[0], t[1], t[2]);
        continue;
      }
      split = true;
      if (count == 3) {
        add(t[0], m[0], m[2]);
        add(m[0], t[1], m[1]);
        add(m[2], m[1], t[2]);
        add(m[0], m[1], m[2]);
        continue;
      }
      // Rotate so that edge 0 (t0-t1) is split and, with two splits, edge 1 (t1-t2) too.
      int r = 0;
      if (count == 1) {
        while (m[r] < 0) ++r;
      } else {
        while (!(m[r] >= 0 && m[(r + 1) % 3] >= 0)) ++r;
      }
      const int a = t[r], b = t[(r + 1) % 3], c = t[(r + 2) % 3];
      const int mab = m[r], mbc = m[(r + 1) % 3];
      if (count == 1) {
        add(a, mab, c);
        add(mab, b, c);
      } else {
        add(mab, b, mbc);
        // Quad a, mab, mbc, c: cut along the shorter diagonal.
        if ((V[a] - V[mbc]).squaredNorm() <= (V[mab] - V[c]).squaredNorm()) {
          add(a, mab, mbc);
          add(a, mbc, c);
        } else {
          add(a, mab, c);
          add(mab, mbc, c);
        }
      }
    }
    mesh->faces.swap(faces);
    mesh->face_group.swap(groups);
    if (!split) return;
  }
}

SurfaceSamples sampleSurface(const TriangleMesh& input, double spacing, double feature_angle) {
  TriangleMesh mesh = input;
  refineMesh(&mesh, spacing);
  const int nv = static_cast<int>(mesh.vertices.size());
  const int nf = static_cast<int>(mesh.faces.size());
  std::vector<Eigen::Vector3d> fn(nf);
  std::vector<double> fa(nf);
  for (int f = 0; f < nf; ++f) {
    fn[f] = mesh.faceNormal(f);
    fa[f] = mesh.faceArea(f);
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
  for (auto& n : s.n_w) {
    const double len = n.norm();
    n = len > 0 ? Eigen::Vector3d(n / len) : Eigen::Vector3d::UnitZ();
  }
  return s;
}

}  // namespace tolver
