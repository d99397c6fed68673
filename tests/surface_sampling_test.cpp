// Surface sampling: the faces re-triangulated at the spacing (resampleFaces) against the input's
// own geometry (area, enclosed volume, every point on an input face, a closed mesh staying
// closed), the spacing reached, determinism, and no regular grid.
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <map>
#include <utility>

#include "geometry/triangle_mesh.h"

namespace tolver {
namespace {

// A cube of side a, each side fanned from its centre to n points along each of its edges: long
// thin triangles, as CAD systems write, and a closed conforming mesh (one group per side).
TriangleMesh fannedCube(double a, int n) {
  TriangleMesh m;
  for (int s = 0; s < 6; ++s) m.group_names.push_back("side" + std::to_string(s));
  std::map<std::tuple<long, long, long>, int> index;
  auto vertex = [&](const Eigen::Vector3d& p) {
    const auto key = std::make_tuple(std::lround(p.x() * 1e6), std::lround(p.y() * 1e6),
                                     std::lround(p.z() * 1e6));
    const auto [it, inserted] = index.try_emplace(key, static_cast<int>(m.vertices.size()));
    if (inserted) m.vertices.push_back(p);
    return it->second;
  };
  for (int axis = 0; axis < 3; ++axis)
    for (int side = 0; side < 2; ++side) {
      // Corner c, edge directions d1, d2 with d1 x d2 outward.
      Eigen::Vector3d out = Eigen::Vector3d::Zero();
      out[axis] = side ? 1 : -1;
      Eigen::Vector3d d1 = Eigen::Vector3d::Zero(), d2 = Eigen::Vector3d::Zero();
      d1[(axis + 1) % 3] = a;
      d2[(axis + 2) % 3] = a;
      if (d1.cross(d2).dot(out) < 0) std::swap(d1, d2);
      Eigen::Vector3d c = Eigen::Vector3d::Zero();
      c[axis] = side ? a : 0;
      // The boundary, counter-clockwise seen from outside: c -> c + d1 -> c + d1 + d2 -> c + d2.
      const Eigen::Vector3d corner[4] = {c, c + d1, c + d1 + d2, c + d2};
      std::vector<int> ring;
      for (int k = 0; k < 4; ++k)
        for (int i = 0; i < n; ++i)
          ring.push_back(vertex(corner[k] + (double(i) / n) * (corner[(k + 1) % 4] - corner[k])));
      const int centre = vertex(c + 0.5 * (d1 + d2));
      for (size_t i = 0; i < ring.size(); ++i) {
        m.faces.emplace_back(centre, ring[i], ring[(i + 1) % ring.size()]);
        m.face_group.push_back(2 * axis + side);
      }
    }
  return m;
}

double volume(const TriangleMesh& m) {
  double v = 0;
  for (const auto& t : m.faces)
    v += m.vertices[t[0]].dot(m.vertices[t[1]].cross(m.vertices[t[2]])) / 6.0;
  return v;
}

double distanceToTriangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                          const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  // Inside the prism over the triangle: the plane distance; else the nearest edge.
  const Eigen::Vector3d n = (b - a).cross(c - a).normalized();
  const Eigen::Vector3d q = p - n.dot(p - a) * n;
  const bool inside = (b - a).cross(q - a).dot(n) >= 0 && (c - b).cross(q - b).dot(n) >= 0 &&
                      (a - c).cross(q - c).dot(n) >= 0;
  if (inside) return std::abs(n.dot(p - a));
  auto seg = [&](const Eigen::Vector3d& u, const Eigen::Vector3d& v) {
    const double t = std::clamp((p - u).dot(v - u) / (v - u).squaredNorm(), 0.0, 1.0);
    return (p - (u + t * (v - u))).norm();
  };
  return std::min({seg(a, b), seg(b, c), seg(c, a)});
}

TEST(ResampleFaces, KeepsTheGeometryAndStaysClosed) {
  const TriangleMesh in = fannedCube(20.0, 16);
  EXPECT_NEAR(volume(in), 8000.0, 1e-9);
  TriangleMesh out = in;
  const double h = 0.5;
  resampleFaces(&out, h);
  ASSERT_GT(out.faces.size(), 10 * in.faces.size());
  EXPECT_NEAR(out.area(), in.area(), 1e-9 * in.area());
  EXPECT_NEAR(volume(out), volume(in), 1e-9 * volume(in));  // also: no face turned over
  // Closed: every edge between exactly two faces, once each way.
  std::map<std::pair<int, int>, int> directed;
  for (const auto& t : out.faces)
    for (int k = 0; k < 3; ++k) ++directed[{t[k], t[(k + 1) % 3]}];
  for (const auto& [e, count] : directed) {
    ASSERT_EQ(count, 1) << e.first << "-" << e.second;
    ASSERT_EQ(directed.count({e.second, e.first}), 1u)
        << "open edge " << e.first << "-" << e.second;
  }
  // Every point on an input face of its own group.
  for (size_t f = 0; f < out.faces.size(); f += 7) {
    const int g = out.face_group[f];
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d& p = out.vertices[out.faces[f][k]];
      double d = 1e9;
      for (size_t i = 0; i < in.faces.size(); ++i)
        if (in.face_group[i] == g)
          d = std::min(
              d, distanceToTriangle(p, in.vertices[in.faces[i][0]], in.vertices[in.faces[i][1]],
                                    in.vertices[in.faces[i][2]]));
      ASSERT_LT(d, 1e-9) << "face " << f;
    }
  }
}

