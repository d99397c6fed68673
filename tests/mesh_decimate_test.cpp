#include "geometry/mesh_decimate.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <random>

#include "geometry/triangle_mesh.h"

namespace tolver {
namespace {

struct Grid {
  std::vector<Eigen::Vector3d> p;
  std::vector<Eigen::Vector3i> faces;
};

// An n x n grid of unit spacing over [0, n-1]^2 mapped by `shape`, two triangles per cell.
template <class Shape>
Grid grid(int n, Shape shape) {
  Grid g;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) g.p.push_back(shape(i, j));
  for (int j = 0; j + 1 < n; ++j)
    for (int i = 0; i + 1 < n; ++i) {
      const int a = j * n + i, b = a + 1, c = a + n, d = c + 1;
      g.faces.emplace_back(a, b, d);
      g.faces.emplace_back(a, d, c);
    }
  return g;
}

// The independent check: the point of the triangle nearest q, by the plane's projection when it
// falls inside, else the nearest of the three edges (clamped projections); barycentric weights.
Eigen::Vector3d nearestWeights(const Eigen::Vector3d& q, const Eigen::Vector3d& a,
                               const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  Eigen::Matrix<double, 3, 2> m;
  m << b - a, c - a;
  const Eigen::Vector2d uv = m.colPivHouseholderQr().solve(q - a);
  if (uv.minCoeff() >= 0 && uv.sum() <= 1) return {1 - uv.sum(), uv[0], uv[1]};
  Eigen::Vector3d best;
  double best_d = INFINITY;
  const Eigen::Vector3d corner[3] = {a, b, c};
  for (int e = 0; e < 3; ++e) {
    const Eigen::Vector3d& s = corner[e];
    const Eigen::Vector3d& t = corner[(e + 1) % 3];
    const double u = std::clamp((q - s).dot(t - s) / (t - s).squaredNorm(), 0.0, 1.0);
    const double d = (s + u * (t - s) - q).norm();
    if (d < best_d) {
      best_d = d;
      best.setZero();
      best[e] = 1 - u;
      best[(e + 1) % 3] = u;
    }
  }
  return best;
}

// Every original vertex has a decimated face of its category within the distance bound on which
// the interpolated value is within the value bound; returns the largest value difference found on
// such faces (the best face per vertex). Every `stride`-th vertex.
double checkBounds(const Grid& g, const std::vector<double>& value,
                   const std::vector<int>& category, const DecimatedMesh& m, size_t stride = 1) {
  double worst = 0;
  for (size_t i = 0; i < g.p.size(); i += stride) {
    double best = INFINITY;
    for (const Eigen::Vector3i& f : m.faces) {
      const int v[3] = {m.vertex[f[0]], m.vertex[f[1]], m.vertex[f[2]]};
      if (category[v[0]] != category[i] || category[v[1]] != category[i] ||
          category[v[2]] != category[i])
        continue;
      const Eigen::Vector3d w = nearestWeights(g.p[i], g.p[v[0]], g.p[v[1]], g.p[v[2]]);
      const Eigen::Vector3d q = w[0] * g.p[v[0]] + w[1] * g.p[v[1]] + w[2] * g.p[v[2]];
      if ((q - g.p[i]).norm() > m.max_distance_mm * (1 + 1e-9) + 1e-12) continue;
      const double interpolated = w[0] * value[v[0]] + w[1] * value[v[1]] + w[2] * value[v[2]];
      best = std::min(best, std::abs(interpolated - value[i]));
    }
    EXPECT_LE(best, m.max_value_difference * (1 + 1e-9) + 1e-15) << "vertex " << i;
    worst = std::max(worst, best);
  }
  return worst;
}

TEST(MeshDecimate, AMeshWithinTheBudgetIsKeptAsSampled) {
  const Grid g = grid(11, [](int i, int j) { return Eigen::Vector3d(i, j, 0); });
  const DecimatedMesh m =
      decimateForDisplay(g.p, g.faces, std::vector<double>(g.p.size(), 0),
                         std::vector<int>(g.p.size(), 0), std::vector<char>(g.p.size(), 0), {});
  EXPECT_EQ(m.vertex.size(), g.p.size());
  EXPECT_EQ(m.faces, g.faces);
  EXPECT_EQ(m.max_distance_mm, 0.0);  // exact: nothing moved
  EXPECT_EQ(m.max_value_difference, 0.0);
}

TEST(MeshDecimate, AFlatGridWithTwoValuesGoesDownToTheBudgetWithinTheBounds) {
  const int n = 41;
  const Grid g = grid(n, [](int i, int j) { return Eigen::Vector3d(i, j, 0); });
  std::vector<double> value(g.p.size());
  std::vector<int> category(g.p.size());
  for (size_t i = 0; i < g.p.size(); ++i) {
    category[i] = g.p[i].x() < 20 ? 0 : 1;
    value[i] = category[i] == 0 ? 1e-3 : 2e-3 + 1e-7 * g.p[i].y();
  }
  const std::vector<char> locked(g.p.size(), 0);
  DecimateOptions o;
  o.max_distance_mm = 1e-3;
  o.max_value_difference = 1e-5;
  o.max_vertices = 300;
  const DecimatedMesh m = decimateForDisplay(g.p, g.faces, value, category, locked, o);
  EXPECT_FALSE(m.relaxed);
  EXPECT_LE(m.vertex.size(), 300u);
  // The border (160 vertices) and the boundary between the categories stay.
  for (int j = 0; j < n; ++j)
    for (int i : {19, 20})
      EXPECT_NE(std::find(m.vertex.begin(), m.vertex.end(), j * n + i), m.vertex.end()) << i << j;
  checkBounds(g, value, category, m);
  // The area is kept: the decimated faces cover the square.
  double area = 0;
  for (const Eigen::Vector3i& f : m.faces)
    area += 0.5 * (g.p[m.vertex[f[1]]] - g.p[m.vertex[f[0]]])
                      .cross(g.p[m.vertex[f[2]]] - g.p[m.vertex[f[0]]])
                      .norm();
  EXPECT_NEAR(area, (n - 1) * (n - 1), 1e-9);
}

// A hub, a vertex of far more neighbours than a sampled surface has (the CL-only surface of a
// Fabex spiral program had one of 73 000 triangles, and its 3D view took more than 5 minutes in
// OpenMesh's link test): the hub and its ring stay as they are, the rest goes down within the
// bounds. A flat wheel: a hub of 200 spokes, then 20 rings of 200 vertices.
TEST(MeshDecimate, AHubAndItsRingStayAsTheyAre) {
  const int spokes = 200, rings = 21;
  Grid g;
  g.p.emplace_back(0, 0, 0);
  for (int k = 0; k < rings; ++k)
    for (int i = 0; i < spokes; ++i) {
      const double a = 2 * M_PI * i / spokes, r = 10.0 + k;
      g.p.emplace_back(r * std::cos(a), r * std::sin(a), 0);
    }
  auto at = [&](int k, int i) { return 1 + k * spokes + (i % spokes); };
  for (int i = 0; i < spokes; ++i) g.faces.emplace_back(0, at(0, i), at(0, i + 1));
  for (int k = 0; k + 1 < rings; ++k)
    for (int i = 0; i < spokes; ++i) {
      g.faces.emplace_back(at(k, i), at(k + 1, i), at(k + 1, i + 1));
      g.faces.emplace_back(at(k, i), at(k + 1, i + 1), at(k, i + 1));
    }
  const std::vector<double> value(g.p.size(), 0.0);
  const std::vector<int> category(g.p.size(), 0);
  DecimateOptions o;
  o.max_distance_mm = 1e-3;
  o.max_value_difference = 1e-5;
  o.max_vertices = 1500;
  const DecimatedMesh m =
      decimateForDisplay(g.p, g.faces, value, category, std::vector<char>(g.p.size(), 0), o);
  EXPECT_LT(m.vertex.size(), g.p.size());  // the rest was decimated
  for (int i = 0; i <= spokes; ++i)        // the hub (0) and its ring (1-200)
    EXPECT_NE(std::find(m.vertex.begin(), m.vertex.end(), i), m.vertex.end()) << i;
  checkBounds(g, value, category, m);
}

TEST(MeshDecimate, ABumpAndTwoCategoriesStayWithinBothBounds) {
  const int n = 41;
  // A cylinder's quarter (radius 30): the distance bound matters.
  const Grid g = grid(n, [](int i, int j) {
    const double t = i / 40.0 * 1.5708;
    return Eigen::Vector3d(30 * std::cos(t), 30 * std::sin(t), j);
  });
  std::vector<double> value(g.p.size());
  std::vector<int> category(g.p.size());
  std::vector<char> locked(g.p.size(), 0);
  for (size_t i = 0; i < g.p.size(); ++i) {
    const double dx = static_cast<double>(i % n) - 25, dy = static_cast<double>(i / n) - 20;
    value[i] = 0.01 * std::exp(-(dx * dx + dy * dy) / 60.0);
    category[i] = (i % n) < 15 ? 0 : 1;
  }
  locked[5 * n + 5] = 1;
  DecimateOptions o;
  o.max_distance_mm = 0.05;
  o.max_value_difference = 2e-3;
  o.max_vertices = 600;
  const DecimatedMesh m = decimateForDisplay(g.p, g.faces, value, category, locked, o);
  EXPECT_LE(m.vertex.size(), 600u);
  EXPECT_NE(std::find(m.vertex.begin(), m.vertex.end(), 5 * n + 5), m.vertex.end());
  const double worst = checkBounds(g, value, category, m);
  EXPECT_GT(worst, 0.05 * m.max_value_difference);  // the bound is used, not just met
}

TEST(MeshDecimate, ANoisyFieldIsDecimatedWithinRelaxedBoundsToFitTheBudget) {
  const int n = 41;
  const Grid g = grid(n, [](int i, int j) { return Eigen::Vector3d(i, j, 0); });
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1e-3, 1e-3);
  std::vector<double> value(g.p.size());
  for (double& v : value) v = u(rng);
  const std::vector<int> category(g.p.size(), 7);
  const std::vector<char> locked(g.p.size(), 0);
  DecimateOptions o;
  o.max_distance_mm = 1e-3;
  o.max_value_difference = 1e-5;  // far below the noise: nothing goes at first
  o.max_vertices = 600;
  const DecimatedMesh m = decimateForDisplay(g.p, g.faces, value, category, locked, o);
  EXPECT_TRUE(m.relaxed);
  EXPECT_LE(m.vertex.size(), 600u);
  EXPECT_GT(m.max_value_difference, o.max_value_difference);
  checkBounds(g, value, category, m);
}

