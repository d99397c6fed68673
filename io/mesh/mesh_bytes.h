#pragma once
// A TriangleMesh through a byte buffer (io/common/child_process.h): the child process that read
// a part file sends its mesh to tolver this way.
#include <cstdint>

#include "geometry/triangle_mesh.h"
#include "io/common/child_process.h"

namespace tolver {

inline void putMesh(ByteWriter& w, const TriangleMesh& m) {
  w.put<uint64_t>(m.vertices.size());
  w.putBytes(m.vertices.data(), m.vertices.size() * sizeof(Eigen::Vector3d));
  w.put<uint64_t>(m.faces.size());
  w.putBytes(m.faces.data(), m.faces.size() * sizeof(Eigen::Vector3i));
  w.putBytes(m.face_group.data(), m.face_group.size() * sizeof(int));
  w.put<uint64_t>(m.group_names.size());
  for (const std::string& g : m.group_names) w.putString(g);
  w.put<uint64_t>(m.group_aliases.size());
  for (const auto& a : m.group_aliases) {
    w.put<uint64_t>(a.size());
    for (const std::string& s : a) w.putString(s);
  }
}

inline bool takeMesh(ByteReader& r, TriangleMesh* m) {
  uint64_t n = 0;
  if (!r.takeCount(&n, sizeof(Eigen::Vector3d))) return false;
  m->vertices.resize(n);
  if (!r.takeBytes(m->vertices.data(), n * sizeof(Eigen::Vector3d))) return false;
  if (!r.takeCount(&n, sizeof(Eigen::Vector3i) + sizeof(int))) return false;
  m->faces.resize(n);
  m->face_group.resize(n);
  if (!r.takeBytes(m->faces.data(), n * sizeof(Eigen::Vector3i)) ||
      !r.takeBytes(m->face_group.data(), n * sizeof(int)) || !r.takeCount(&n, 8))
    return false;
  m->group_names.resize(n);
  for (std::string& g : m->group_names)
    if (!r.takeString(&g)) return false;
  if (!r.takeCount(&n, 8)) return false;
  m->group_aliases.resize(n);
  for (auto& a : m->group_aliases) {
    uint64_t k = 0;
    if (!r.takeCount(&k, 8)) return false;
    a.resize(k);
    for (std::string& s : a)
      if (!r.takeString(&s)) return false;
  }
  return true;
}

}  // namespace tolver