TEST(ResampleFaces, ReachesTheSpacingOnLongThinTriangles) {
  const TriangleMesh in = fannedCube(20.0, 16);  // slivers 10 mm high on 1.25 mm
  const double h = 0.5;
  TriangleMesh out = in;
  resampleFaces(&out, h);
  std::vector<double> edges;
  for (const auto& t : out.faces)
    for (int k = 0; k < 3; ++k)
      edges.push_back((out.vertices[t[k]] - out.vertices[t[(k + 1) % 3]]).norm());
  std::sort(edges.begin(), edges.end());
  const double median = edges[edges.size() / 2];
  EXPECT_GT(median, 0.8 * h);
  EXPECT_LT(median, 1.25 * h);
  EXPECT_LT(edges.back(), 2.5 * h);
  // About the vertices of equilateral triangles of side h over the area (an isotropic mesh):
  // splitting edges alone made 4.7 times as many on such slivers.
  const double ideal = in.area() / (std::sqrt(3.0) / 2.0 * h * h);
  EXPECT_GT(out.vertices.size(), 0.8 * ideal);
  EXPECT_LT(out.vertices.size(), 1.25 * ideal);
}

TEST(ResampleFaces, IsTheSameOnOneThreadAsOnMany) {
  const TriangleMesh in = fannedCube(10.0, 5);
  TriangleMesh many = in, one = in;
  resampleFaces(&many, 0.3);
  {
    tbb::global_control single(tbb::global_control::max_allowed_parallelism, 1);
    resampleFaces(&one, 0.3);
  }
  ASSERT_EQ(one.vertices.size(), many.vertices.size());
  ASSERT_EQ(one.faces.size(), many.faces.size());
  for (size_t i = 0; i < one.vertices.size(); ++i)
    ASSERT_EQ(one.vertices[i], many.vertices[i]) << i;
  for (size_t i = 0; i < one.faces.size(); ++i) ASSERT_EQ(one.faces[i], many.faces[i]) << i;
  EXPECT_EQ(one.face_group, many.face_group);
}

TEST(ResampleFaces, KeepsAFaceWithNoAreaConforming) {
  // Two triangles on a square, and a third with collinear corners on its diagonal's side.
  TriangleMesh m;
  m.group_names = {"all"};
  m.vertices = {{0, 0, 0}, {10, 0, 0}, {10, 10, 0}, {0, 10, 0}, {5, 0, 0}};
  m.faces = {{0, 4, 2}, {4, 1, 2}, {2, 3, 0}, {0, 4, 1}};  // the last: no area, on the edge y = 0
  m.face_group = {0, 0, 0, 0};
  resampleFaces(&m, 1.0);
  for (const auto& v : m.vertices) ASSERT_TRUE(v.allFinite());
  std::map<std::pair<int, int>, int> undirected;
  for (const auto& t : m.faces)
    for (int k = 0; k < 3; ++k) ++undirected[std::minmax(t[k], t[(k + 1) % 3])];
  // The y = 0 edge is seen by the two faces above it and by the flat one (once or twice); no
  // edge of the square's inside is seen once (a crack).
  for (const auto& [e, count] : undirected) {
    const Eigen::Vector3d a = m.vertices[e.first], b = m.vertices[e.second];
    const bool on_border = (a.y() == 0 && b.y() == 0) || (a.x() == 10 && b.x() == 10) ||
                           (a.y() == 10 && b.y() == 10) || (a.x() == 0 && b.x() == 0);
    if (!on_border) EXPECT_EQ(count, 2) << a.transpose() << " - " << b.transpose();
  }
  EXPECT_NEAR(m.area(), 100.0, 1e-9);
}