TEST(MeshDecimate, ANonManifoldFaceIsKeptAsGivenAndWrongSizesAreRefused) {
  Grid g = grid(5, [](int i, int j) { return Eigen::Vector3d(i, j, 0); });
  // A third face on the edge (0, 1): OpenMesh cannot add it.
  g.p.emplace_back(0.5, 0, 1);
  g.faces.emplace_back(0, 1, static_cast<int>(g.p.size()) - 1);
  const std::vector<double> value(g.p.size(), 0);
  const std::vector<int> category(g.p.size(), 0);
  const std::vector<char> locked(g.p.size(), 0);
  DecimateOptions o;
  o.max_vertices = 5;
  const DecimatedMesh m = decimateForDisplay(g.p, g.faces, value, category, locked, o);
  EXPECT_EQ(m.faces_kept_as_given, 1);
  EXPECT_THROW(decimateForDisplay(g.p, g.faces, std::vector<double>(3), category, locked, {}),
               std::invalid_argument);
}

// The mesh the decimater starts from is built directly when the faces make a manifold, by
// add_face otherwise: a bow-tie (two grids meeting at one corner, a vertex whose faces are two
// fans) and a face turned over (an edge run the same way by two faces) still decimate to a
// surface of the same area (the flat grids' area, each turned face kept as given), within the
// budget where it can be.
TEST(MeshDecimate, ABowTieAndATurnedFaceDecimateAsTheyAre) {
  auto area = [](const std::vector<Eigen::Vector3d>& p, const std::vector<Eigen::Vector3i>& faces,
                 const std::vector<int>* vertex) {
    double a = 0;
    for (const Eigen::Vector3i& f : faces) {
      auto at = [&](int k) { return p[vertex ? (*vertex)[f[k]] : f[k]]; };
      a += 0.5 * (at(1) - at(0)).cross(at(2) - at(0)).norm();
    }
    return a;
  };
  for (int turned = 0; turned < 2; ++turned) {
    Grid g = grid(12, [](int i, int j) { return Eigen::Vector3d(i, j, 0); });
    const int corner = 11 * 12 + 11;  // (11, 11)
    const Grid h = grid(12, [](int i, int j) { return Eigen::Vector3d(11 + i, 11 + j, 0); });
    const int offset = static_cast<int>(g.p.size());
    for (size_t k = 1; k < h.p.size(); ++k) g.p.push_back(h.p[k]);  // (11, 11) is shared
    for (const Eigen::Vector3i& f : h.faces) {
      Eigen::Vector3i t;
      for (int k = 0; k < 3; ++k) t[k] = f[k] == 0 ? corner : f[k] - 1 + offset;
      g.faces.push_back(t);
    }
    if (turned) std::swap(g.faces[40][1], g.faces[40][2]);
    const std::vector<double> value(g.p.size(), 0);
    const std::vector<int> category(g.p.size(), 0);
    const std::vector<char> locked(g.p.size(), 0);
    DecimateOptions o;
    o.max_vertices = 60;
    o.pieces = 1;
    const DecimatedMesh m = decimateForDisplay(g.p, g.faces, value, category, locked, o);
    EXPECT_NEAR(area(g.p, m.faces, &m.vertex), area(g.p, g.faces, nullptr), 1e-9) << turned;
    EXPECT_LT(m.vertex.size(), g.p.size() / 2) << turned;
    if (turned) EXPECT_GE(m.faces_kept_as_given, 1);
  }
  // Two octahedra sharing a vertex, no border: the shared vertex's faces are two closed fans.
  // OpenMesh cannot add the face that closes the second fan: it is kept as given.
  std::vector<Eigen::Vector3d> p = {{0, 0, 0}};
  std::vector<Eigen::Vector3i> faces;
  for (const double x : {1.0, -1.0}) {
    const int b = static_cast<int>(p.size());
    // The octahedron of centre (x, 0, 0): its vertex towards the origin is p[0].
    for (const Eigen::Vector3d& q :
         {Eigen::Vector3d(x, 1, 0), Eigen::Vector3d(x, 0, 1), Eigen::Vector3d(x, -1, 0),
          Eigen::Vector3d(x, 0, -1), Eigen::Vector3d(2 * x, 0, 0)})
      p.push_back(q);
    for (int k = 0; k < 4; ++k) {
      const int r = b + k, s = b + (k + 1) % 4;
      if (x > 0) {
        faces.emplace_back(0, s, r);
        faces.emplace_back(b + 4, r, s);
      } else {
        faces.emplace_back(0, r, s);
        faces.emplace_back(b + 4, s, r);
      }
    }
  }
  const DecimatedMesh m =
      decimateForDisplay(p, faces, std::vector<double>(p.size(), 0), std::vector<int>(p.size(), 0),
                         std::vector<char>(p.size(), 0), DecimateOptions{0.01, 1e-3, 5, 1, {}});
  EXPECT_GE(m.faces_kept_as_given, 1);
}

