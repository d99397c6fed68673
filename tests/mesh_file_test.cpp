// Part meshes in every supported format, and the repairs.
#include "io/mesh/mesh_file.h"

#include <assimp/scene.h>
#include <gtest/gtest.h>
#include <unistd.h>
#include <vtkCellArray.h>
#include <vtkDataArray.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>
#include <vtkXMLPolyDataReader.h>

#include <assimp/Exporter.hpp>
#include <assimp/Importer.hpp>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>

#include "io/common/io_error.h"
#include "test_support.h"

namespace tolver {
namespace {

// A cube [0, s]^3 as 8 vertices and 12 outward triangles.
const double kSide = 20.0;
const double kCorner[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                              {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
const int kFaces[12][3] = {{0, 2, 1}, {0, 3, 2}, {4, 5, 6}, {4, 6, 7}, {0, 1, 5}, {0, 5, 4},
                           {1, 2, 6}, {1, 6, 5}, {2, 3, 7}, {2, 7, 6}, {3, 0, 4}, {3, 4, 7}};

std::string objText(int skip_face = -1, bool flip_face0 = false, bool extra_fin = false) {
  std::string s = "# cube\n";
  char buf[128];
  for (const auto& c : kCorner) {
    std::snprintf(buf, sizeof buf, "v %g %g %g\n", c[0] * kSide, c[1] * kSide, c[2] * kSide);
    s += buf;
  }
  if (extra_fin) s += "v 10 -10 10\n";  // vertex 9
  s += "g cube\n";
  for (int f = 0; f < 12; ++f) {
    if (f == skip_face) continue;
    int a = kFaces[f][0] + 1, b = kFaces[f][1] + 1, c = kFaces[f][2] + 1;
    if (f == 0 && flip_face0) std::swap(b, c);
    std::snprintf(buf, sizeof buf, "f %d %d %d\n", a, b, c);
    s += buf;
  }
  if (extra_fin) s += "f 1 2 9\n";  // a third face on the edge 1-2
  return s;
}

double signedVolume(const TriangleMesh& m) {
  double v = 0;
  for (const auto& f : m.faces)
    v += m.vertices[f[0]].dot(m.vertices[f[1]].cross(m.vertices[f[2]])) / 6.0;
  return v;
}

class MeshFileTest : public test::TempDirTest {};

void expectCube(const ImportedPart& p, double scale = 1.0) {
  const double s = kSide * scale;
  EXPECT_NEAR(p.mesh.area(), 6 * s * s, 1e-6 * s * s);
  EXPECT_NEAR(signedVolume(p.mesh), s * s * s, 1e-6 * s * s * s);  // outward
  EXPECT_TRUE(p.repair.closed);
  EXPECT_EQ(p.repair.components, 1);
}

TEST_F(MeshFileTest, ReadsEveryFormat) {
  const std::string obj = write("cube.obj", objText());
  expectCube(readPartMesh(obj));
  // STL ASCII and binary, PLY, OFF by hand.
  {
    std::ofstream a(path("cube.stl"));
    a << "solid cube\n";
    std::ofstream b(path("cube_bin.stl"), std::ios::binary);
    char header[80] = "binary cube";
    b.write(header, 80);
    const uint32_t n = 12;
    b.write(reinterpret_cast<const char*>(&n), 4);
    for (const auto& f : kFaces) {
      a << " facet normal 0 0 0\n  outer loop\n";
      float v[12] = {0, 0, 0};
      for (int k = 0; k < 3; ++k) {
        const auto& c = kCorner[f[k]];
        a << "   vertex " << c[0] * kSide << " " << c[1] * kSide << " " << c[2] * kSide << "\n";
        for (int d = 0; d < 3; ++d) v[3 + 3 * k + d] = static_cast<float>(c[d] * kSide);
      }
      a << "  endloop\n endfacet\n";
      b.write(reinterpret_cast<const char*>(v), 48);
      const uint16_t attr = 0;
      b.write(reinterpret_cast<const char*>(&attr), 2);
    }
    a << "endsolid cube\n";
  }
  {
    std::ofstream ply(path("cube.ply")), off(path("cube.off"));
    ply << "ply\nformat ascii 1.0\nelement vertex 8\nproperty float x\nproperty float y\n"
           "property float z\nelement face 12\nproperty list uchar int "
           "vertex_indices\nend_header\n";
    off << "OFF\n8 12 0\n";
    for (const auto& c : kCorner) {
      ply << c[0] * kSide << " " << c[1] * kSide << " " << c[2] * kSide << "\n";
      off << c[0] * kSide << " " << c[1] * kSide << " " << c[2] * kSide << "\n";
    }
    for (const auto& f : kFaces) {
      ply << "3 " << f[0] << " " << f[1] << " " << f[2] << "\n";
      off << "3 " << f[0] << " " << f[1] << " " << f[2] << "\n";
    }
  }
  for (const char* f : {"cube.stl", "cube_bin.stl", "cube.ply", "cube.off"}) {
    SCOPED_TRACE(f);
    expectCube(readPartMesh(path(f)));
  }
  // 3MF and glTF through assimp's exporters, from the OBJ.
  Assimp::Importer importer;
  const aiScene* scene = importer.ReadFile(obj, 0);
  ASSERT_NE(scene, nullptr);
  Assimp::Exporter exporter;
  ASSERT_EQ(exporter.Export(scene, "3mf", path("cube.3mf")), aiReturn_SUCCESS)
      << exporter.GetErrorString();
  ASSERT_EQ(exporter.Export(scene, "glb2", path("cube.glb")), aiReturn_SUCCESS)
      << exporter.GetErrorString();
  expectCube(readPartMesh(path("cube.3mf")));
  // glTF's unit is the metre: 20 "m" read as 20000 mm unless told otherwise.
  expectCube(readPartMesh(path("cube.glb")), 1000.0);
  PartImportOptions mm;
  mm.units = "mm";
  expectCube(readPartMesh(path("cube.glb"), mm));
}

TEST_F(MeshFileTest, UnitsAndPlacement) {
  const std::string obj = write("cube.obj", objText());
  PartImportOptions o;
  o.units = "inch";
  o.w_T_file.translation() = Eigen::Vector3d(1, 2, 3);
  const ImportedPart p = readPartMesh(obj, o);
  expectCube(p, 25.4);
  Eigen::AlignedBox3d box;
  for (const auto& v : p.mesh.vertices) box.extend(v);
  EXPECT_TRUE(box.min().isApprox(Eigen::Vector3d(1, 2, 3)));
  o.units = "furlong";
  EXPECT_THROW(readPartMesh(obj, o), InputError);
}

TEST_F(MeshFileTest, RepairsWhatIsSafe) {
  // A flipped face is turned back.
  {
    const ImportedPart p = readPartMesh(write("flipped.obj", objText(-1, true)));
    EXPECT_GE(p.repair.reoriented_faces, 1);
    expectCube(p);
  }
  // A duplicate and a degenerate face are removed.
  {
    const ImportedPart p = readPartMesh(write("dup.obj", objText() + "f 1 3 2\nf 1 2 2\n"));
    EXPECT_EQ(p.repair.duplicate_faces, 1);
    EXPECT_EQ(p.repair.degenerate_faces, 1);
    expectCube(p);
  }
  // A missing triangle is a hole: filled when small enough.
  {
    PartImportOptions o;
    o.repair.max_hole_perimeter = 100.0;
    const ImportedPart p = readPartMesh(write("hole.obj", objText(5)), o);
    EXPECT_EQ(p.repair.holes_filled, 1);
    expectCube(p);
    // With a smaller limit, it stays open and is reported.
    o.repair.max_hole_perimeter = 10.0;
    const ImportedPart q = readPartMesh(path("hole.obj"), o);
    EXPECT_EQ(q.repair.holes_filled, 0);
    EXPECT_EQ(q.repair.open_borders, 1);
    EXPECT_FALSE(q.repair.closed);
  }
}

TEST_F(MeshFileTest, RefusesWhatIsNot) {
  try {
    readPartMesh(write("fin.obj", objText(-1, false, true)));
    FAIL();
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("fin.obj"), std::string::npos) << what;
    EXPECT_NE(what.find("non-manifold edge"), std::string::npos) << what;
    EXPECT_NE(what.find("(0.0000, 0.0000, 0.0000) mm to (20.0000, 0.0000, 0.0000) mm"),
              std::string::npos)
        << what;
  }
  EXPECT_THROW(readPartMesh(write("empty.stl", "solid x\nendsolid x\n")), InputError);
  EXPECT_THROW(readPartMesh(write("garbage.off", "this is not a mesh\n")), InputError);
  EXPECT_THROW(readPartMesh(write("part.step", "ISO-10303-21;\n")), InputError);
  EXPECT_THROW(readPartMesh(path("missing.stl")), InputError);
  // One vertex at 1.3e7 mm: refused at once, not swept for hours.
  try {
    readPartMesh(write("far.obj", "v 0 0 0\nv 10 0 0\nv 0 10 0\nv 1.3e7 0 5\nf 1 2 3\nf 1 2 4\n"));
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("beyond 1e5 mm"), std::string::npos) << e.what();
  }
  // A PLY header cut short before end_header (the mesh fuzz harness's input, found in CI's 30 s):
  // Debian's assimp looped for minutes on it, allocating; refused at once, naming the line.
  try {
    readPartMesh(
        write("no_end_header.ply",
              "ply\nformat ascii 1.0\nelement vertex 8\nproperty float x\nproperty float y\n"
              "property float z\nelement face 12\nproperty list uchar int vertex_indices\n"
              "end_he0 10 0\n10 10 10\n3 0 1 3\n3 0 3 2\n"));
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("no_end_header.ply:9"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("is not a PLY header line"), std::string::npos)
        << e.what();
  }
  // A binary PLY with a proper header still reads (the header check stops at end_header).
  {
    std::string bin =
        "ply\r\nformat binary_little_endian 1.0\r\nelement vertex 3\r\nproperty float x\r\n"
        "property float y\r\nproperty float z\r\nelement face 1\r\n"
        "property list uchar int vertex_indices\r\nend_header\r\n";
    const float v[9] = {0, 0, 0, 10, 0, 0, 0, 10, 0};
    bin.append(reinterpret_cast<const char*>(v), sizeof v);
    bin.push_back(3);
    const int idx[3] = {0, 1, 2};
    bin.append(reinterpret_cast<const char*>(idx), sizeof idx);
    EXPECT_EQ(readPartMesh(write("binary.ply", bin)).mesh.faces.size(), 1u);
  }
  // A PLY face list with a face of no vertex (the mesh fuzz harness's input): assimp's
  // triangulation aborted the process on it; refused with a message instead. The harness's
  // form, with more numbers on a line than the face takes, is refused from the body's check,
  // naming the line; a face line that declares no vertex, by assimp's reading.
  const std::string header =
      "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
      "property float z\nelement face 3\nproperty list uchar int vertex_indices\nend_header\n"
      "0 0 0\n10 0 0\n0 10 0\n0 0 10\n3 0 1 2\n";
  try {
    readPartMesh(write("no_vertex_face.ply", header + "3 0 1 3 3\n0 2 3\n"));
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("no_vertex_face.ply:15"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("more numbers than"), std::string::npos) << e.what();
  }
  try {
    readPartMesh(write("no_vertex_face.ply", header + "3 0 1 3\n0\n"));
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("has no vertex"), std::string::npos) << e.what();
  }
}

// The mesh fuzz harness's input that made CGAL's hole filling walk for minutes in its 3D
// Delaunay point location (a mutated binary STL, 8 kB; the corpus file's first byte chose .stl):
// it now reads in well under a second, its holes filled by the bounded dynamic programme or left
// open. Without the fix this test does not finish (ctest's timeout fails it).
TEST_F(MeshFileTest, AFuzzedBorderDoesNotMakeHoleFillingWalk) {
  std::ifstream in(std::string(TOLVER_SOURCE_DIR) + "/tests/fuzz/mesh_corpus/stl_hole_fill_walk",
                   std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  ASSERT_GT(bytes.size(), 1000u);
  const std::string stl = write("walk.stl", bytes.substr(1));
  try {
    const ImportedPart part = readPartMesh(stl);
    EXPECT_GT(part.mesh.faces.size(), 0u);
    EXPECT_GE(part.repair.holes_filled + part.repair.open_borders, 1);
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("walk.stl"), std::string::npos) << e.what();
  }
}

// The mesh harness's OBJ on which assimp's parser ran strtol past its unterminated buffer (seen
// by the sanitized build with strict_string_checks; the file is now handed over with a zero
// byte after it), and a valid OBJ ending in digits without a line end: read or refused with the
// file's name, never a read past the buffer.
TEST_F(MeshFileTest, AnObjEndingInDigitsIsReadWithinItsBuffer) {
  std::ifstream in(
      std::string(TOLVER_SOURCE_DIR) + "/tests/fuzz/mesh_corpus/obj_strtol_unterminated",
      std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  ASSERT_GT(bytes.size(), 1u);
  for (const std::string& text :
       {bytes.substr(1), std::string("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3")}) {
    const std::string obj = write("digits.obj", text);
    try {
      const ImportedPart part = readPartMesh(obj);
      EXPECT_EQ(part.mesh.faces.size(), 1u);
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("digits.obj"), std::string::npos) << e.what();
    }
  }
}

// A PLY header's element counts must fit in the file (the mesh harness: 'element face
// 777...71' in a 345-byte file made assimp ask for 26 GB): refused with the line, before assimp
// reads it; a count that fits, and a file that holds what it declares, read as before.
TEST_F(MeshFileTest, APlyElementCountBeyondTheFileIsRefused) {
  std::ifstream in(std::string(TOLVER_SOURCE_DIR) + "/tests/fuzz/mesh_corpus/ply_huge_face_count",
                   std::ios::binary);
  const std::string found((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  ASSERT_GT(found.size(), 100u);
  const std::string header =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
      "property float y\nproperty float z\nelement face ";
  const std::string body =
      "\nproperty list uchar int vertex_indices\nend_header\n"
      "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
  // (The harness takes the first byte as the format.)
  for (const std::string& text : {found.substr(1), header + "4000" + body, header + "12x" + body,
                                  header + std::string(40, '9') + body}) {
    const std::string ply = write("huge.ply", text);
    try {
      readPartMesh(ply);
      ADD_FAILURE() << "accepted " << text.substr(0, 120);
    } catch (const InputError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("huge.ply:"), std::string::npos) << what;
      EXPECT_NE(what.find("element"), std::string::npos) << what;
      EXPECT_LT(what.size(), 300u) << what;
    }
  }
  const ImportedPart part = readPartMesh(write("fits.ply", header + "1" + body));
  EXPECT_EQ(part.mesh.faces.size(), 1u);
}

// An OFF header's counts must fit in the file: Debian's assimp allocates the declared faces
// first (the mesh harness: 'OFF' then '8 1888...880' asked for more than 2 GB). Refused from
// the header, with its line, at once; comments and the 'n' dimension are skipped as assimp does.
TEST_F(MeshFileTest, AnOffCountBeyondTheFileIsRefused) {
  std::ifstream in(std::string(TOLVER_SOURCE_DIR) + "/tests/fuzz/mesh_corpus/off_huge_face_count",
                   std::ios::binary);
  const std::string found((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  ASSERT_GT(found.size(), 100u);
  std::ifstream in2(
      std::string(TOLVER_SOURCE_DIR) + "/tests/fuzz/mesh_corpus/off_keyword_glued_count",
      std::ios::binary);
  const std::string glued((std::istreambuf_iterator<char>(in2)), std::istreambuf_iterator<char>());
  ASSERT_GT(glued.size(), 50u);
  const std::string body = "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
  // The second found input: 'OFF8' then a count of 2222222223222222220 on the next line.
  for (const std::string& text :
       {found.substr(1), glued.substr(1), "OFF3 4000000 0\n" + body, "OFF\n3 4000000 0\n" + body,
        "OFF\n4000000 1 0\n" + body,
        "# a comment\nOFF\n# another\n3 " + std::string(40, '9') + " 0\n" + body,
        "nOFF 3\n3 4000000 0\n" + body, "3 4000000 0\n" + body, "C3 4000000 0\n" + body,
        "OFF\n#3 1 0\n3 4000000 0\n" + body}) {
    const std::string off = write("huge.off", text);
    const auto t0 = std::chrono::steady_clock::now();
    try {
      readPartMesh(off);
      ADD_FAILURE() << "accepted " << text.substr(0, 120);
    } catch (const InputError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("huge.off:"), std::string::npos) << what;
      EXPECT_NE(what.find("OFF header"), std::string::npos) << what;
      EXPECT_LT(what.size(), 300u) << what;
    }
    EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 5.0);
  }
  const ImportedPart part = readPartMesh(write("fits.off", "OFF\n# c\n3 1 0\n" + body));
  EXPECT_EQ(part.mesh.faces.size(), 1u);
  // A coordinate is no count, even a large one in a short file.
  EXPECT_EQ(readPartMesh(write("far.off", "OFF\n3 1 0\n900 0 0\n901 0 0\n900 1 0\n3 0 1 2\n"))
                .mesh.faces.size(),
            1u);
}

// Faces need the vertices declared before them (the mesh harness: an 'element vbspertex' in
// place of the vertices, with garbage in the face list, took assimp 50 s and 17 GB before it
// said so): refused from the header, at once.
TEST_F(MeshFileTest, APlyWithoutVerticesBeforeItsFacesIsRefusedFromItsHeader) {
  std::ifstream in(
      std::string(TOLVER_SOURCE_DIR) + "/tests/fuzz/mesh_corpus/ply_faces_without_vertices",
      std::ios::binary);
  const std::string found((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  ASSERT_GT(found.size(), 100u);
  const std::string faces_first =
      "ply\nformat ascii 1.0\nelement face 1\nproperty list uchar int vertex_indices\n"
      "element vertex 3\nproperty float x\nproperty float y\nproperty float z\nend_header\n"
      "3 0 1 2\n0 0 0\n1 0 0\n0 1 0\n";
  for (const std::string& text : {found.substr(1), faces_first}) {  // (first byte: the format)
    const auto t0 = std::chrono::steady_clock::now();
    try {
      readPartMesh(write("novertex.ply", text));
      ADD_FAILURE() << "accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("novertex.ply:"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("vertex"), std::string::npos) << e.what();
    }
    EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 5.0);
  }
}

// An ASCII PLY's list counts must fit their type and the file (the mesh harness: a face whose
// count is a run of 4s made assimp allocate 477 million indices, 15 s and 7.5 GB, before it
// refused the face): refused with the line, at once; ordinary faces still read.
TEST_F(MeshFileTest, AnAsciiPlyListCountBeyondItsTypeIsRefused) {
  std::ifstream in(std::string(TOLVER_SOURCE_DIR) + "/tests/fuzz/mesh_corpus/ply_ascii_list_count",
                   std::ios::binary);
  const std::string found((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  ASSERT_GT(found.size(), 100u);
  const std::string header =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
      "property float y\nproperty float z\nelement face 1\n"
      "property list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n";
  for (const std::string& text : {found.substr(1), header + std::string(58, '4') + " 0 1 2\n",
                                  header + "256 0 1 2\n", header + "x 0 1 2\n"}) {
    const auto t0 = std::chrono::steady_clock::now();
    try {
      readPartMesh(write("count.ply", text));
      ADD_FAILURE() << "accepted " << text.substr(text.size() - 20);
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("count.ply:"), std::string::npos) << e.what();
    }
    EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 5.0);
  }
  EXPECT_EQ(readPartMesh(write("ok.ply", header + "3 0 1 2\n")).mesh.faces.size(), 1u);
  try {
    readPartMesh(write("line.ply", header + std::string(58, '4') + " 0 1 2\n"));
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("line.ply:13:"), std::string::npos) << e.what();
  }
}

// A PLY is checked whole before assimp reads it (its header line by line, its body against the
// header): the mesh harness's zero bytes inside a property line made assimp ask for 3.8 GB.
// Each malformed form is refused with its line and field, at once; the same triangle written in
// ASCII, binary little-endian and binary big-endian still reads.
TEST_F(MeshFileTest, APlyIsCheckedWholeBeforeAssimpReadsIt) {
  std::ifstream in(
      std::string(TOLVER_SOURCE_DIR) + "/tests/fuzz/mesh_corpus/ply_zero_bytes_in_header",
      std::ios::binary);
  const std::string found((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  ASSERT_GT(found.size(), 300u);
  auto header = [](const std::string& format, const std::string& list = "uchar int") {
    return "ply\nformat " + format +
           " 1.0\ncomment made by hand\nelement vertex 3\nproperty float x\n"
           "property float y\nproperty float z\nelement face 1\nproperty list " +
           list + " vertex_indices\nend_header\n";
  };
  const std::string ascii = header("ascii") + "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
  auto binary = [&](bool big, unsigned char count) {
    std::string b = header(big ? "binary_big_endian" : "binary_little_endian");
    auto put = [&](const void* p, size_t n) {
      std::string bytes(static_cast<const char*>(p), n);
      if (big) std::reverse(bytes.begin(), bytes.end());
      b += bytes;
    };
    for (float v : {0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f, 0.f}) put(&v, 4);
    b.push_back(static_cast<char>(count));
    for (int i : {0, 1, 2}) put(&i, 4);
    return b;
  };
  struct Case {
    std::string text, where, field;
  };
  const std::vector<Case> refused = {
      {found.substr(1), "bad.ply:5", "PLY header"},  // (the harness's first byte: the format)
      {"ply\nformat ascii 2.0\n" + ascii.substr(21), "bad.ply:2", "PLY format"},
      {header("ascii", "float int") + "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", "bad.ply:9",
       "PLY property"},
      {"ply\nformat ascii 1.0\nproperty float x\n" + ascii.substr(21), "bad.ply:3", "PLY property"},
      {header("ascii") + "0 0 0\n1 0 0\n0 1 0\n", "bad.ply:", "PLY body"},  // a face short
      {header("ascii") + "0 0 0\n1 0\n0 1 0\n3 0 1 2\n", "bad.ply:12",
       "PLY body"},  // a number short
      {header("ascii") + "0 0 0\n1 0 x\n0 1 0\n3 0 1 2\n", "bad.ply:12", "PLY body"},
      {binary(false, 3).substr(0, binary(false, 3).size() - 1), "bad.ply", "PLY body"},
      {binary(false, 200), "bad.ply", "PLY body"},  // a list count beyond the file
      {binary(true, 255), "bad.ply", "PLY body"},
  };
  for (const Case& c : refused) {
    const auto t0 = std::chrono::steady_clock::now();
    try {
      readPartMesh(write("bad.ply", c.text));
      ADD_FAILURE() << "accepted " << c.where << " " << c.field;
    } catch (const InputError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find(c.where), std::string::npos) << what;
      EXPECT_NE(what.find(c.field), std::string::npos) << what;
      EXPECT_LT(what.size(), 300u) << what;
      EXPECT_EQ(what.find('\0'), std::string::npos);
    }
    EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 5.0);
  }
  for (const std::string& text : {ascii, binary(false, 3), binary(true, 3)}) {
    const ImportedPart part = readPartMesh(write("good.ply", text));
    ASSERT_EQ(part.mesh.faces.size(), 1u);
    EXPECT_EQ(part.mesh.vertices.size(), 3u);
  }
}

// The swept surfaces tolver writes (binary PLY with a per-vertex scalar) read back through the
// part loader and its whole-file check: every triangle, every vertex to float precision.
TEST_F(MeshFileTest, TheSweptSurfacePlyReadsBackThroughThePartLoader) {
  std::vector<Eigen::Vector3d> points;
  std::vector<Eigen::Vector3i> faces;
  std::vector<double> scalar;
  for (int i = 0; i < 20; ++i)
    for (int j = 0; j < 20; ++j) {
      points.emplace_back(2.5 * i, 3.0 * j, 0.01 * i * j);
      scalar.push_back(1e-3 * (i - j));
    }
  for (int i = 0; i + 1 < 20; ++i)
    for (int j = 0; j + 1 < 20; ++j) {
      const int a = 20 * i + j;
      faces.emplace_back(a, a + 20, a + 1);
      faces.emplace_back(a + 1, a + 20, a + 21);
    }
  const std::string ply = path("swept.ply");
  writePlyWithScalar(ply, points, faces, scalar, "deviation_um");
  const ImportedPart part = readPartMesh(ply);
  ASSERT_EQ(part.mesh.faces.size(), faces.size());
  ASSERT_EQ(part.mesh.vertices.size(), points.size());
  for (size_t i = 0; i < points.size(); ++i)
    EXPECT_LT((part.mesh.vertices[i] - points[i]).norm(), 1e-5) << i;
}

// A 3MF archive is checked before assimp reads it: Debian's assimp 5.2 aborted the process (an
// ai_assert) on a model that does not inflate (the scene harness, one corrupt byte), on a
// _rels/.rels naming a model not in the archive and on a _rels/.rels that is not XML. Each is
// refused with a message, and the sound archive they were made from still reads.
TEST_F(MeshFileTest, ADamaged3mfIsRefusedBeforeAssimpReadsIt) {
  auto corpus = [](const std::string& name) {
    std::ifstream in(std::string(TOLVER_SOURCE_DIR) + "/tests/fuzz/scene_corpus/" + name,
                     std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    EXPECT_GT(bytes.size(), 100u) << name;
    return bytes.substr(1);  // (the harness's first byte: the format)
  };
  const std::pair<const char*, const char*> refused[] = {
      {"3mf_model_does_not_inflate", "'3D/3DModel.model' is damaged"},
      {"3mf_model_inflates_short",
       "'3D/3DModel.model' is damaged (it inflates to 2183 of its 2188 bytes)"},
      {"3mf_rels_names_a_missing_model",
       "'3D/Other.model' that _rels/.rels names is not in the archive"},
      {"3mf_rels_not_xml", "_rels/.rels is not XML"},
      {"3mf_without_rels", "no _rels/.rels"}};
  for (const auto& [name, why] : refused) {
    try {
      readPartMesh(write("damaged.3mf", corpus(name)));
      ADD_FAILURE() << "accepted " << name;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("damaged.3mf: 3MF: "), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(why), std::string::npos) << e.what();
    }
  }
  try {
    readPartMesh(write("text.3mf", "solid not a zip\n"));
    ADD_FAILURE() << "accepted a text file";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("not a zip archive"), std::string::npos) << e.what();
  }
  EXPECT_EQ(readPartMesh(write("sound.3mf", corpus("scene_3mf"))).mesh.faces.size(), 12u);
  // A .gltf holding a damaged zip (the harness again): assimp, failing to parse it as glTF,
  // handed it to its 3MF reader, which aborted. Checked as a zip whatever its extension.
  try {
    readPartMesh(write("zip.gltf", corpus("gltf_holding_a_damaged_zip")));
    ADD_FAILURE() << "accepted a .gltf holding a damaged zip";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("zip.gltf: zip archive read as 3MF: "), std::string::npos)
        << e.what();
  }
  EXPECT_EQ(readPartMesh(write("sound.gltf", corpus("scene_gltf")), PartImportOptions{})
                .mesh.faces.size(),
            12u);
  // A binary glTF whose JSON chunk declares 0xf8000000 bytes in a 3 kB file (the harness:
  // assimp asked for 4.2 GB), and the sound one with its BIN chunk cut short: refused from the
  // header; the sound one reads.
  const std::string glb = corpus("scene_glb");
  for (const std::string& text :
       {corpus("glb_json_chunk_beyond_the_file"), glb.substr(0, glb.size() - 4)}) {
    try {
      readPartMesh(write("damaged.glb", text));
      ADD_FAILURE() << "accepted a damaged .glb";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("damaged.glb: glTF: "), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("bytes"), std::string::npos) << e.what();
    }
  }
  EXPECT_EQ(readPartMesh(write("sound.glb", glb)).mesh.faces.size(), 12u);
}