// A regular lattice aliases with regular marks on the part (scallops at a step-over): one large
// face, sampled at 0.5 mm, its lattice rows 0.433 mm apart (parallel to its first edge, y = 0),
// and f(y) = sin^2(pi y / 0.433 mm), zero on every row. The samples' area-weighted mean of f is
// about 0.03 for the regular lattice (only the edge points see f); the jittered one must see
// a good part of f's mean of 1/2 (about 0.32 for a jitter of 0.3 spacing).
TEST(SampleSurface, SamplesAreNoRegularGrid) {
  TriangleMesh m;
  m.group_names = {"plane"};
  m.vertices = {{0, 0, 0}, {40, 0, 0}, {40, 40, 0}};
  m.faces = {{0, 1, 2}};
  m.face_group = {0};
  const double h = 0.5, row = h * std::sqrt(3.0) / 2.0;
  const SurfaceSamples s = sampleSurface(m, h);
  double sum = 0, w = 0;
  for (size_t i = 0; i < s.size(); ++i) {
    const double f = std::pow(std::sin(M_PI * s.p_w[i].y() / row), 2);
    sum += s.area[i] * f;
    w += s.area[i];
  }
  EXPECT_NEAR(w, 800.0, 1e-9 * 800.0);
  EXPECT_GT(sum / w, 0.2);
  EXPECT_LT(sum / w, 0.5);
}

// Samples on sharp edges and borders are marked (not verified), and only they: on the cube,
// the samples with two coordinates on a side's plane; on one open triangle, those on its sides.
TEST(SampleSurface, MarksTheSamplesOnSharpEdgesAndBorders) {
  const double a = 20.0;
  const SurfaceSamples cube = sampleSurface(fannedCube(a, 16), 0.5);
  int marked = 0;
  for (size_t i = 0; i < cube.size(); ++i) {
    int on = 0;
    for (int k = 0; k < 3; ++k)
      on += std::abs(cube.p_w[i][k]) < 1e-9 || std::abs(cube.p_w[i][k] - a) < 1e-9;
    ASSERT_EQ(cube.on_edge[i] != 0, on >= 2) << cube.p_w[i].transpose();
    marked += cube.on_edge[i];
  }
  EXPECT_GE(
      marked,
      12 * 31 * 2);  // each of the 12 edges in 16 input pieces, each cut in two; a sample per side
  TriangleMesh m;
  m.group_names = {"plane"};
  m.vertices = {{0, 0, 0}, {10, 0, 0}, {0, 10, 0}};
  m.faces = {{0, 1, 2}};
  m.face_group = {0};
  const SurfaceSamples s = sampleSurface(m, 0.5);
  for (size_t i = 0; i < s.size(); ++i) {
    const Eigen::Vector3d& p = s.p_w[i];
    const bool on_side =
        std::abs(p.x()) < 1e-9 || std::abs(p.y()) < 1e-9 || std::abs(p.x() + p.y() - 10) < 1e-9;
    ASSERT_EQ(s.on_edge[i] != 0, on_side) << p.transpose();
  }
}

// A mesh already finer than the spacing goes to the remesher, whose collapses bring the samples
// near the spacing (splitting alone would keep every input vertex).
TEST(SampleSurface, AFineInputIsCoarsenedToTheSpacing) {
  TriangleMesh m;
  m.group_names = {"plane"};
  const int n = 100;  // 0.1 mm grid over 10 x 10 mm
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) m.vertices.emplace_back(0.1 * i, 0.1 * j, 0);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const int v = j * (n + 1) + i;
      m.faces.emplace_back(v, v + 1, v + n + 2);
      m.faces.emplace_back(v, v + n + 2, v + n + 1);
      m.face_group.push_back(0);
      m.face_group.push_back(0);
    }
  const SurfaceSamples s = sampleSurface(m, 1.0);
  EXPECT_LT(s.size(), m.vertices.size() / 10);
  EXPECT_GT(s.size(), 60u);  // about 115 for equilateral triangles of 1 mm over 100 mm2
}

}  // namespace
}  // namespace tolver