// A resampled part's own faces where they carry the map (coarseForDisplay): an 80 x 80 mm plate
// of 128 given triangles, sampled at 0.5 mm (about 30 000 samples), a budget of 5 000 vertices.
// A linear field: every given face is drawn as it is (its 81 corners), within the bounds
// (a linear field on a plane: exact). A bump of 20 um in one face's middle, and a second
// category on another: those two (and only they, with their neighbours' common edges) are
// decimated from their samples; every sample still lies on a face of the result, within the
// bounds, of its category (the independent check of every decimation above). When the faces drawn
// whole would take more than half of the budget: empty (the caller decimates everything).
TEST(MeshDecimate, AResampledPartsOwnFacesAreDrawnWhereTheyCarryTheMap) {
  TriangleMesh plate;
  for (int j = 0; j <= 8; ++j)
    for (int i = 0; i <= 8; ++i) plate.vertices.emplace_back(10.0 * i, 10.0 * j, 0.0);
  for (int j = 0; j < 8; ++j)
    for (int i = 0; i < 8; ++i) {
      const int a = j * 9 + i;
      plate.faces.emplace_back(a, a + 1, a + 10);
      plate.faces.emplace_back(a, a + 10, a + 9);
    }
  plate.face_group.assign(plate.faces.size(), 0);
  plate.group_names = {"plate"};
  const SurfaceSamples s = sampleSurface(plate, 0.5);
  ASSERT_EQ(s.given_faces.size(), plate.faces.size());
  ASSERT_EQ(s.face_given.size(), s.faces.size());
  ASSERT_GT(s.size(), size_t{20000});
  Grid g{s.p_w, s.faces};
  DecimateOptions o;
  o.max_distance_mm = 0.25;
  o.max_value_difference = 2e-3;
  o.max_vertices = 5000;
  std::vector<double> value(s.size());
  std::vector<int> category(s.size(), 0);
  for (size_t i = 0; i < s.size(); ++i) value[i] = 1e-4 * s.p_w[i].x() - 2e-4 * s.p_w[i].y();
  const DecimatedMesh linear =
      coarseForDisplay(s.p_w, s.faces, s.given_faces, s.face_given, value, category, {}, o);
  EXPECT_EQ(linear.given_faces_drawn, 128);
  EXPECT_EQ(linear.faces.size(), size_t{128});
  EXPECT_EQ(linear.vertex.size(), size_t{81});
  checkBounds(g, value, category, linear, 7);
  // The bump (in the face over (45, 43)) and the second category (the face over (15, 12)).
  for (size_t i = 0; i < s.size(); ++i) {
    const double r = (s.p_w[i] - Eigen::Vector3d(45, 43, 0)).norm();
    if (r < 1.5) value[i] += 0.02 * (1.0 - r / 1.5);
    if ((s.p_w[i] - Eigen::Vector3d(15, 12, 0)).norm() < 1.0) category[i] = 1;
  }
  const DecimatedMesh bumped =
      coarseForDisplay(s.p_w, s.faces, s.given_faces, s.face_given, value, category, {}, o);
  EXPECT_GE(bumped.given_faces_drawn, 120);
  EXPECT_LE(bumped.given_faces_drawn, 126);
  EXPECT_LE(bumped.vertex.size(), size_t{5000});
  EXPECT_GT(bumped.vertex.size(), size_t{81});
  EXPECT_FALSE(bumped.relaxed);
  checkBounds(g, value, category, bumped, 7);
  o.max_vertices = 100;  // about 77 corners alone: more than half
  EXPECT_TRUE(coarseForDisplay(s.p_w, s.faces, s.given_faces, s.face_given, value, category, {}, o)
                  .vertex.empty());
}