// The two glTF files on which Debian's assimp 5.2 crashed (the scene harness: a line loop whose
// indices pass its vertices, a segmentation fault; a strip without positions, 2^32 faces) are
// refused before assimp reads them, naming the primitive and what the glTF specification
// requires; so is the first with its fuzzed key repaired (the index check itself), and the same
// defects in a text .gltf with a base64 buffer.
TEST_F(MeshFileTest, GltfMeshesAreCheckedAsTheSpecificationRequiresBeforeAssimpReadsThem) {
  auto corpus = [](const char* name) {
    std::ifstream in(std::string(TOLVER_SOURCE_DIR) + "/tests/fuzz/scene_corpus/" + name,
                     std::ios::binary);
    const std::string s((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    return s.substr(1);  // the harness's format byte
  };
  auto says = [&](const std::string& file, const std::string& text) {
    try {
      readPartMesh(write(file, text));
      return std::string("accepted");
    } catch (const InputError& e) {
      return std::string(e.what());
    }
  };
  std::string loop = corpus("scene_glb_line_loop_index_past_vertices");
  EXPECT_NE(says("loop.glb", loop).find("loop.glb: glTF: the JSON does not parse"),
            std::string::npos);  // a key that is not UTF-8 (glTF's JSON is)
  loop[loop.find('\x94')] = 'i';
  EXPECT_NE(says("loop.glb", loop).find("mesh 0 primitive 0: index 0 is "), std::string::npos)
      << says("loop.glb", loop);
  EXPECT_NE(says("loop.glb", loop).find("past its 6 vertices"), std::string::npos);
  EXPECT_NE(says("strip.glb", corpus("scene_glb_strip_without_positions"))
                .find("strip.glb: glTF: mesh 0 primitive 0 has no POSITION attribute"),
            std::string::npos);
  // A text glTF: one triangle with a base64 buffer (3 float vertices, then 3 uint16 indices).
  auto gltf = [](int last_index, bool positions) {
    std::string bin(36, '\0');
    const float v[9] = {0, 0, 0, 10, 0, 0, 0, 10, 0};
    std::memcpy(bin.data(), v, 36);
    const uint16_t idx[3] = {0, 1, static_cast<uint16_t>(last_index)};
    bin.append(reinterpret_cast<const char*>(idx), 6);
    static const char* abc = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::string b64;
    for (size_t i = 0; i < bin.size(); i += 3) {
      const unsigned n = (static_cast<unsigned char>(bin[i]) << 16) |
                         (i + 1 < bin.size() ? static_cast<unsigned char>(bin[i + 1]) << 8 : 0) |
                         (i + 2 < bin.size() ? static_cast<unsigned char>(bin[i + 2]) : 0);
      b64 += abc[(n >> 18) & 63];
      b64 += abc[(n >> 12) & 63];
      b64 += i + 1 < bin.size() ? abc[(n >> 6) & 63] : '=';
      b64 += i + 2 < bin.size() ? abc[n & 63] : '=';
    }
    return std::string(R"({"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],)") +
           R"("nodes":[{"mesh":0}],"meshes":[{"primitives":[{"attributes":{)" +
           (positions ? R"("POSITION":0)" : R"("NORMAL":0)") +
           R"(},"indices":1}]}],"accessors":[{"bufferView":0,"componentType":5126,"count":3,)" +
           R"("type":"VEC3","max":[10,10,0],"min":[0,0,0]},{"bufferView":1,"componentType":5123,)" +
           R"("count":3,"type":"SCALAR"}],"bufferViews":[{"buffer":0,"byteLength":36},)" +
           R"({"buffer":0,"byteOffset":36,"byteLength":6}],"buffers":[{"byteLength":42,)" +
           R"("uri":"data:application/octet-stream;base64,)" + b64 + R"("}]})";
  };
  EXPECT_EQ(readPartMesh(write("sound.gltf", gltf(2, true))).mesh.faces.size(), 1u);
  EXPECT_NE(says("far.gltf", gltf(3, true))
                .find("far.gltf: glTF: mesh 0 primitive 0: index 2 is 3, "
                      "past its 3 vertices"),
            std::string::npos)
      << says("far.gltf", gltf(3, true));
  EXPECT_NE(says("bare.gltf", gltf(2, false)).find("has no POSITION attribute"), std::string::npos);
}

// The scene formats are read by assimp in a child process: a child that stops on a signal (as
// Debian's assimp 5.2 did on the harness's findings; injected here, since no known file passes
// the checks and crashes it) is an error naming the file, and the process goes on to read a sound
// one. (Under the sanitizers the child ends with the sanitizer's exit instead of the signal.)
TEST_F(MeshFileTest, AssimpCrashingOnASceneFileIsAnErrorNotACrash) {
  std::ifstream in(std::string(TOLVER_SOURCE_DIR) + "/tests/fuzz/scene_corpus/scene_glb",
                   std::ios::binary);
  const std::string found((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  ASSERT_GT(found.size(), 1000u);
  ::setenv("TOLVER_TEST_CRASH_SCENE_READER", "1", 1);
  try {
    readPartMesh(write("crash.glb", found.substr(1)));
    ADD_FAILURE() << "accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("crash.glb: mesh: assimp stopped"), std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("a damaged file?"), std::string::npos) << e.what();
  }
  ::unsetenv("TOLVER_TEST_CRASH_SCENE_READER");
  // The same reading path gives the sound file whole: its groups, faces and vertices.
  std::ifstream in2(std::string(TOLVER_SOURCE_DIR) + "/tests/fuzz/scene_corpus/scene_glb",
                    std::ios::binary);
  const std::string glb((std::istreambuf_iterator<char>(in2)), std::istreambuf_iterator<char>());
  const ImportedPart part = readPartMesh(write("sound.glb", glb.substr(1)));
  EXPECT_EQ(part.mesh.faces.size(), 12u);
  EXPECT_EQ(part.mesh.face_group.size(), 12u);
  ASSERT_EQ(part.mesh.group_names.size(), 1u);
  EXPECT_EQ(part.mesh.group_names[0], "part");
  Eigen::AlignedBox3d box;
  for (const auto& v : part.mesh.vertices) box.extend(v);
  EXPECT_TRUE(box.max().isApprox(Eigen::Vector3d(20000, 20000, 20000)))
      << box.max().transpose();  // m -> mm
}

// The VTP surface (raw appended binary, no compression) reads back through VTK's own reader:
// every point, triangle and scalar value exactly.
TEST(SurfaceFiles, VtpSurfaceReadsBackExactly) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> U(-100.0, 100.0);
  std::vector<Eigen::Vector3d> points(500);
  for (auto& p : points) p = Eigen::Vector3d(U(rng), U(rng), U(rng));
  std::vector<Eigen::Vector3i> faces;
  for (int k = 0; k + 2 < 500; k += 3) faces.emplace_back(k, k + 1, k + 2);
  std::vector<double> a(500), b(500);
  for (size_t i = 0; i < 500; ++i) {
    a[i] = U(rng) * 1e-3;
    b[i] = static_cast<double>(i % 4);
  }
  const std::string path = (std::filesystem::temp_directory_path() /
                            ("tolver_vtp_test_" + std::to_string(::getpid()) + ".vtp"))
                               .string();
  writeVtpWithScalars(path, points, faces, {{"total_um", &a}, {"state", &b}});
  {
    // The triangles in 32-bit arrays (VTK's default is 64-bit: a third of a verify's VTP bytes).
    std::ifstream in(path, std::ios::binary);
    std::string head(4096, '\0');
    in.read(head.data(), static_cast<std::streamsize>(head.size()));
    EXPECT_NE(head.find("type=\"Int32\" Name=\"connectivity\""), std::string::npos);
    EXPECT_NE(head.find("type=\"Int32\" Name=\"offsets\""), std::string::npos);
  }
  vtkNew<vtkXMLPolyDataReader> reader;
  reader->SetFileName(path.c_str());
  reader->Update();
  vtkPolyData* poly = reader->GetOutput();
  ASSERT_EQ(poly->GetNumberOfPoints(), 500);
  ASSERT_EQ(poly->GetNumberOfPolys(), static_cast<vtkIdType>(faces.size()));
  for (vtkIdType i = 0; i < 500; ++i) {
    double p[3];
    poly->GetPoint(i, p);
    EXPECT_EQ(Eigen::Vector3d(p[0], p[1], p[2]), points[i]) << i;
    EXPECT_EQ(poly->GetPointData()->GetArray("total_um")->GetTuple1(i), a[i]) << i;
    EXPECT_EQ(poly->GetPointData()->GetArray("state")->GetTuple1(i), b[i]) << i;
  }
  vtkIdType n = 0;
  const vtkIdType* ids = nullptr;
  poly->GetPolys()->InitTraversal();
  for (size_t f = 0; poly->GetPolys()->GetNextCell(n, ids); ++f) {
    ASSERT_EQ(n, 3);
    EXPECT_EQ(Eigen::Vector3i(ids[0], ids[1], ids[2]), faces[f]) << f;
  }
  std::filesystem::remove(path);
}

}  // namespace
}  // namespace tolver
