// geometry/mesh_repair.h on meshes built here: a solid's voids, the slivers CAD
// tessellators leave along straight edges, and borders, holes and components.
#include "geometry/mesh_repair.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

namespace tolver {
namespace {

const int kCube[12][3] = {{0, 2, 1}, {0, 3, 2}, {4, 5, 6}, {4, 6, 7}, {0, 1, 5}, {0, 5, 4},
                          {1, 2, 6}, {1, 6, 5}, {2, 3, 7}, {2, 7, 6}, {3, 0, 4}, {3, 4, 7}};

// Appends the cube [lo, lo + side]^3, its faces outward (or inward when `inward`).
void addCube(TriangleMesh* m, const Eigen::Vector3d& lo, double side, bool inward) {
  const int base = static_cast<int>(m->vertices.size());
  for (int k = 0; k < 8; ++k)
    m->vertices.push_back(lo + side * Eigen::Vector3d(k == 1 || k == 2 || k == 5 || k == 6,
                                                      k == 2 || k == 3 || k == 6 || k == 7,
                                                      k >= 4));
  for (const auto& f : kCube) {
    m->faces.emplace_back(base + f[0], base + (inward ? f[2] : f[1]),
                          base + (inward ? f[1] : f[2]));
    m->face_group.push_back(0);
  }
}

double signedVolume(const TriangleMesh& m) {
  double v = 0;
  for (const auto& t : m.faces)
    v += m.vertices[t[0]].dot(m.vertices[t[1]].cross(m.vertices[t[2]])) / 6.0;
  return v;
}

// A solid with a void (a STEP solid's inner shell): the void's faces look into it, and the
// repair leaves them so; turned the wrong way, it turns them back. A cube beside the block, not
// in it, faces outwards whichever way it came.
TEST(MeshRepair, AVoidInsideASolidKeepsItsFacesLookingIntoIt) {
  for (bool void_wrong : {false, true}) {
    SCOPED_TRACE(void_wrong);
    TriangleMesh m;
    addCube(&m, Eigen::Vector3d(0, 0, 0), 10, false);
    addCube(&m, Eigen::Vector3d(3, 4, 2), 2, /*inward=*/!void_wrong);  // the void
    addCube(&m, Eigen::Vector3d(20, 0, 0), 4, /*inward=*/true);        // a separate body
    MeshRepairReport rep;
    const TriangleMesh out = repairMesh(m, {}, &rep);
    EXPECT_TRUE(rep.closed);
    EXPECT_EQ(rep.components, 3);
    EXPECT_EQ(rep.reoriented_faces, void_wrong ? 24 : 12);
    EXPECT_NEAR(signedVolume(out), 1000.0 - 8.0 + 64.0, 1e-9);
  }
}

// A zero-area sliver along an edge (BRepMesh leaves them on cones): its middle point is a
// T-junction in the face across. Removing the sliver alone would leave a slit; the repair splits
// the face at the point and the surface stays closed.
TEST(MeshRepair, ASliverAlongAnEdgeSplitsTheFaceAcrossInsteadOfLeavingASlit) {
  TriangleMesh m;
  addCube(&m, Eigen::Vector3d(0, 0, 0), 10, false);
  // The front face (y = 0: corners 0, 1, 5, 4) re-triangulated through M, the middle of the edge
  // from corner 4 to corner 5 that the top face shares without M.
  const int mid = static_cast<int>(m.vertices.size());
  m.vertices.emplace_back(5, 0, 10);
  std::vector<Eigen::Vector3i> faces;
  for (const auto& t : m.faces)
    if (!(t == Eigen::Vector3i(0, 1, 5) || t == Eigen::Vector3i(0, 5, 4))) faces.push_back(t);
  faces.emplace_back(0, 1, mid);
  faces.emplace_back(1, 5, mid);
  faces.emplace_back(0, mid, 4);
  faces.emplace_back(4, mid, 5);  // the sliver: 4, M, 5 on one line
  m.faces = faces;
  m.face_group.assign(faces.size(), 0);
  MeshRepairReport rep;
  const TriangleMesh out = repairMesh(m, {}, &rep);
  EXPECT_EQ(rep.degenerate_faces, 1);
  EXPECT_TRUE(rep.closed);
  EXPECT_TRUE(rep.holes.empty());
  EXPECT_EQ(rep.open_borders, 0);
  EXPECT_NEAR(signedVolume(out), 1000.0, 1e-9);
}

// The topology read from OpenMesh's half-edge mesh, against what the mesh is by construction: a
// closed cube and, beside it, a 10 x 10 mm sheet with a 4 x 4 mm square missing from its middle
// (kept open: longer than the largest hole filled). Two components, one of them open; two
// borders kept (the sheet's edge and the hole); one hole, of the missing square's area; a
// small hole (one cell, 4 mm of border) is filled when the limit allows it.
TEST(MeshRepair, BordersHolesAndComponentsComeFromTheHalfEdgeMesh) {
  for (const double max_hole : {1.0, 5.0}) {
    TriangleMesh m;
    addCube(&m, Eigen::Vector3d(20, 0, 0), 5, false);
    const int base = static_cast<int>(m.vertices.size());
    for (int j = 0; j <= 10; ++j)
      for (int i = 0; i <= 10; ++i) m.vertices.emplace_back(i, j, 0);
    for (int j = 0; j < 10; ++j)
      for (int i = 0; i < 10; ++i) {
        const bool missing =
            max_hole < 2 ? (i >= 3 && i < 7 && j >= 3 && j < 7) : (i == 5 && j == 5);
        if (missing) continue;
        const int a = base + j * 11 + i;
        m.faces.emplace_back(a, a + 1, a + 12);
        m.faces.emplace_back(a, a + 12, a + 11);
        m.face_group.push_back(0);
        m.face_group.push_back(0);
      }
    MeshRepairOptions o;
    o.max_hole_perimeter = max_hole;
    MeshRepairReport rep;
    const TriangleMesh out = repairMesh(m, o, &rep);
    EXPECT_EQ(rep.components, 2);
    EXPECT_FALSE(rep.closed);
    if (max_hole < 2) {
      EXPECT_EQ(rep.open_borders, 2);
      EXPECT_EQ(rep.holes_filled, 0);
      ASSERT_EQ(rep.holes.size(), 1u);
      EXPECT_NEAR(rep.holes[0].area, 16.0, 1e-9);
      EXPECT_NEAR(rep.holes[0].perimeter, 16.0, 1e-9);
      EXPECT_NEAR((rep.holes[0].centre_w - Eigen::Vector3d(5, 5, 0)).norm(), 0.0, 1e-9);
    } else {
      EXPECT_EQ(rep.holes_filled, 1);  // the one cell, 4 mm around
      EXPECT_EQ(rep.open_borders, 1);  // the sheet's edge
      EXPECT_TRUE(rep.holes.empty());
      EXPECT_EQ(out.faces.size(), m.faces.size() + 2);
    }
  }
}

}  // namespace
}  // namespace tolver