// In pieces (slabs decimated in parallel, seams kept whole): the surface is still covered once
// (the faces' area is the square's, none turned over), the budget holds, and the bounds hold on
// every 97th vertex.
TEST(MeshDecimate, InPiecesTheSurfaceStaysWholeAndWithinTheBounds) {
  const int n = 201;
  const Grid g = grid(n, [](int i, int j) { return Eigen::Vector3d(0.15 * i, 0.15 * j, 0); });
  std::vector<double> value(g.p.size());
  std::vector<int> category(g.p.size());
  for (size_t i = 0; i < g.p.size(); ++i) {
    const Eigen::Vector3d& q = g.p[i];
    value[i] = 1e-3 * std::sin(q.x() / 3) * std::cos(q.y() / 4);
    category[i] = (q - Eigen::Vector3d(15, 15, 0)).norm() < 6 ? 1 : 0;
  }
  const std::vector<char> locked(g.p.size(), 0);
  DecimateOptions o;
  o.max_distance_mm = 1e-3;
  o.max_value_difference = 1e-4;
  o.max_vertices = 4000;  // the borders, seams and the category's boundary hold about 2 000
  o.pieces = 3;
  const DecimatedMesh m = decimateForDisplay(g.p, g.faces, value, category, locked, o);
  EXPECT_LE(m.vertex.size(), 4000u);
  EXPECT_GT(m.vertex.size(), 2000u);
  double area = 0;
  for (const Eigen::Vector3i& f : m.faces) {
    const Eigen::Vector3d n_w = (g.p[m.vertex[f[1]]] - g.p[m.vertex[f[0]]])
                                    .cross(g.p[m.vertex[f[2]]] - g.p[m.vertex[f[0]]]);
    EXPECT_GT(n_w.z(), 0);
    area += 0.5 * n_w.norm();
  }
  EXPECT_NEAR(area, 30.0 * 30.0, 1e-6);
  checkBounds(g, value, category, m, 97);
}

}  // namespace
}  // namespace tolver
