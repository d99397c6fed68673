// The CLI on posted G-code and real CAM files: predict, setup and verify end to end.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <regex>
#include <string>

#include "core/kinematics/inverse_kinematics.h"
#include "core/path/tool_path_prediction.h"
#include "io/machine/machine_file.h"
#include "io/program/apt_reader.h"
#include "io/program/gcode_reader.h"
#include "io/program/setup_file.h"
#include "test_support.h"

namespace fs = std::filesystem;

namespace tolver {
namespace {

class GcodeCli : public test::TempDirTest {
 protected:
  static std::string src(const std::string& rel) { return test::sourcePath(rel); }
  // The xyzac-trt machine file with A turning the other way (its travel mirrored).
  std::string aReversed(const std::string& right) const {
    std::string text = test::readText(right);
    const std::string from = "min=\"-100\" max=\"50\"  nc_sign=\"1\"";
    EXPECT_NE(text.find(from), std::string::npos);
    if (text.find(from) != std::string::npos)
      text.replace(text.find(from), from.size(), "min=\"-50\" max=\"100\"  nc_sign=\"-1\"");
    return write("a_reversed.xml", text);
  }
};

// A posted program end to end: predict on its machine, the predicted CL reads back with the same
// set-up (the singular band and the travel tolerance keep the pole and the limits stable), and
// the machine without errors says its share is zero by construction.
TEST_F(GcodeCli, PostedProgramPredictsAndItsPredictedClReadsBack) {
  const std::string m = src("resources/machines/umc_bc_trunnion.xml");
  auto r =
      test::runTolver("predict --machine " + m + " --nc " + src("samples/gcode/umc_bc_inch.nc") +
                      " --gauge-length 76.2 -o " + path("umc.apt"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("(G-code)"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("units INCH"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("zero by construction"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("rotary steps above"), std::string::npos) << r.output;
  r = test::runTolver("predict --machine " + m + " --cl " + path("umc.apt") +
                      " --gauge-length 76.2 -o " + path("back.apt"));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  // The written CL is the program's path (a machine without errors predicts the nominal), in
  // mm in the part frame, to the six decimals written.
  {
    Machine mm = readMachineFile(m);
    mm.model.setup.gauge_length = 76.2;
    const ClProgram nominal = readGcodeFile(src("samples/gcode/umc_bc_inch.nc"), mm.model);
    const ClProgram written = readAptFile(path("umc.apt"));
    ASSERT_EQ(written.path.size(), nominal.path.size());
    for (size_t i = 0; i < nominal.path.size(); ++i) {
      EXPECT_LT((written.path[i].p_w - nominal.path[i].p_w).norm(), 1e-6) << i;
      EXPECT_LT((written.path[i].u_w - nominal.path[i].u_w).norm(), 1e-8) << i;
      EXPECT_EQ(written.path[i].rapid, nominal.path[i].rapid) << i;
    }
  }
  for (const char* machine : {"resources/machines/linuxcnc_xyzac_trt.xml"}) {
    r = test::runTolver(std::string("predict --machine ") + src(machine) + " --nc " +
                        src("samples/gcode/boat-xyzac.ngc") + " --setup " +
                        src("samples/gcode/linuxcnc_setup.txt") + " -o " + path("boat.apt"));
    EXPECT_EQ(r.exit_code, 0) << r.output;
    r = test::runTolver(std::string("predict --machine ") + src(machine) + " --cl " +
                        path("boat.apt") + " --setup " + src("samples/gcode/linuxcnc_setup.txt") +
                        " -o " + path("boat_back.apt"));
    EXPECT_EQ(r.exit_code, 0) << r.output;
  }
}

// The LinuxCNC boat does not fit with the part zero at the C axis and a 75 mm tool... it does:
// setup reports the ranges and a proposal inside travel, and writes a set-up predict accepts.
// Three-axis posted G-code, as a planner runs it: setup proposes the work offset (G54 values to
// enter at the control), verify then sweeps each tool with its own cutter; a tool the program
// does not describe is an error listing the tools, never the last cutter for all.
TEST_F(GcodeCli, ThreeAxisProgramSetupAndToolsPerOperation) {
  const std::string m = src("resources/machines/vmc_3axis_iso.xml");
  const std::string known =
      write("known.nc",
            "(T1 D=6 CR=0 - flat end mill)\n(T2 D=3 CR=1.5 - ball end mill)\nG21 G90 G54\nT1 M6\n"
            "G0 X0 Y0 Z10\nG1 Z-1 F100\nX20\nT2 M6\nG0 X5 Y5 Z10\nG1 Z-1\nX25\nG0 Z10\nM30\n");
  auto s = test::runTolver("setup --machine " + m + " --nc " + known + " -o " + path("s.txt"));
  ASSERT_EQ(s.exit_code, 0) << s.output;
  // Each axis's range centred in its travel (machine coordinates X -762..0, Y -406..0, Z -508..0):
  // X 0..25 -> -381 - 12.5, Y 0..5 -> -203 - 2.5, Z -1..10 -> -254 - 4.5 (no tool length given).
  EXPECT_NE(s.output.find("work offset at the control (G54..., machine coordinates): X-393.500 "
                          "Y-205.500 Z-258.500"),
            std::string::npos)
      << s.output;
  auto v = test::runTolver("verify --machine " + m + " --setup " + path("s.txt") + " --nc " +
                           known + " --tolerance 0.1 --no-images --report-dir " + path("v"));
  EXPECT_NE(v.output.find("2 tools, each from its line on: line 4 flat end D6 mm"),
            std::string::npos)
      << v.output;
  EXPECT_NE(v.output.find("line 8 ball end D3 mm"), std::string::npos) << v.output;
  const std::string unknown = write("unknown.nc",
                                    "G21 G90 G54\nT1 M6\nG0 X0 Y0 Z10\nG1 Z-1 F100\n"
                                    "T2 M6\nG0 X5 Y5 Z10\nG1 Z-1\nM30\n");
  v = test::runTolver("verify --machine " + m + " --setup " + path("s.txt") + " --nc " + unknown +
                      " --tolerance 0.1 --no-images --report-dir " + path("u"));
  EXPECT_EQ(v.exit_code, 2) << v.output;
  EXPECT_NE(v.output.find("the program cuts with T1 (line 2), T2 (line 5)"), std::string::npos)
      << v.output;
  // A tool file describes them (by number, with or without its T).
  const std::string tools = write("tools.csv",
                                  "tool,type,diameter_mm,corner_radius_mm,length_mm\n"
                                  "1,flat,6,0,30\nT2,ball,3,,20\n");
  v = test::runTolver("verify --machine " + m + " --setup " + path("s.txt") + " --nc " + unknown +
                      " --tools " + tools + " --tolerance 0.1 --no-images --report-dir " +
                      path("t"));
  EXPECT_NE(v.output.find("2 tools, each from its line on: line 2 flat end D6 mm"),
            std::string::npos)
      << v.output;
  EXPECT_NE(v.output.find("line 5 ball end D3 mm, corner R1.5 mm, length 20 mm"), std::string::npos)
      << v.output;
  const std::string bad = write("bad_tools.csv", "tool,diameter_mm\n1,6\n2,-3\n");
  v = test::runTolver("verify --machine " + m + " --setup " + path("s.txt") + " --nc " + unknown +
                      " --tools " + bad + " --tolerance 0.1 --no-images --report-dir " + path("b"));
  EXPECT_EQ(v.exit_code, 2) << v.output;
  EXPECT_NE(v.output.find("bad_tools.csv:3"), std::string::npos) << v.output;
}

// The convention check: a TCP program posted for LinuxCNC's xyzac-trt faces a 45-degree face
// with A-45 (the flat end square on it). On the machine file it was posted for it passes; on a
// file whose A turns the other way every point gouges, and verify says that A turns the other
// way instead of a verdict (issue 32: a HAAS UMC program "gouged" by 0.5 mm and nothing noticed).
TEST_F(GcodeCli, VerifyNamesARotaryAxisThatTurnsTheOtherWay) {
  const std::string right = src("resources/machines/linuxcnc_xyzac_trt.xml");
  const Machine mc = readMachineFile(right);
  const ClProgram probe = parseGcode("G21\nM428\nG0 X0 Y0 Z0 A-45 C0\n", "probe.ngc", mc.model);
  ASSERT_EQ(probe.path.size(), 1u);
  const Eigen::Vector3d u = probe.path[0].u_w.normalized();
  const Eigen::Vector3d e1 = Eigen::Vector3d::UnitX(), e2 = u.cross(e1).normalized();
  ASSERT_LT(std::abs(u.dot(e1)), 1e-12);
  // A slab whose top face, through the origin, is square to u.
  std::string obj;
  char buf[160];
  for (int k = 0; k < 8; ++k) {
    const double a = (k & 1) ? 20 : -20, b = (k & 2) ? 20 : -20, c = (k & 4) ? 0 : -10;
    const Eigen::Vector3d v = a * e1 + b * e2 + c * u;
    std::snprintf(buf, sizeof buf, "v %.9f %.9f %.9f\n", v.x(), v.y(), v.z());
    obj += buf;
  }
  // Faces outward: the box's faces (vertex index = 1 + a + 2b + 4c), counter-clockwise seen from
  // out.
  obj +=
      "f 5 6 8\nf 5 8 7\nf 1 3 4\nf 1 4 2\nf 1 2 6\nf 1 6 5\nf 3 7 8\nf 3 8 4\n"
      "f 1 5 7\nf 1 7 3\nf 2 4 8\nf 2 8 6\n";
  // Check the winding's orientation from e1 x e2 = u: the top (c=1) face 5 6 8 turns about +u.
  write("slab.obj", obj);
  std::string prog = "G21\nM428\nG43 H1\n";
  auto tip = [&](double a, double b, double h) {
    const Eigen::Vector3d p = a * e1 + b * e2 + h * u;
    std::snprintf(buf, sizeof buf, "X%.4f Y%.4f Z%.4f", p.x(), p.y(), p.z());
    return std::string(buf);
  };
  prog += "G0 " + tip(-15, -15, 10) + " A-45 C0\n";
  for (int row = 0; row <= 10; ++row) {
    const double b = -15 + 3 * row;
    prog += "G1 " + tip(-15, b, 0) + " F500\nG1 " + tip(15, b, 0) + "\n";
  }
  prog += "G0 " + tip(15, 15, 10) + "\nM429\nM2\n";
  write("face.ngc", prog);
  // The same passes 5 mm above the face: nothing checked is cut, so INCOMPLETE, never PASS.
  std::string lifted = "G21\nM428\nG43 H1\nG0 " + tip(-15, -15, 10) + " A-45 C0\n";
  for (int row = 0; row <= 10; ++row)
    lifted += "G1 " + tip(-15, -15 + 3 * row, 5) + " F500\nG1 " + tip(15, -15 + 3 * row, 5) + "\n";
  lifted += "M429\nM2\n";
  write("lifted.ngc", lifted);
  const std::string setup = src("samples/gcode/linuxcnc_setup.txt");
  const std::string common = " --setup " + setup + " --nc " + path("face.ngc") + " --part " +
                             path("slab.obj") +
                             " --cutter 4,0,30 --tolerance 0.1 --no-images --report-dir ";
  auto ok = test::runTolver("verify --machine " + right + common + path("ok"));
  EXPECT_EQ(ok.exit_code, 0) << ok.output;
  EXPECT_NE(ok.output.find("tolver verify: PASS"), std::string::npos) << ok.output;
  EXPECT_NE(ok.output.find("100.00 % of"), std::string::npos) << ok.output;
  auto none = test::runTolver("verify --machine " + right + " --setup " + setup + " --nc " +
                              path("lifted.ngc") + " --part " + path("slab.obj") +
                              " --cutter 4,0,30 --tolerance 0.1 --no-images "
                              "--report-dir " +
                              path("none"));
  EXPECT_EQ(none.exit_code, 1) << none.output;
  EXPECT_NE(none.output.find("INCOMPLETE: the program cuts none of the checked surface"),
            std::string::npos)
      << none.output;
  const std::string wrong = aReversed(right);
  auto bad = test::runTolver("verify --machine " + wrong + common + path("bad"));
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
  EXPECT_NE(bad.output.find("A turns the other way in this program compared with the machine file"),
            std::string::npos)
      << bad.output;
  EXPECT_NE(bad.output.find("set the nc_sign of A in the machine file"), std::string::npos)
      << bad.output;
  // A file whose C zero is half a turn away (its link turned 180 deg about z): named as such.
  std::string text = test::readText(right);
  const std::regex c_link("(<axis name=\"C\"[^>]*>\\s*<link [^>]*rotation=\")0 0 0\"");
  ASSERT_TRUE(std::regex_search(text, c_link)) << text;
  const std::string c_flipped =
      write("c_zero.xml", std::regex_replace(text, c_link, "$010 0 180\""));
  auto zero = test::runTolver("verify --machine " + c_flipped + common + path("zero"));
  EXPECT_EQ(zero.exit_code, 2) << zero.output;
  EXPECT_NE(zero.output.find("the zero of C is half a turn away"), std::string::npos)
      << zero.output;
}

// Per operation: a three-axis facing at A0 and a chamfer faced square with A-45 in one program.
// On a file whose A turns the other way only the chamfer's operation gouges (under 30 % of the
// whole cut), and verify names A and that operation's lines.
TEST_F(GcodeCli, VerifyNamesTheConventionOfOneOperation) {
  const std::string right = src("resources/machines/linuxcnc_xyzac_trt.xml");
  const Machine mc = readMachineFile(right);
  const ClProgram probe = parseGcode("G21\nM428\nG0 X0 Y0 Z0 A-45 C0\n", "probe.ngc", mc.model);
  ASSERT_EQ(probe.path.size(), 1u);
  const Eigen::Vector3d u = probe.path[0].u_w.normalized();
  ASSERT_NEAR(std::abs(u.y()), std::sqrt(0.5), 1e-12);
  const double sy = u.y() > 0 ? 1.0 : -1.0;  // the chamfer on the side the tool leans to
  // A prism along x: section (y, z) = (-20,-20) (20,-20) (20,-10) (10,0) (-20,0), y times sy.
  const double Y[5] = {-20, 20, 20, 10, -20}, Z[5] = {-20, -20, -10, 0, 0};
  std::string obj;
  char buf[200];
  for (int side = 0; side < 2; ++side)
    for (int k = 0; k < 5; ++k) {
      std::snprintf(buf, sizeof buf, "v %d %.9f %.9f\n", side ? 20 : -20, sy * Y[k], Z[k]);
      obj += buf;
    }
  // Vertex k of the -x cap is k+1, of the +x cap k+6. The section is counter-clockwise seen from
  // +x when sy = +1 (the caps and sides then face out as written); mirrored, every face turns.
  auto face = [&](int a, int b, int c) {
    if (sy > 0)
      std::snprintf(buf, sizeof buf, "f %d %d %d\n", a, b, c);
    else
      std::snprintf(buf, sizeof buf, "f %d %d %d\n", a, c, b);
    obj += buf;
  };
  for (int k = 1; k < 4; ++k) face(6, 6 + k, 7 + k);  // +x cap
  for (int k = 1; k < 4; ++k) face(1, 2 + k, 1 + k);  // -x cap
  for (int k = 0; k < 5; ++k) {
    const int n = (k + 1) % 5;
    face(1 + k, 1 + n, 6 + n);
    face(1 + k, 6 + n, 6 + k);
  }
  write("roof.obj", obj);
  std::string prog = "G21\nM428\nG43 H1\nG0 X-15 Y" + std::to_string(-18 * sy) + " Z10 A0 C0\n";
  for (int row = 0; row <= 8; ++row) {
    const double y = sy * (-18 + 3 * row);
    std::snprintf(buf, sizeof buf, "G1 X-15 Y%.4f Z0 F500\nG1 X15 Y%.4f Z0\n", y, y);
    prog += buf;
  }
  prog += "G0 Z20\n";
  // The chamfer: centre (0, 15 sy, -5), across it e1 = x and e2 = u x e1, square to u.
  const Eigen::Vector3d c(0, 15 * sy, -5), e1 = Eigen::Vector3d::UnitX(),
                                           e2 = u.cross(e1).normalized();
  auto tip = [&](double a, double b, double h) {
    const Eigen::Vector3d q = c + a * e1 + b * e2 + h * u;
    std::snprintf(buf, sizeof buf, "X%.4f Y%.4f Z%.4f", q.x(), q.y(), q.z());
    return std::string(buf);
  };
  prog += "G0 " + tip(-15, -2, 10) + " A-45 C0\n";
  for (int row = 0; row <= 2; ++row)
    prog += "G1 " + tip(-15, -2 + 2 * row, 0) + " F500\nG1 " + tip(15, -2 + 2 * row, 0) + "\n";
  prog += "G0 " + tip(15, 2, 10) + "\nM429\nM2\n";
  write("two_ops.ngc", prog);
  const std::string common = " --setup " + src("samples/gcode/linuxcnc_setup.txt") + " --nc " +
                             path("two_ops.ngc") + " --part " + path("roof.obj") +
                             " --cutter 4,0,30 --tolerance 0.1 --no-images --report-dir ";
  auto ok = test::runTolver("verify --machine " + right + common + path("ok"));
  EXPECT_EQ(ok.exit_code, 0) << ok.output;
  const std::string wrong = aReversed(right);
  auto bad = test::runTolver("verify --machine " + wrong + common + path("bad"));
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
  EXPECT_NE(bad.output.find(
                "A turns the other way in this program compared with the machine file: with that "
                "convention the operation of lines 24-"),
            std::string::npos)
      << bad.output;
}

TEST_F(GcodeCli, SetupReachesTheXyzbcBoatOnItsMachine) {
  auto r = test::runTolver("setup --machine " + src("resources/machines/linuxcnc_xyzbc_trt.xml") +
                           " --nc " + src("tests/fixtures/gcode/linuxcnc_boat-xyzbc.ngc") +
                           " --gauge-length 25 -o " + path("bc.txt"));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("every point inside travel"), std::string::npos) << r.output;
  r = test::runTolver("predict --machine " + src("resources/machines/linuxcnc_xyzbc_trt.xml") +
                      " --nc " + src("tests/fixtures/gcode/linuxcnc_boat-xyzbc.ngc") + " --setup " +
                      path("bc.txt") + " -o " + path("bc.apt"));
  EXPECT_EQ(r.exit_code, 0) << r.output;
}

TEST_F(GcodeCli, SetupProposesASetupThatReaches) {
  const std::string m = src("resources/machines/linuxcnc_xyzac_trt.xml");
  auto r = test::runTolver("setup --machine " + m + " --nc " + src("samples/gcode/boat-xyzac.ngc") +
                           " --setup " + src("samples/gcode/linuxcnc_setup.txt") + " -o " +
                           path("proposed.txt"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("every point inside travel"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("the program needs"), std::string::npos);
  r = test::runTolver("predict --machine " + m + " --nc " + src("samples/gcode/boat-xyzac.ngc") +
                      " --setup " + path("proposed.txt") + " -o " + path("p.apt"));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  // Far outside travel: the failing axis, how far over and the count per axis.
  r = test::runTolver("predict --machine " + m + " --nc " + src("samples/gcode/boat-xyzac.ngc") +
                      " --part-zero 0,0,0 --gauge-length 400 -o " + path("q.apt"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("beyond its travel"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("points fail (first axis to break: Z"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(path("q.apt")));
}

// A LinuxCNC program under G41 with the control's tool table (--tool-table): predict reads the
// compensated path (the tool centre a radius off the contour), says so, and compensate refuses
// to rewrite it at the G41's line; a program under G41 without the table is refused naming the
// option; a bad table names its file, line and word.
TEST_F(GcodeCli, CutterRadiusCompensationWithTheControlsToolTable) {
  const std::string m = src("resources/machines/linuxcnc_xyzac_trt.xml");
  std::ofstream(path("comp.ngc")) << "G21 G90 G17\nT2 M6\nG0 X-10 Y-10 Z5\nG1 Z-1 F300\n"
                                     "G41 G1 X0 Y0\nG1 X40\nG1 Y30\nG1 X0\nG1 Y0\nG40 G1 X-10 "
                                     "Y-10\nG0 Z5\nM2\n";
  std::ofstream(path("tools.tbl")) << "T1 P1 Z10 D6 ;6 mm end mill\nT2 P2 Z20 D10\n";
  auto r = test::runTolver("predict --machine " + m + " --nc " + path("comp.ngc") +
                           " --tool-table " + path("tools.tbl") + " -o " + path("p.apt"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("cutter radius compensation carried out"), std::string::npos) << r.output;
  // The square, run counter-clockwise with the tool on its left, is cut from inside: the tool
  // centre's inside corners, 5 mm in from each side, are in the predicted CL.
  const std::string cl = test::readText(path("p.apt"));
  for (const char* corner : {"GOTO/35.000000,5.000000,-1.0", "GOTO/35.000000,25.000000,-1.0",
                             "GOTO/5.000000,25.000000,-1.0"})
    EXPECT_NE(cl.find(corner), std::string::npos) << corner;
  // The entry move's point under its own line (compensation held it until line 6 was read).
  EXPECT_NE(cl.find("$$ line 5\nGOTO/-3.535534,3.535534"), std::string::npos) << cl;
  r = test::runTolver("compensate --machine " + m + " --nc " + path("comp.ngc") + " --tool-table " +
                      path("tools.tbl") + " -o " + path("c.ngc"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("comp.ngc:5"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("cutter radius compensation"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(path("c.ngc")));
  r = test::runTolver("predict --machine " + m + " --nc " + path("comp.ngc") + " -o " +
                      path("q.apt"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("comp.ngc:5"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("--tool-table"), std::string::npos) << r.output;
  std::ofstream(path("bad.tbl")) << "T1 P1 D6\nT2 P2 D1O\n";
  r = test::runTolver("predict --machine " + m + " --nc " + path("comp.ngc") + " --tool-table " +
                      path("bad.tbl") + " -o " + path("b.apt"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("bad.tbl:2:7: D"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(path("b.apt")));
  // On another control the table would do nothing: the option is refused by name.
  r = test::runTolver("predict --machine " + src("resources/machines/vmc_3axis_iso.xml") +
                      " --nc " + path("comp.ngc") + " --tool-table " + path("tools.tbl") + " -o " +
                      path("v.apt"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("--tool-table: LinuxCNC's tool table"), std::string::npos) << r.output;
}

TEST_F(GcodeCli, BadGcodeExitsWithCode2NamingTheLine) {
  std::ofstream(path("bad.nc")) << "G21 G90\nG0 X0 Y0 Z0\nG68 X0 Y0 R15\n";
  auto r = test::runTolver("predict --machine " + src("resources/machines/linuxcnc_xyzac_trt.xml") +
                           " --nc " + path("bad.nc") + " -o " + path("x.apt"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("bad.nc:3"), std::string::npos) << r.output;
  std::ofstream(path("tcp.nc")) << "G21\nM428\nG0 X0 Y0 Z0\n";
  r = test::runTolver("predict --machine " + src("resources/machines/trunnion_ac_trt.xml") +
                      " --nc " + path("tcp.nc") + " -o " + path("y.apt"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("declares no TCP words"), std::string::npos) << r.output;
  r = test::runTolver("predict --machine " + src("resources/machines/linuxcnc_xyzac_trt.xml") +
                      " --nc " + src("samples/gcode/boat-xyzac.ngc") + " --gauge-length -5 -o " +
                      path("z.apt"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  // A HEIDENHAIN program, conversational or DIN/ISO, whatever its extension and whichever
  // command reads it: refused by name at its first line (it was read as CL data, "the program
  // has no tool positions", or as G-code, "expected a word letter").
  std::ofstream(path("tnc.h")) << "0 BEGIN PGM PART MM\n1 BLK FORM 0.1 Z X+0 Y+0 Z-20\n"
                                  "2 TOOL CALL 1 Z S5000\n3 L X+10 Y+10 R0 FMAX\n"
                                  "4 END PGM PART MM\n";
  std::ofstream(path("tnc.nc")) << "%PART G71 *\nN10 G30 G17 X+0 Y+0 Z-40 *\n"
                                   "N20 G00 G40 G90 Z+100 *\nN99999999 %PART G71 *\n";
  const std::string vmc = src("resources/machines/vmc_3axis_iso.xml");
  for (const std::string& command :
       {"predict --machine " + vmc + " --cl " + path("tnc.h") + " -o " + path("t.apt"),
        "setup --machine " + vmc + " --cl " + path("tnc.h") + " -o " + path("t.txt"),
        "compensate --machine " + vmc + " --cl " + path("tnc.h") + " -o " + path("t2.apt")}) {
    r = test::runTolver(command);
    EXPECT_EQ(r.exit_code, 2) << command << r.output;
    EXPECT_NE(r.output.find("tnc.h:1:3: BEGIN PGM: a HEIDENHAIN conversational (Klartext)"),
              std::string::npos)
        << command << r.output;
  }
  r = test::runTolver("predict --machine " + vmc + " --nc " + path("tnc.nc") + " -o " +
                      path("t3.apt"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("tnc.nc:1:1: %: a HEIDENHAIN DIN/ISO program"), std::string::npos)
      << r.output;
  EXPECT_FALSE(fs::exists(path("t.apt")));
  // OpenSBP (FreeCAD's opensbp post, ShopBot): it read as CL data with "no tool positions".
  std::ofstream(path("part.sbp")) << "'Generated by FreeCAD\nSA\nMS,1.0,0.5\nJ2,0,0\n"
                                     "M3,1,1,-0.1\nEND\n";
  r = test::runTolver("predict --machine " + vmc + " --cl " + path("part.sbp") + " -o " +
                      path("t4.apt"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("part.sbp:2:1: SA: an OpenSBP (ShopBot) program"), std::string::npos)
      << r.output;
}

// The cone finish posted as TCP G-code for the LinuxCNC xyzac-trt machine (rotary words from
// the nominal inverse kinematics, 6 decimals on X Y Z and 9 on the angles), as a post would.
std::string postCone(const std::string& machine_file, const ClProgram& cl) {
  const Machine m = readMachineFile(machine_file);
  const InverseKinematics ik(m.model);
  std::string g = "%\n(cone finish posted by the test)\nG21 G90 G17\nM428\n";
  const JointVector* previous = nullptr;
  JointVector q;
  char buf[200];
  for (const ClPoint& c : cl.path) {
    const IkSolution s = ik.solve(c.p_w, c.u_w, previous);
    if (s.status != IkStatus::Ok) return "";
    q = s.q;
    previous = &q;
    std::snprintf(buf, sizeof buf, "%s X%.6f Y%.6f Z%.6f A%.9f C%.9f\n", c.rapid ? "G0" : "G1",
                  c.p_w.x(), c.p_w.y(), c.p_w.z(), q[3] * 180.0 / M_PI, q[4] * 180.0 / M_PI);
    g += buf;
  }
  return g + "M429\nM30\n%\n";
}

// verify end to end on a posted program with a part mesh: the same verdict and figures as the
// CL it was posted from (nominal machine: the program's share alone), through the written
// report.json.
TEST_F(GcodeCli, VerifyOnPostedGcodeWithAPartMeshMatchesTheClRun) {
  const std::string m = src("resources/machines/linuxcnc_xyzac_trt.xml");
  const ClProgram cl = readAptFile(src("samples/nas979_cone.apt"));
  const std::string g = postCone(m, cl);
  ASSERT_FALSE(g.empty());
  std::ofstream(path("cone.ngc")) << g;
  const std::string common = " --machine " + m + " --part " + src("samples/nas979_cone.stl") +
                             " --tolerance 0.05 --cutter 10,0,50 --no-images --spacing 1";
  auto a = test::runTolver("verify --cl " + src("samples/nas979_cone.apt") + common +
                           " --report-dir " + path("cl"));
  auto b =
      test::runTolver("verify --nc " + path("cone.ngc") + common + " --report-dir " + path("nc"));
  ASSERT_LE(a.exit_code, 1) << a.output;
  ASSERT_EQ(b.exit_code, a.exit_code) << b.output;
  EXPECT_NE(b.output.find("(G-code)"), std::string::npos) << b.output;
  EXPECT_NE(b.output.find("zero by construction"), std::string::npos) << b.output;
  std::ifstream ja(path("cl/report.json")), jb(path("nc/report.json"));
  const auto A = nlohmann::json::parse(ja), B = nlohmann::json::parse(jb);
  EXPECT_EQ(A["verdict"], B["verdict"]);
  const double ta = A["deviation"]["total"]["max_um"], tb = B["deviation"]["total"]["max_um"];
  EXPECT_NEAR(ta, tb, 0.05) << "max total deviation, um";
  EXPECT_NEAR(B["deviation"]["machine"]["max_um"].get<double>(), 0.0, 1e-9);
  // The program does machine the part (the comparison is not of two empty runs).
  EXPECT_GT(B["area"]["machined_mm2"].get<double>(), 1000.0) << B["area"];
}

// Units and tolerance plausibility: an inch part, a 30 meant as micrometres.
TEST_F(GcodeCli, VerifyRefusesImplausibleUnitsAndTolerances) {
  const std::string m = src("samples/machines/matsuura_mc760vx_measured.xml");
  const std::string base = " --machine " + m + " --setup " + src("samples/matsuura_setup.txt") +
                           " --cl " + src("samples/nas979_cone.apt") + " --no-images";
  auto r = test::runTolver("verify" + base + " --tolerance 30 --report-dir " + path("a"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("not a plausible profile tolerance"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(path("a")));
  // The part written in inches (scaled by 1/25.4) without --mesh-units.
  const std::string ascii =
      "solid cone\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 3.1 0 0\nvertex 0 3.1 0\n"
      "endloop\nendfacet\nfacet normal 0 0 1\nouter loop\nvertex 3.1 0 0\nvertex 3.1 3.1 0\n"
      "vertex 0 3.1 0\nendloop\nendfacet\nendsolid cone\n";
  std::ofstream(path("inch.stl")) << ascii;
  r = test::runTolver("verify" + base + " --tolerance 0.05 --part " + path("inch.stl") +
                      " --report-dir " + path("b"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("--mesh-units inch"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(path("b")));
}

// A real NX CLSF (MSYS, 800 mm long, tool axes down to 4 deg from horizontal) on the Matsuura
// (X 760, Y 510 mm of travel): no single set-up reaches it, which setup says with the lines the
// best one leaves outside, and then splits it into two pieces whose set-up files each reach
// every point of their lines; --absolute-msys puts the points in NX's absolute frame (in its
// MCS, whose z points down in that frame, every tool axis points down).
TEST_F(GcodeCli, SetupOnARealClsfSplitsItIntoPiecesThatEachReach) {
  const std::string machine = src("resources/machines/matsuura_mc760vx.xml");
  const std::string cl = src("tests/fixtures/cl/nx_ust_a.cls");
  auto r = test::runTolver("setup --machine " + machine + " --cl " + cl +
                           " --absolute-msys --gauge-length 100 -o " + path("s.txt"));
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("no single set-up reaches the whole program"), std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("MSYS at line 3 applied"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("-120.259, -1196.500, 142.500"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("extent     x -189.770 .. 130.866"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("2 set-ups reach the program, one piece each"), std::string::npos)
      << r.output;
  // The best single proposal is written and reads back; predict with it fails on as many
  // points as setup said it leaves outside.
  const size_t at = r.output.find("the best leaves ");
  ASSERT_NE(at, std::string::npos);
  const int outside = std::stoi(r.output.substr(at + 16));
  auto p = test::runTolver("predict --machine " + machine + " --cl " + cl +
                           " --absolute-msys --setup " + path("s.txt") + " -o " + path("p.apt"));
  EXPECT_EQ(p.exit_code, 2) << p.output;  // still out of travel, now by the figures setup gave
  EXPECT_NE(p.output.find("; " + std::to_string(outside) + " points fail"), std::string::npos)
      << outside << ": " << p.output;
  // Each piece's set-up file puts every point of its lines inside travel, and the pieces
  // cover the program.
  const Machine m = readMachineFile(machine);
  AptReadOptions absolute;
  absolute.absolute_msys = true;
  const ClProgram program = readAptFile(cl, absolute);
  size_t covered = 0;
  for (int k = 1; k <= 2; ++k) {
    const std::string f = path("s_part" + std::to_string(k) + ".txt");
    ASSERT_TRUE(fs::exists(f)) << r.output;
    const size_t w = r.output.find("piece " + std::to_string(k) + "  lines ");
    ASSERT_NE(w, std::string::npos) << r.output;
    const std::string range = r.output.substr(w + 15);
    const int first = std::stoi(range), last = std::stoi(range.substr(range.find('-') + 1));
    MachineModel model = m.model;
    model.setup = readSetupFile(f, model.setup);
    std::vector<ClPoint> piece;
    for (const ClPoint& c : program.path)
      if (c.line >= first && c.line <= last) piece.push_back(c);
    covered += piece.size();
    const PredictionResult pred = predictToolPath(model, m.params, piece);
    EXPECT_TRUE(pred.ok()) << f << ": " << pred.failed_points << " points outside travel";
    // And as a planner runs it: predict the piece with its set-up file and --lines.
    const std::string lines = std::to_string(first) + "-" + std::to_string(last);
    auto pr = test::runTolver("predict --machine " + machine + " --cl " + cl +
                              " --absolute-msys --setup " + f + " --lines " + lines + " -o " +
                              path("piece.apt"));
    EXPECT_EQ(pr.exit_code, 0) << pr.output;
    EXPECT_NE(pr.output.find(std::to_string(piece.size()) + " tool positions"), std::string::npos)
        << pr.output;
  }
  auto bad = test::runTolver("predict --machine " + machine + " --cl " + cl + " --lines 9-x -o " +
                             path("b.apt"));
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
  EXPECT_NE(bad.output.find("--lines"), std::string::npos) << bad.output;
  bad = test::runTolver("predict --machine " + machine + " --cl " + cl + " --lines 1-5 -o " +
                        path("b.apt"));
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
  EXPECT_FALSE(fs::exists(path("b.apt")));
  EXPECT_EQ(covered, program.path.size());
}

// A program that homes with G28 (every shop program does) has moves at the travel's ends
// whatever the work offset: setup says the margin its proposal chose (the work-offset moves,
// centred: Y's 0 .. 0 in 406 mm leaves 203 mm) and where the home moves are, not "smallest margin
// 0.000 mm" alone; the defaults it proposes are not warned about, the gauge length is.
TEST_F(GcodeCli, SetupSaysTheMarginOfTheWorkOffsetMovesBesideTheHomeMoves) {
  const std::string m = src("resources/machines/vmc_3axis_iso.xml");
  const std::string nc = write("home.nc",
                               "G21 G90 G54\nG0 X0 Y0 Z10\nG1 Z-1 F100\nX20\nG0 Z10\n"
                               "G91 G28 Z0\nG28 X0 Y0\nM30\n");
  auto s = test::runTolver("setup --machine " + m + " --nc " + nc + " -o " + path("s.txt"));
  ASSERT_EQ(s.exit_code, 0) << s.output;
  EXPECT_NE(s.output.find("the work-offset moves at least 203.000 mm from the travel's ends"),
            std::string::npos)
      << s.output;
  EXPECT_NE(s.output.find("in machine coordinates (G53/G28/SUPA) where the control puts them"),
            std::string::npos)
      << s.output;
  EXPECT_EQ(s.output.find("no set-up given"), std::string::npos) << s.output;
  EXPECT_NE(s.output.find("no gauge length given"), std::string::npos) << s.output;
  s = test::runTolver("setup --machine " + m + " --nc " + nc + " --gauge-length 50 -o " +
                      path("s2.txt"));
  EXPECT_EQ(s.output.find("no gauge length given"), std::string::npos) << s.output;
}

// A program that moves Z only in machine coordinates (G53 Z0, then X Y in the work offset; a
// LinuxCNC test of M73): setup wrote "part_zero_mm = -nan, -nan, -nan", which predict then
// refused. The part zero is placed along X and Y, left along Z, and said.
TEST_F(GcodeCli, SetupLeavesAnAxisTheProgramNeverMovesInTheWorkOffset) {
  const std::string m = src("resources/machines/linuxcnc_xyzac_trt.xml");
  const std::string nc =
      write("g53z.ngc", "G21 G90\nG53 G0 X0 Y0 Z0\nG91 G0 X10 Y10\nG0 X10\nM2\n");
  auto s = test::runTolver("setup --machine " + m + " --nc " + nc + " -o " + path("s.txt"));
  ASSERT_EQ(s.exit_code, 0) << s.output;
  EXPECT_EQ(s.output.find("nan"), std::string::npos) << s.output;
  EXPECT_NE(s.output.find("moves Z only in machine coordinates"), std::string::npos) << s.output;
  const std::string text = test::readText(path("s.txt"));
  EXPECT_EQ(text.find("nan"), std::string::npos) << text;
  s = test::runTolver("predict --machine " + m + " --nc " + nc + " --setup " + path("s.txt") +
                      " -o " + path("p.apt"));
  EXPECT_EQ(s.exit_code, 0) << s.output;
  // Every point placed by the program itself (G10 L2): no set-up file, and setup says so (it
  // was silent, and the next command's --setup could not be opened).
  const std::string own = write("g10.ngc", "G21 G90\nG10 L2 P1 X5 Y5 Z0\nG54 G0 X0 Y0 Z0\nM2\n");
  s = test::runTolver("setup --machine " + m + " --nc " + own + " -o " + path("o.txt"));
  EXPECT_EQ(s.exit_code, 0) << s.output;
  EXPECT_NE(s.output.find("o.txt not written"), std::string::npos) << s.output;
  EXPECT_FALSE(fs::exists(path("o.txt")));
}

// A program posted with the CAM's wear compensation (Fusion, Mastercam: G41 D.. on a tool-centre
// path): setup and predict refuse it naming the line and the option; with --cutter-comp wear both
// read it as written and say so.
TEST_F(GcodeCli, CutterCompensationNeedsTheUsersWord) {
  const std::string m = src("resources/machines/vmc_3axis_iso.xml");
  const std::string nc =
      write("wear.nc",
            "(T1 D=6 CR=0 - flat end mill)\nG21 G90 G54\nT1 M6\nG0 X-5 Y-5 Z10\nG1 Z-1 F100\n"
            "G41 D1 X0 Y0\nX20\nG3 X30 Y10 J10\nG40 G1 X35 Y15\nG0 Z10\nM30\n");
  auto s = test::runTolver("setup --machine " + m + " --nc " + nc + " -o " + path("s.txt"));
  EXPECT_EQ(s.exit_code, 2) << s.output;
  EXPECT_NE(s.output.find("wear.nc:6"), std::string::npos) << s.output;
  EXPECT_NE(s.output.find("--cutter-comp wear"), std::string::npos) << s.output;
  EXPECT_FALSE(fs::exists(path("s.txt")));
  s = test::runTolver("setup --machine " + m + " --nc " + nc + " --cutter-comp wear -o " +
                      path("s.txt"));
  ASSERT_EQ(s.exit_code, 0) << s.output;
  auto p = test::runTolver("predict --machine " + m + " --setup " + path("s.txt") + " --nc " + nc +
                           " --cutter-comp wear -o " + path("p.apt"));
  EXPECT_EQ(p.exit_code, 0) << p.output;
  EXPECT_NE(p.output.find("G41/G42 (first at line 6) read as wear compensation"), std::string::npos)
      << p.output;
  auto bad = test::runTolver("predict --machine " + m + " --setup " + path("s.txt") + " --nc " +
                             nc + " --cutter-comp full -o " + path("q.apt"));
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
  EXPECT_FALSE(fs::exists(path("q.apt")));
}

// A CL without UNITS whose tool and extent look like inches: predict says so and names the
// option; with --cl-units inch the points are scaled.
TEST_F(GcodeCli, ClWithoutUnitsThatLooksLikeInches) {
  std::ofstream(path("inch.apt")) << "MULTAX\nCUTTER/0.75\nGOTO/0.5,0.5,0.2,0,0,1\n"
                                     "GOTO/1.5,0.5,0.2,0,0,1\nGOTO/1.5,1.2,0.2,0,0,1\n";
  const std::string base = "predict --machine " + src("resources/machines/matsuura_mc760vx.xml") +
                           " --setup " + src("samples/matsuura_setup.txt") + " --cl " +
                           path("inch.apt");
  auto r = test::runTolver(base + " -o " + path("a.apt"));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("looks like inches"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("--cl-units inch"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("units MM (assumed)"), std::string::npos) << r.output;
  r = test::runTolver(base + " --cl-units inch -o " + path("b.apt"));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("units INCH"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("looks like inches"), std::string::npos) << r.output;
  const ClProgram back = readAptFile(path("b.apt"));
  ASSERT_EQ(back.path.size(), 3u);
  EXPECT_NEAR(back.path[1].p_w.x(), 1.5 * 25.4, 1e-6);  // written in inches, read back in mm
}

// A CL that declares inches over millimetres (Creo: 4r19415/5-axis-Rotation-tool-center-point-
// RTCP-, assets/finition.ncl, UNITS / INCHES over a 6 mm cutter, 7.6 m across read in inches):
// setup says the extent would fit in mm and names the option; --cl-units mm then holds over the
// statement, said with its line, and the written CL says how to read it back.
TEST_F(GcodeCli, DeclaredInchesThatAreMillimetres) {
  std::ofstream(path("mislabel.apt")) << "PARTNO/X\nUNITS / INCHES\nMULTAX / ON\n"
                                         "GOTO/0,0,20,0,0,1\nGOTO/250,0,20,0,0,1\n"
                                         "GOTO/250,150,20,0,0,1\nGOTO/0,150,5,0,0,1\n";
  const std::string m = " --machine " + src("resources/machines/vmc_3axis_iso.xml");
  auto r = test::runTolver("setup" + m + " --cl " + path("mislabel.apt") + " -o " + path("s.txt"));
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("declares UNITS/INCHES at line 2 and spans 7415 mm"), std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("read as mm it would span 291.9 mm"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("give --cl-units mm"), std::string::npos) << r.output;
  // --max-seconds bounds the split of a program no set-up reaches, and says where it stopped.
  r = test::runTolver("setup" + m + " --cl " + path("mislabel.apt") + " --max-seconds 1e-6 -o " +
                      path("s.txt"));
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("--max-seconds 1e-06 ran out while splitting the program: 0 piece(s) "
                          "found, covering 0 of 4 points; the rest is not split"),
            std::string::npos)
      << r.output;
  r = test::runTolver("setup" + m + " --cl-units mm --cl " + path("mislabel.apt") + " -o " +
                      path("s.txt"));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("declares UNITS/INCHES at line 2: read in mm, as --cl-units says"),
            std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("units MM"), std::string::npos) << r.output;
  r = test::runTolver("predict" + m + " --setup " + path("s.txt") + " --cl-units mm --cl " +
                      path("mislabel.apt") + " -o " + path("p.apt"));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  std::ifstream in(path("p.apt"));
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("not as UNITS at line 2 declares: read this file with --cl-units mm"),
            std::string::npos)
      << text;
  AptReadOptions ro;
  ro.unit_given = true;  // read back as the header says: the points are the program's
  const ClProgram back = readAptFile(path("p.apt"), ro);
  ASSERT_EQ(back.path.size(), 4u);
  EXPECT_NEAR(back.path[1].p_w.x(), 250.0, 1e-6);
  EXPECT_EQ(back.units_in_file, "INCH");
  // compensate's CL says the same of its numbers.
  r = test::runTolver("compensate" + m + " --setup " + path("s.txt") + " --cl-units mm --cl " +
                      path("mislabel.apt") + " -o " + path("c.apt"));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(test::readText(path("c.apt"))
                .find("not as UNITS at line 2 declares: read this file with --cl-units mm"),
            std::string::npos);
}

TEST_F(GcodeCli, SetupBadInputExitsWithCode2AndWritesNothing) {
  const std::string m = " --machine " + src("resources/machines/linuxcnc_xyzac_trt.xml");
  const std::string nc = " --nc " + src("samples/gcode/boat-xyzac.ngc");
  auto r = test::runTolver("setup" + m + nc + " --gauge-lengths 50,-3 -o " + path("s.txt"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("--gauge-lengths"), std::string::npos) << r.output;
  r = test::runTolver("setup" + m + nc + " -o " + path("missing/dir/s.txt"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  std::ofstream(path("empty.nc")) << "";
  r = test::runTolver("setup" + m + " --nc " + path("empty.nc") + " -o " + path("s.txt"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("empty.nc"), std::string::npos) << r.output;
  r = test::runTolver("setup" + m + " --cl " + src("samples/nas979_cone.apt") + nc);
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_FALSE(fs::exists(path("s.txt")));
}

}  // namespace
}  // namespace tolver
