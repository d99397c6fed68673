// G-code reader: the real LinuxCNC programs against an independent forward/inverse kinematics
// written from the LinuxCNC trt modules' equations (not from tolver's chain), joint-mode words,
// arcs, offsets, units and the refusals.
#include "io/program/gcode_reader.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <map>
#include <random>
#include <sstream>

#include "core/kinematics/forward_kinematics.h"
#include "core/numerics/units.h"
#include "core/path/tool_path_prediction.h"
#include "io/common/io_error.h"
#include "io/machine/machine_file.h"
#include "io/program/tool_table.h"
#include "test_support.h"

namespace tolver {
namespace {

constexpr double kDeg = M_PI / 180.0;

// LinuxCNC xyzac-trt-kins inverse (rotation points 0): joints from the controlled point pos =
// tip + dt ez in the part frame and the joint angles (rad). dy, dz: y-offset, z-offset.
Eigen::Vector3d xyzacInverse(const Eigen::Vector3d& pos, double a, double c, double dy, double dz,
                             double dt) {
  dz += dt;
  Eigen::Vector3d J;
  J.x() = std::cos(c) * pos.x() - std::sin(c) * pos.y();
  J.y() = std::sin(c) * std::cos(a) * pos.x() + std::cos(c) * std::cos(a) * pos.y() -
          std::sin(a) * pos.z() - std::cos(a) * dy + std::sin(a) * dz + dy;
  J.z() = std::sin(c) * std::sin(a) * pos.x() + std::cos(c) * std::sin(a) * pos.y() +
          std::cos(a) * pos.z() - std::sin(a) * dy - std::cos(a) * dz + dz;
  return J;
}
// Its forward: pos from joints.
Eigen::Vector3d xyzacForward(const Eigen::Vector3d& J, double a, double c, double dy, double dz,
                             double dt) {
  dz += dt;
  Eigen::Vector3d p;
  p.x() = std::cos(c) * J.x() + std::sin(c) * std::cos(a) * (J.y() - dy) +
          std::sin(c) * std::sin(a) * (J.z() - dz) + std::sin(c) * dy;
  p.y() = -std::sin(c) * J.x() + std::cos(c) * std::cos(a) * (J.y() - dy) +
          std::cos(c) * std::sin(a) * (J.z() - dz) + std::cos(c) * dy;
  p.z() = -std::sin(a) * (J.y() - dy) + std::cos(a) * (J.z() - dz) + dz;
  return p;
}
// LinuxCNC xyzbc-trt-kins inverse (rotation points 0).
Eigen::Vector3d xyzbcInverse(const Eigen::Vector3d& pos, double b, double c, double dx, double dz,
                             double dt) {
  dz += dt;
  const double dpx = -std::cos(b) * dx - std::sin(b) * dz + dx;
  const double dpz = std::sin(b) * dx - std::cos(b) * dz + dz;
  Eigen::Vector3d J;
  J.x() = std::cos(c) * std::cos(b) * pos.x() - std::sin(c) * std::cos(b) * pos.y() +
          std::sin(b) * pos.z() + dpx;
  J.y() = std::sin(c) * pos.x() + std::cos(c) * pos.y();
  J.z() = -std::cos(c) * std::sin(b) * pos.x() + std::sin(c) * std::sin(b) * pos.y() +
          std::cos(b) * pos.z() + dpz;
  return J;
}

Machine machine(const char* rel, double gauge = 0.0) {
  Machine m = readMachineFile(test::sourcePath(rel));
  m.model.setup.gauge_length = gauge;
  return m;
}

// Every point of the real program: tolver's joints (nominal IK, rotaries as commanded) equal
// LinuxCNC's inverse kinematics of the program's XYZ and rotary words.
bool hasNote(const ClProgram& p, const std::string& text) {
  for (const std::string& n : p.notes)
    if (n.find(text) != std::string::npos) return true;
  return false;
}

TEST(GcodeReader, BoatXyzacMatchesLinuxCncKinematics) {
  for (double dt : {0.0, 25.0}) {
    const Machine m = machine("resources/machines/linuxcnc_xyzac_trt.xml", dt);
    const ClProgram p =
        readGcodeFile(test::sourcePath("tests/fixtures/gcode/linuxcnc_boat-xyzac.ngc"), m.model);
    ASSERT_GT(p.path.size(), 1800u);
    EXPECT_EQ(p.units, "MM");
    EXPECT_FALSE(p.units_declared);
    const PredictionResult r = predictToolPath(m.model, m.params, p.path, 20, &p.joints);
    ASSERT_TRUE(r.ok()) << r.failures.front().message << " line " << r.failures.front().line;
    int tcp = 0;
    double worst = 0.0, worst_axis = 0.0;
    for (size_t i = 0; i < p.path.size(); ++i) {
      if (!p.tcp[i]) continue;
      ++tcp;
      const JointVector& q = r.points[i].q;
      const double a = q[3], c = q[4];
      EXPECT_NEAR(a, p.joints[i][3], 1e-12) << "line " << p.path[i].line;
      EXPECT_NEAR(c, p.joints[i][4], 1e-12) << "line " << p.path[i].line;
      const Eigen::Vector3d pos = p.path[i].p_w + dt * Eigen::Vector3d::UnitZ();
      const Eigen::Vector3d J = xyzacInverse(pos, a, c, 20, 10, dt);
      worst = std::max(worst, (J - q.head<3>()).norm());
      const Eigen::Vector3d u(std::sin(c) * std::sin(a), std::cos(c) * std::sin(a), std::cos(a));
      worst_axis = std::max(worst_axis, (u - p.path[i].u_w).norm());
    }
    EXPECT_GT(tcp, 1800);
    EXPECT_LT(worst, 1e-9) << "dt " << dt;
    EXPECT_LT(worst_axis, 1e-12);
  }
}

TEST(GcodeReader, BoatXyzbcMatchesLinuxCncKinematics) {
  const Machine m = machine("resources/machines/linuxcnc_xyzbc_trt.xml", 50.0);
  const ClProgram p =
      readGcodeFile(test::sourcePath("tests/fixtures/gcode/linuxcnc_boat-xyzbc.ngc"), m.model);
  const PredictionResult r = predictToolPath(m.model, m.params, p.path, 20, &p.joints);
  ASSERT_TRUE(r.ok()) << r.failures.front().message;
  double worst = 0.0;
  for (size_t i = 0; i < p.path.size(); ++i) {
    const JointVector& q = r.points[i].q;
    const Eigen::Vector3d J =
        xyzbcInverse(p.path[i].p_w + 50.0 * Eigen::Vector3d::UnitZ(), q[3], q[4], -20, -15, 50.0);
    worst = std::max(worst, (J - q.head<3>()).norm());
    const Eigen::Vector3d u(-std::cos(q[4]) * std::sin(q[3]), std::sin(q[4]) * std::sin(q[3]),
                            std::cos(q[3]));
    EXPECT_LT((u - p.path[i].u_w).norm(), 1e-12) << "line " << p.path[i].line;
  }
  EXPECT_LT(worst, 1e-9);
}

// Outside TCP mode the words are joints: the tip is LinuxCNC's forward kinematics of them.
TEST(GcodeReader, JointWordsGiveLinuxCncForwardKinematics) {
  const Machine m = machine("resources/machines/linuxcnc_xyzac_trt.xml", 40.0);
  const ClProgram p = parseGcode(
      "G21 G90\nM429\nG43 H1\nG0 X10 Y-20 Z30 A-25 C40\nG1 X-15 Y5 Z-12 A10 C-130\nG1 A-60 C400\n",
      "joint.ngc", m.model);
  ASSERT_EQ(p.path.size(), 3u);
  const double words[3][5] = {
      {10, -20, 30, -25, 40}, {-15, 5, -12, 10, -130}, {-15, 5, -12, -60, 400}};
  for (int k = 0; k < 3; ++k) {
    const double a = words[k][3] * kDeg, c = words[k][4] * kDeg;
    // G43 H1 with no tool table: H1 is the gauge length, so the joint is word + 40 on Z and the
    // controlled point (the tip) is the word.
    const Eigen::Vector3d J(words[k][0], words[k][1], words[k][2] + 40.0);
    const Eigen::Vector3d tip =
        xyzacForward(J, a, c, 20, 10, 40.0) - 40.0 * Eigen::Vector3d::UnitZ();
    EXPECT_LT((tip - p.path[k].p_w).norm(), 1e-9) << k;
    EXPECT_NEAR(p.joints[k][2], J.z(), 1e-12);
    EXPECT_NEAR(p.joints[k][4], c, 1e-12);
  }
}

// The table-dual-rotary demo: parameters from the control, G10 L2/L20, G53, M61, G43.
TEST(GcodeReader, ReadsTheTableDualRotaryDemoWithControlParameters) {
  const Machine m = machine("tests/fixtures/machines/xyzab_tdr_like.xml", 30.0);
  const ClProgram p =
      readGcodeFile(test::sourcePath("tests/fixtures/gcode/linuxcnc_xyzab-tdr-demo.ngc"), m.model);
  EXPECT_GT(p.path.size(), 25u);
  EXPECT_TRUE(p.units_declared);
  // Without the control's HAL pins the same program names the line and the pin.
  Machine bare = m;
  bare.model.control.parameters.clear();
  try {
    readGcodeFile(test::sourcePath("tests/fixtures/gcode/linuxcnc_xyzab-tdr-demo.ngc"), bare.model);
    FAIL() << "expected an error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.line(), 10);
    EXPECT_NE(std::string(e.what()).find("_hal[xyzab_tdr_kins.x-rot-point]"), std::string::npos)
        << e.what();
  }
}

// A HAAS-style inch program: BOM, CRLF, listing header, G20, G234/G49, G254/G255, arcs in both
// forms, multi-turn C on an endless axis, G53 and G28.
TEST(GcodeReader, InchHaasProgramWithTcpAndDwo) {
  Machine m = machine("resources/machines/umc_bc_trunnion.xml", 76.2);
  const ClProgram p =
      readGcodeFile(test::sourcePath("tests/fixtures/gcode/umc_bc_inch.nc"), m.model);
  EXPECT_EQ(p.units, "INCH");
  // N70 G02 X0.5 Y0.5 I0.5 J0: a quarter circle about (0.5, 0) in the part frame, clockwise.
  int arc_points = 0;
  for (size_t i = 0; i < p.path.size(); ++i)
    if (p.path[i].line == 10) {
      ++arc_points;
      EXPECT_NEAR((p.path[i].p_w.head<2>() - Eigen::Vector2d(12.7, 0)).norm(), 12.7, 1e-9);
      EXPECT_NEAR(p.path[i].p_w.z(), 2.54, 1e-9);
    }
  EXPECT_GT(arc_points, 10);
  // The R arc of N80 ends at (1, 0) inch.
  const ClPoint* end80 = nullptr;
  for (const ClPoint& c : p.path)
    if (c.line == 11) end80 = &c;
  ASSERT_NE(end80, nullptr);
  EXPECT_LT((end80->p_w - Eigen::Vector3d(25.4, 0, 2.54)).norm(), 1e-9);
  // N100: C-400 is kept as a multi-turn joint value (the table turns +400: HAAS and ISO 841
  // give the tool's sense); the tool axis follows B30 C-400.
  for (size_t i = 0; i < p.path.size(); ++i)
    if (p.path[i].line == 13) {
      EXPECT_NEAR(p.joints[i][4], 400 * kDeg, 1e-12);  // nc_sign -1
    }
  const PredictionResult r = predictToolPath(m.model, m.params, p.path, 20, &p.joints);
  EXPECT_TRUE(r.ok()) << (r.ok() ? "" : r.failures.front().message);
}

TEST(GcodeReader, ArcFormsAgreeAndIncrementalMovesAdd) {
  const Machine m = machine("resources/machines/linuxcnc_xyzac_trt.xml", 0.0);
  const ClProgram ijk =
      parseGcode("G21 M428\nG0 X0 Y0 Z0 A0 C0\nG3 X-10 Y10 I-10 J0\n", "a.ngc", m.model);
  const ClProgram r =
      parseGcode("G21 M428\nG0 X0 Y0 Z0 A0 C0\nG3 X-10 Y10 R10\n", "b.ngc", m.model);
  ASSERT_EQ(ijk.path.size(), r.path.size());
  for (size_t i = 0; i < r.path.size(); ++i)
    EXPECT_LT((ijk.path[i].p_w - r.path[i].p_w).norm(), 1e-9);
  const ClProgram inc =
      parseGcode("G21 M428\nG0 X1 Y2 Z3 A0 C0\nG91 G1 X1 Y1 Z-1\nX1\n", "c.ngc", m.model);
  EXPECT_LT((inc.path.back().p_w - Eigen::Vector3d(3, 3, 2)).norm(), 1e-12);
}

// A control whose TCP words are names (Siemens TRAORI / TRAFOOF).
TEST(GcodeReader, NamedTcpWords) {
  Machine m = machine("resources/machines/linuxcnc_xyzac_trt.xml", 0.0);
  m.model.control.tcp_words = {{"TRAORI", "TRAFOOF"}};
  const ClProgram p = parseGcode("G21\nTRAORI\nG1 X10 Y5 Z2 A-30 C20\nTRAFOOF\nG1 X0 Y0 Z0 A0 C0\n",
                                 "siemens.mpf", m.model);
  ASSERT_EQ(p.path.size(), 2u);
  EXPECT_TRUE(p.tcp[0]);
  EXPECT_FALSE(p.tcp[1]);
  EXPECT_LT((p.path[0].p_w - Eigen::Vector3d(10, 5, 2)).norm(), 1e-12);
}

TEST(GcodeReader, DrillingCycleBecomesStraightMoves) {
  const Machine m = machine("resources/machines/linuxcnc_xyzac_trt.xml", 0.0);
  const ClProgram p = parseGcode(
      "G21 M428\nG0 X0 Y0 Z20 A0 C0\nG98 G81 X5 Y6 Z-3 R2 F100\nX8\nG80\n", "d.ngc", m.model);
  // Per hole: over it at the clearance, down to R, feed to Z, back to the initial height.
  ASSERT_EQ(p.path.size(), 9u);
  EXPECT_LT((p.path[3].p_w - Eigen::Vector3d(5, 6, -3)).norm(), 1e-12);
  EXPECT_FALSE(p.path[3].rapid);
  EXPECT_LT((p.path[4].p_w - Eigen::Vector3d(5, 6, 20)).norm(), 1e-12);
  EXPECT_LT((p.path[7].p_w - Eigen::Vector3d(8, 6, -3)).norm(), 1e-12);
}

// Refusals name file and line; harmless unknown words are listed, not dropped silently.
TEST(GcodeReader, RefusesWhatItCannotCarryOutWithFileAndLine) {
  const Machine m = machine("resources/machines/linuxcnc_xyzac_trt.xml", 0.0);
  struct Case {
    const char* text;
    int line;
    const char* says;
  };
  const Case cases[] = {
      {"G21\nG0 X0 Y0 Z0\nG68 X0 Y0 R30\n", 3, "rotation"},
      {"G21\nG41 D1\n", 2, "cutter radius compensation"},
      {"G21\nG0 X0 Y0 Z0\nG1 X10 ,R2 F100\n", 3, "corner rounding (,R"},
      {"G21\nG0 X0 Y0 Z0\nG91 G53 G0 Z10\n", 3, "in G91: controls differ"},
      {"G21\nG0 X0 Y-5 Z0\nG91 G3 I-5 Z-1 L5 F100\n", 3, "L on an arc"},
      // A frame change with no axis words is refused, not noted as an unknown code.
      {"G21\nG0 X0 Y0 Z0\nG68.3\nG0 X1\n", 3, "G68.3"},
      {"G21\nG0 X0 Y0 Z0\nG54.2 P1\nG0 X1\n", 3, "dynamic fixture offset"},
      {"G21\nG0 X0 Y0 Z0\nG43.8 H1\nG0 X1\n", 3, "cutting point"},
      {"G21\nG0 X0 Y0 Z0\nG1 X10 ,C1 F100\n", 3, "chamfering (,C"},
      {"G21\nM98 P1000\n", 2, "subprogram"},
      {"G21\no100 call\n", 2, "no o100 sub defined above it"},
      {"G21\nG0 X0 Y0 Z0\nWHILE [#1 LT 3] DO1\n", 3, "WHILE: Fanuc macro B's"},
      {"G21\nG0 X0 Y0 Z0\nIF [#1 GT 2] GOTO 10\n", 3, "IF: Fanuc macro B's"},
      {"G21\nG0 X0 Y0 Z0 B10\n", 2, "axis B"},
      {"G21\nG43.4 H1\n", 2, "does not use"},
      {"G21\nG0 X1.2.3\n", 2, "malformed"},
      {"G21\nG0 X0 Y0 Z0 A70\n", 2, "outside the travel"},
      {"G21\nG0 X(unclosed\n", 2, "unclosed comment"},
      {"(only a comment)\n", 0, "no moves"},
      {"", 0, "empty file"},
      {"G21\nG0 X99999999999\n", 2, "plausible"},
      {"G21\nG1 X[1/0]\n", 2, "division by zero"},
      // The fuzzer's input (tests/fuzz): thousands of signs made the expression parser's
      // recursion overflow the stack.
      {"G21\ng2++++++++++++++++++++++++++++++++++++++++++++++++++++++++++++++++++++++++++\n", 2,
       "nested deeper"},
  };
  for (const Case& c : cases) {
    try {
      parseGcode(c.text, "bad.ngc", m.model);
      ADD_FAILURE() << "accepted: " << c.text;
    } catch (const InputError& e) {
      EXPECT_EQ(e.line(), c.line) << c.text << " -> " << e.what();
      EXPECT_NE(std::string(e.what()).find(c.says), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("bad.ngc"), std::string::npos);
    }
  }
  // Arc expansion is bounded before anything is expanded.
  GcodeReadOptions fine;
  fine.chordal_tolerance_mm = 1e-6;
  try {
    parseGcode("G21 M428\nG0 X0 Y0 Z0 A0 C0\nG2 X0 Y0 I900000 J0\n", "arc.ngc", m.model, fine);
    ADD_FAILURE() << "accepted a huge arc";
  } catch (const InputError& e) {
    EXPECT_EQ(e.line(), 3);
    EXPECT_NE(std::string(e.what()).find("more than a million"), std::string::npos) << e.what();
  }
  // A TCP word on a machine whose file declares no control.
  const Machine plain = machine("resources/machines/trunnion_ac_trt.xml", 0.0);
  try {
    parseGcode("G21\nM428\nG0 X0 Y0 Z0\n", "tcp.ngc", plain.model);
    ADD_FAILURE() << "accepted M428 without TCP words";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("declares no TCP words"), std::string::npos) << e.what();
  }
  // A code tolver does not know is named with its line as unknown, not as harmless (M123; M8 is
  // known: coolant); G64 is known not to move the tool and is not listed.
  const ClProgram p = parseGcode("G21 G64 P0.01\nM123\nG0 X0 Y0 Z0 A0 C0 M8\n", "ok.ngc", m.model);
  EXPECT_TRUE(hasNote(p,
                      "codes tolver does not know, read as not moving the tool (check what "
                      "they do on the control): M123 (line 2)"));
  for (const std::string& n : p.notes) {
    EXPECT_EQ(n.find("M8"), std::string::npos) << n;
    EXPECT_EQ(n.find("G64"), std::string::npos) << n;
  }
  // The default work offset is said to be the default, not "used" by a block that never names it
  // (a Rotrix DexArm program: G21, then moves); a selected one is named with its first line.
  const Machine vmc = machine("resources/machines/vmc_3axis_iso.xml", 0.0);
  const ClProgram d = parseGcode("G21\nG0 X1 Y2 Z5\n", "default.gcode", vmc.model);
  EXPECT_TRUE(hasNote(d,
                      "G54 (the control's default work offset: the program never selects one; "
                      "in force from line 2)"));
  const ClProgram g = parseGcode("G21\nG0 X1 Y2 Z5\nG55 G0 X2\n", "g55.gcode", vmc.model);
  EXPECT_TRUE(hasNote(g, "G55 (first used at line 3) is not in the set-up"));
}

// Mutated lines of the real program: the reader either reads or throws InputError naming the
// file; never another exception, a crash or a non-finite point.
// The fuzzer's input itself (5 kB of '+' after a BOM and a comment): an error naming the line.
TEST(GcodeReader, DeepExpressionNestingIsAnErrorNotAStackOverflow) {
  const Machine m = machine("resources/machines/linuxcnc_xyzac_trt.xml", 0.0);
  const std::string text =
      test::readText(test::sourcePath("tests/fuzz/gcode_corpus/deep_signs.ngc"));
  for (const std::string& t :
       {text, "G21\nG0 X" + std::string(100000, '[') + "1\n",
        "G21\nG0 X" + std::string(100000, '-') + "1\n", "#1=" + std::string(100000, '#') + "1\n"}) {
    try {
      parseGcode(t, "deep.ngc", m.model);
      FAIL() << "no error";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("deep.ngc:"), std::string::npos) << e.what();
    }
  }
}

// Numbered parameters are LinuxCNC's: an integer number from 1 to 5601. The G-code harness found
// "#1111...1" (35 digits) read as a parameter number: a double of 1.1e35 cast to int (undefined
// behaviour). Now each such number is an error naming the line; good numbers still read.
TEST(GcodeReader, AParameterNumberOutOfRangeOrNotAnIntegerIsAnError) {
  const Machine m = machine("resources/machines/linuxcnc_xyzac_trt.xml", 0.0);
  const std::string found =
      test::readText(test::sourcePath("tests/fuzz/gcode_corpus/huge_parameter_number.ngc"));
  const std::vector<std::pair<std::string, std::string>> bad = {
      {found, "out of range"},
      {"G21\nG0 X#" + std::string(35, '1') + "\n", "out of range"},
      {"G21\n#0=1\n", "out of range"},
      {"G21\n#5602=1\n", "out of range"},
      {"G21\n#-3=1\n", ""},
      {"G21\n#1=2\nG0 X#[0.5]\n", "not an integer"},
      {"G21\n#1.5=2\n", "not an integer"},
      {"G21\n#1=2\nG0 X#1.5\n", "not an integer"},
      {"G21\n#1=2\nG0 X#[1e300]\n", ""}};
  for (const auto& [text, why] : bad) {
    try {
      parseGcode(text, "par.ngc", m.model);
      FAIL() << "no error: " << text.substr(0, 60);
    } catch (const InputError& e) {
      const std::string w = e.what();
      EXPECT_NE(w.find("par.ngc:"), std::string::npos) << w;
      EXPECT_NE(w.find(why), std::string::npos) << w;
      EXPECT_LT(w.size(), 300u) << w;
    }
  }
  const ClProgram p =
      parseGcode("G21\n#5601=2\n#1=3.00001\nG0 X#5601 Y#1 Z0 A0 C0\n", "ok.ngc", m.model);
  ASSERT_FALSE(p.path.empty());
}

TEST(GcodeReader, MutatedProgramsFailCleanly) {
  const Machine m = machine("resources/machines/linuxcnc_xyzac_trt.xml", 0.0);
  const std::string base =
      test::readText(test::sourcePath("tests/fixtures/gcode/linuxcnc_boat-xyzac.ngc"));
  std::mt19937 rng(7);
  const std::string junk = "XYZACGMIJKR#[]()-+.;/%0123456789eE\xff\x00 ";
  int errors = 0;
  for (int n = 0; n < 300; ++n) {
    std::string text = base.substr(0, 6000);
    for (int k = 0; k < 4; ++k) {
      const size_t at = rng() % text.size();
      text[at] = junk[rng() % junk.size()];
    }
    try {
      const ClProgram p = parseGcode(text, "mutated.ngc", m.model);
      for (const ClPoint& c : p.path) ASSERT_TRUE(c.p_w.allFinite() && c.u_w.allFinite());
    } catch (const InputError& e) {
      ++errors;
      EXPECT_NE(std::string(e.what()).find("mutated.ngc"), std::string::npos);
      EXPECT_LT(std::string(e.what()).size(), 600u);
    }
  }
  EXPECT_GT(errors, 20);
}

TEST(GcodeReader, DetectsGcodeAgainstApt) {
  EXPECT_TRUE(looksLikeGcode("%\nO1000\nN10 G21 G90\nG0 X0 Y0\n"));
  EXPECT_TRUE(looksLikeGcode("\xEF\xBB\xBF; comment\nM428\nG0 X0\n"));
  EXPECT_FALSE(looksLikeGcode("PARTNO/X\nMULTAX\nGOTO/0,0,0,0,0,1\n"));
  EXPECT_FALSE(looksLikeGcode("$$ header\nTOOL PATH/A\nGOTO/1,2,3\n"));
  EXPECT_TRUE(looksLikeGcode(
      test::readText(test::sourcePath("tests/fixtures/gcode/linuxcnc_boat-xyzbc.ngc"))));
}

// ---------------------------------------------------------------- issue 32: ISO as controls read
// it

// The Sinumerik B/C table with G54 at (-300, 0, 200) in machine coordinates, as the NX
// programs' tests set it.
Machine sinumerikMachine() {
  Machine m = machine("resources/machines/sinumerik_bc_table.xml", 0.0);
  m.model.setup.work_offsets["G54"] = Eigen::Vector3d(-300, 0, 200);
  return m;
}

std::string refusal(const std::string& text, const MachineModel& model) {
  try {
    parseGcode(text, "r.nc", model);
  } catch (const InputError& e) {
    return e.what();
  }
  return "accepted";
}

// Cutter radius compensation: the file cannot say whether its D registers hold the tool's radius
// (the path is the part's contour) or only its wear (the path is the tool centre, as Fusion's
// and Mastercam's "wear" compensation post it). Refused by default, naming the way out; with the
// user's word (--cutter-comp wear) the path is read as written, the same points as without the
// G41/G40 words, said in a note. LinuxCNC's G41.1 (the diameter in the program) stays refused.
TEST(GcodeReader, CutterCompensationReadAsWearOnlyByTheUsersWord) {
  const Machine vmc = machine("resources/machines/vmc_3axis_iso.xml", 0.0);
  const std::string with_comp =
      "G21 G90\nG0 X-5 Y-5 Z5\nG1 Z-1 F300\nG41 D1 G1 X0 Y0\nX20\nG3 X30 Y10 I0 J10\n"
      "G40 G1 X35 Y15\nM30\n";
  const std::string without =
      "G21 G90\nG0 X-5 Y-5 Z5\nG1 Z-1 F300\nG1 X0 Y0\nX20\nG3 X30 Y10 I0 J10\n"
      "G1 X35 Y15\nM30\n";
  const std::string refused = refusal(with_comp, vmc.model);
  EXPECT_NE(refused.find("r.nc:4"), std::string::npos) << refused;
  EXPECT_NE(refused.find("G41"), std::string::npos) << refused;
  EXPECT_NE(refused.find("--cutter-comp wear"), std::string::npos) << refused;
  GcodeReadOptions wear;
  wear.cutter_comp_wear = true;
  const ClProgram a = parseGcode(with_comp, "wear.nc", vmc.model, wear);
  const ClProgram b = parseGcode(without, "plain.nc", vmc.model);
  ASSERT_EQ(a.path.size(), b.path.size());
  ASSERT_GT(a.path.size(), 10u);  // the arc expanded
  for (size_t i = 0; i < a.path.size(); ++i)
    EXPECT_EQ((a.path[i].p_w - b.path[i].p_w).norm(), 0.0) << i;
  EXPECT_TRUE(hasNote(a, "G41/G42 (first at line 4) read as wear compensation"));
  EXPECT_FALSE(hasNote(b, "wear compensation"));
  // A block-delete line runs, as with the switch off, and is said.
  const ClProgram slash =
      parseGcode("G21\nG0 X0 Y0 Z0\n/G0 X9\n/G0 X8\nG0 X1\n", "bd.nc", vmc.model);
  EXPECT_EQ(slash.path.size(), 4u);
  EXPECT_TRUE(
      hasNote(slash, "2 block(s) marked '/' (block delete, the first at line 3) read as run"));
  // A program whose post writes "15." and which also writes "Z-1" (a hand edit): on a Fanuc
  // with DPI = 0 the latter is 1 um, said on an ISO control; not for zeros, not on LinuxCNC,
  // not when every number goes without a point.
  const ClProgram mixed = parseGcode("G21\nG0 X0 Y0 Z15.\nG1 Z-1 F100\n", "dp.nc", vmc.model);
  EXPECT_TRUE(hasNote(mixed,
                      "(the first, Z-1, at line 3) read in mm: a Fanuc control with "
                      "parameter 3401#0 DPI = 0"));
  EXPECT_FALSE(hasNote(parseGcode("G21\nG0 X0 Y0 Z15\nG1 Z-1 F100\n", "i.nc", vmc.model), "DPI"));
  EXPECT_FALSE(hasNote(parseGcode("G21\nG0 X0 Y0 Z15.\nG1 Z0 F100\n", "z.nc", vmc.model), "DPI"));
  // G42 likewise; G41.1 (a diameter in the program) is refused even so.
  const ClProgram right =
      parseGcode("G21\nG0 X0 Y0 Z5\nG42 G1 X10 F100\nG40 X20\n", "r42.nc", vmc.model, wear);
  EXPECT_TRUE(hasNote(right, "first at line 3"));
  try {
    parseGcode("G21\nG0 X0 Y0 Z5\nG41.1 D6 G1 X10 F100\n", "d.ngc", vmc.model, wear);
    ADD_FAILURE() << "G41.1 read";
  } catch (const InputError& e) {
    EXPECT_EQ(e.line(), 3) << e.what();
    EXPECT_NE(std::string(e.what()).find("G41.1"), std::string::npos) << e.what();
  }
}

// Drilling cycles in G91 and repeats, by the documented formulas (Fanuc 0i-MF, HAAS, LinuxCNC's
// interp_cycles.cc after NCMS p. 98): R from the initial level, Z from the R point, X Y from the
// current position, L (or K on an ISO control) holes at the same increments. Hand values: from
// Z100 at (10, 20), "G91 G81 X5 Y0 R-98 Z-12 L3" drills at X15, X20, X25, R plane 2, bottom -10,
// back to the initial level 100 (G98).
TEST(GcodeReader, DrillingCyclesInG91AndTheirRepeats) {
  const Machine vmc = machine("resources/machines/vmc_3axis_iso.xml", 0.0);
  const std::string head = "G21 G90 G54\nG0 X10 Y20 Z100\nG98\n";
  const ClProgram p =
      parseGcode(head + "G91 G81 X5 Y0 R-98 Z-12 L3 F50\nG80\nM30\n", "inc.nc", vmc.model);
  ASSERT_EQ(p.path.size(), 1u + 3u * 4u);
  EXPECT_EQ(p.cycle_holes, 3);
  for (int k = 0; k < 3; ++k) {
    const double x = 15.0 + 5.0 * k;
    EXPECT_LT((p.path[1 + 4 * k].p_w - Eigen::Vector3d(x, 20, 100)).norm(), 1e-9) << k;
    EXPECT_LT((p.path[2 + 4 * k].p_w - Eigen::Vector3d(x, 20, 2)).norm(), 1e-9) << k;
    EXPECT_LT((p.path[3 + 4 * k].p_w - Eigen::Vector3d(x, 20, -10)).norm(), 1e-9) << k;
    EXPECT_FALSE(p.path[3 + 4 * k].rapid);
    EXPECT_LT((p.path[4 + 4 * k].p_w - Eigen::Vector3d(x, 20, 100)).norm(), 1e-9) << k;
  }
  // Fanuc's K repeats on an ISO control; in G90 a repeat drills the same place again.
  const ClProgram k =
      parseGcode(head + "G91 G81 X0 Y-4 R-98 Z-12 K2 F50\nG80\n", "k.nc", vmc.model);
  ASSERT_EQ(k.cycle_holes, 2);
  EXPECT_LT((k.path[7].p_w - Eigen::Vector3d(10, 12, -10)).norm(), 1e-9);
  const ClProgram same = parseGcode(head + "G81 X1 Y1 R2 Z-3 L2 F50\nG80\n", "s.nc", vmc.model);
  ASSERT_EQ(same.cycle_holes, 2);
  EXPECT_LT((same.path[7].p_w - Eigen::Vector3d(1, 1, -3)).norm(), 1e-9);
  // Refused: R and Z kept from G91 and used in G90 (controls differ), a bottom above R.
  const std::string mixed = refusal(head + "G91 G81 X5 R-98 Z-12 F50\nG90 X40\n", vmc.model);
  EXPECT_NE(mixed.find("r.nc:5"), std::string::npos) << mixed;
  EXPECT_NE(mixed.find("give R and Z again"), std::string::npos) << mixed;
  EXPECT_EQ(refusal(head + "G91 G81 X5 R-98 Z-12 F50\nG90 X40 R2 Z-3\nG80\n", vmc.model),
            "accepted");
  EXPECT_NE(refusal(head + "G91 G81 X5 R-98 Z12 F50\n", vmc.model).find("above the R point"),
            std::string::npos);
  EXPECT_NE(refusal(head + "G81 X5 R2 Z-3 L2.5 F50\n", vmc.model).find("whole number"),
            std::string::npos);
}

// An arc whose end is off its circle but on it with I J read as the centre's absolute
// coordinates: the post wrote absolute centres (MaestroFusion360/easy_gcode_plot's
// CONTOUR_ABS.NC, BOTTLE.NC). The refusal says so and names G90.1; with G90.1 the arc reads, and
// an arc wrong either way gets no hint.
TEST(GcodeReader, ArcRefusalSaysWhenTheCentresAreAbsolute) {
  const Machine vmc = machine("resources/machines/vmc_3axis_iso.xml", 0.0);
  const std::string arc = "G0 X10 Y5 Z0\nG3 X5 Y10 I5 J5 F100\n";
  const std::string e = refusal("G21\n" + arc, vmc.model);
  EXPECT_NE(e.find("r.nc:3"), std::string::npos) << e;
  EXPECT_NE(e.find("the post wrote absolute arc centres"), std::string::npos) << e;
  EXPECT_NE(e.find("G90.1"), std::string::npos) << e;
  const ClProgram p = parseGcode("G21 G90.1\n" + arc, "abs.nc", vmc.model);
  EXPECT_LT((p.path.back().p_w - Eigen::Vector3d(5, 10, 0)).norm(), 1e-9);
  EXPECT_EQ(p.arcs_expanded, 1);
  const std::string neither = refusal("G21\nG0 X10 Y5 Z0\nG3 X5 Y10 I7 J5 F100\n", vmc.model);
  EXPECT_NE(neither.find("not on the arc's circle"), std::string::npos) << neither;
  EXPECT_EQ(neither.find("absolute arc centres"), std::string::npos) << neither;
  // Under G90.1, centres written incremental get the other hint.
  const std::string inc = refusal("G21 G90.1\nG0 X10 Y5 Z0\nG3 X5 Y10 I-5 J0 F100\n", vmc.model);
  EXPECT_NE(inc.find("the post wrote incremental centres"), std::string::npos) << inc;
}

// A new work offset moves no axis: the next block moves only the axes it names (Fanuc 0i-MF,
// "Workpiece coordinate system"; LinuxCNC, "G54-G59.3"). "G55 G0 X10" after "G54 G0 X0 Y0 Z0"
// keeps Y and Z where G54 put them (they were carried to G55's Y0 Z0: 10 mm moves nobody
// programmed).
TEST(GcodeReader, ANewWorkOffsetMovesOnlyTheAxesTheNextBlockNames) {
  Machine vmc = machine("resources/machines/vmc_3axis_iso.xml", 0.0);
  vmc.model.setup.work_offsets["G54"] = Eigen::Vector3d(-300, -200, -250);
  vmc.model.setup.work_offsets["G55"] = Eigen::Vector3d(-310, -190, -240);
  const ClProgram p =
      parseGcode("G21 G90\nG54 G0 X0 Y0 Z0\nG55 G0 X10\nG0 Y5\nM30\n", "w.nc", vmc.model);
  ASSERT_EQ(p.path.size(), 3u);
  // X10 in G55 is X0 in G54 (machine -300): the point does not move at all.
  EXPECT_LT((p.path[1].p_w - p.path[0].p_w).norm(), 1e-9);
  // Y5 in G55 is machine -185, 15 mm from G54's Y0; X and Z stay.
  const Eigen::Vector3d d = p.path[2].p_w - p.path[1].p_w;
  EXPECT_NEAR(d.norm(), 15.0, 1e-9);
  EXPECT_NEAR(std::abs(d.y()), 15.0, 1e-9);
}

// LinuxCNC's M70/M72 (save, restore the modal state) and M73 (restore it when the sub returns):
// they were ignored as harmless, so a sub that switched to G91 left the rest of the program
// incremental. Hand values: X0, then the sub's G91 X5 (5), G90 X1 (1), G91 X1 (2), M72's G90 X10.
TEST(GcodeReader, LinuxCncModalStateSavedAndRestored) {
  const Machine m = machine("resources/machines/linuxcnc_xyzac_trt.xml", 0.0);
  const ClProgram p = parseGcode(
      "G21 G90\no100 sub\nM73\nG91\nG0 X5\no100 endsub\nG0 X0 Y0 Z0 A0 C0\no100 call\n"
      "G0 X1\nM70\nG91\nG0 X1\nM72\nG0 X10\nM2\n",
      "m7x.ngc", m.model);
  ASSERT_EQ(p.path.size(), 5u);
  const double x0 = p.path[0].p_w.x();
  const double want[] = {0, 5, 1, 2, 10};
  for (size_t k = 0; k < 5; ++k) EXPECT_NEAR(p.path[k].p_w.x() - x0, want[k], 1e-9) << k;
  EXPECT_NE(refusal("G21\nM72\n", m.model).find("no M70 saved"), std::string::npos);
  EXPECT_NE(refusal("G21\nM73\n", m.model).find("outside an o-word sub"), std::string::npos);
}

// LinuxCNC's G28.1 and G30.1 store the current position as G28's and G30's home (#5161-#5166,
// #5181-#5186; LinuxCNC G-code reference): G28 then goes there, not to machine zero (G28.1 was
// noted as an unknown code), and G30 reads once G30.1 set its position. G43.2 is refused.
TEST(GcodeReader, LinuxCncStoredHomePositions) {
  const Machine m = machine("resources/machines/linuxcnc_xyzac_trt.xml", 0.0);
  const ClProgram p = parseGcode(
      "G21\nG0 X10 Y20 Z-5 A0 C0\nG28.1\nG0 X0 Y0 Z0\nG28\nG0 X3 Y4 Z-6\nG30.1\nG0 X0\n"
      "G30\nM2\n",
      "home.ngc", m.model);
  ASSERT_EQ(p.path.size(), 6u);
  EXPECT_LT((p.path[2].p_w - p.path[0].p_w).norm(), 1e-9);  // G28 to the G28.1 position
  EXPECT_LT((p.path[5].p_w - p.path[3].p_w).norm(), 1e-9);  // G30 to the G30.1 position
  EXPECT_NE(refusal("G21\nG0 X0 Y0 Z0 A0 C0\nG30\n", m.model).find("second reference point"),
            std::string::npos);
  EXPECT_NE(refusal("G21\nG43.2 H2\n", m.model).find("G43.2"), std::string::npos);
}

// Drilling cycles in the three planes, both retract modes, G90 and G91 with repeats, against
// LinuxCNC's own interpreter: its tests/interp/g81/{g17,g18,g19}/{g98,g99} programs and the
// canonical moves it printed (tests/fixtures/gcode/linuxcnc_g81). In G18 and G19 LinuxCNC drills
// along Y and X; tolver drilled along Z there (the points off by the hole depth, unsaid).
TEST(GcodeReader, LinuxCncDrillingCyclesInEveryPlaneAsItsInterpreterRunsThem) {
  const Machine m = machine("resources/machines/linuxcnc_xyzac_trt.xml", 0.0);
  for (const char* plane : {"g17", "g18", "g19"})
    for (const char* retract : {"g98", "g99"}) {
      const std::string stem =
          std::string("tests/fixtures/gcode/linuxcnc_g81/") + plane + "-" + retract + "-g81";
      SCOPED_TRACE(stem);
      // LinuxCNC's points (inches): every STRAIGHT_TRAVERSE and STRAIGHT_FEED.
      std::vector<Eigen::Vector3d> want;
      std::istringstream expected(test::readText(test::sourcePath(stem + "_expected.txt")));
      for (std::string l; std::getline(expected, l);) {
        const size_t at = l.find("STRAIGHT_");
        if (at == std::string::npos) continue;
        Eigen::Vector3d v;
        ASSERT_EQ(
            std::sscanf(l.c_str() + l.find('(', at) + 1, "%lf, %lf, %lf", &v.x(), &v.y(), &v.z()),
            3)
            << l;
        if (want.empty() || (v - want.back()).norm() > 1e-9) want.push_back(v);
      }
      const ClProgram p = readGcodeFile(test::sourcePath(stem + ".ngc"), m.model);
      std::vector<Eigen::Vector3d> got;
      for (const ClPoint& c : p.path) {
        const Eigen::Vector3d v = c.p_w / 25.4;
        if (got.empty() || (v - got.back()).norm() > 1e-9) got.push_back(v);
      }
      ASSERT_EQ(got.size(), want.size());
      ASSERT_GT(got.size(), 30u);
      for (size_t i = 0; i < got.size(); ++i)
        EXPECT_LT(((got[i] - got[0]) - (want[i] - want[0])).norm(), 1e-4) << i;
    }
  // Other controls: in G18/G19 the drilling axis is a setting (Fanuc 5101#0 FXY): refused.
  const Machine vmc = machine("resources/machines/vmc_3axis_iso.xml", 0.0);
  EXPECT_NE(refusal("G21 G18\nG0 X0 Y0 Z0\nG81 X1 Z1 Y-1 R1 F10\n", vmc.model).find("FXY"),
            std::string::npos);
}

// The canonical moves LinuxCNC's interpreter printed for a program (its tests' "expected"): the
// end of every STRAIGHT_TRAVERSE, STRAIGHT_FEED and ARC_FEED (with the arc's centre) in mm, the
// G5x and G92 offsets it printed (SET_G5X_OFFSET, SET_G92_OFFSET) added, in the units it printed
// (USE_LENGTH_UNITS).
struct CanonMove {
  Eigen::Vector3d end;                    // mm
  std::optional<Eigen::Vector3d> centre;  // an arc's, its coordinate along `normal` 0
  int normal = 2;                         // the arc's plane: its normal's index (XY: 2, XZ: 1)
  double unit = 1.0;                      // mm per unit printed (the tolerance: its last digit)
};
std::vector<CanonMove> canonMoves(const std::string& expected_path) {
  std::vector<CanonMove> moves;
  Eigen::Vector3d g5x = Eigen::Vector3d::Zero(), g92 = Eigen::Vector3d::Zero();
  double unit = 1.0;
  int normal = 2;
  std::istringstream in(test::readText(test::sourcePath(expected_path)));
  for (std::string l; std::getline(in, l);) {
    if (l.find("USE_LENGTH_UNITS(") != std::string::npos)
      unit = l.find("INCHES") != std::string::npos ? 25.4 : 1.0;
    if (l.find("SELECT_PLANE(") != std::string::npos)
      normal = l.find("_XZ") != std::string::npos ? 1 : l.find("_YZ") != std::string::npos ? 0 : 2;
    const size_t s = l.find("STRAIGHT_"), a = l.find("ARC_FEED("), o5 = l.find("SET_G5X_OFFSET("),
                 o92 = l.find("SET_G92_OFFSET(");
    double v[6];
    int index = 0;
    const Eigen::Vector3d off = g5x + g92;
    if (o5 != std::string::npos)
      EXPECT_EQ(std::sscanf(l.c_str() + o5 + 15, "%d, %lf, %lf, %lf", &index, &g5x.x(), &g5x.y(),
                            &g5x.z()),
                4);
    else if (o92 != std::string::npos)
      EXPECT_EQ(std::sscanf(l.c_str() + o92 + 15, "%lf, %lf, %lf", &g92.x(), &g92.y(), &g92.z()),
                3);
    else if (s != std::string::npos &&
             std::sscanf(l.c_str() + l.find('(', s) + 1, "%lf, %lf, %lf", &v[0], &v[1], &v[2]) == 3)
      moves.push_back({unit * (Eigen::Vector3d(v[0], v[1], v[2]) + off), std::nullopt, 2, unit});
    else if (a != std::string::npos &&
             std::sscanf(l.c_str() + a + 9, "%lf, %lf, %lf, %lf, %lf, %lf", &v[0], &v[1], &v[2],
                         &v[3], &v[4], &v[5]) == 6) {
      // ARC_FEED(end1, end2, centre1, centre2, turn, end along the normal): X Y in XY, Z X in XZ.
      const Eigen::Vector3d end =
          normal == 2 ? Eigen::Vector3d(v[0], v[1], v[5]) : Eigen::Vector3d(v[1], v[5], v[0]);
      Eigen::Vector3d centre =
          normal == 2 ? Eigen::Vector3d(v[2], v[3], 0) : Eigen::Vector3d(v[3], 0, v[2]);
      centre += off;
      centre[normal] = 0;
      moves.push_back({unit * (end + off), unit * centre, normal, unit});
    }
  }
  return moves;
}

// Whether the path (mm) runs through LinuxCNC's moves in order: every end point on it, and each
// arc's points between its ends on the circle about the printed centre (to the printed four
// decimals). The path starts at LinuxCNC's start, 0 0 0. Returns "" or what differs.
std::string followsCanonMoves(const ClProgram& p, const std::vector<CanonMove>& want) {
  std::vector<Eigen::Vector3d> got;
  for (const ClPoint& c : p.path)
    if (got.empty() || (c.p_w - got.back()).norm() > 1e-9) got.push_back(c.p_w);
  if (got.empty() || got[0].norm() > 1e-9) return "the path does not start at 0 0 0";
  size_t j = 1;
  for (size_t i = 0; i < want.size(); ++i) {
    const CanonMove& m = want[i];
    const double tol = 1.5e-4 * m.unit;
    // A straight move of no length (an arc back to its start is a full circle).
    if (!m.centre && (got[j - 1] - m.end).norm() < tol) continue;
    if (m.centre) {
      auto radius = [&](Eigen::Vector3d q) {
        q[m.normal] = 0;
        return (q - *m.centre).norm();
      };
      const double r = radius(m.end);
      while (j < got.size() && (got[j] - m.end).norm() >= tol) {
        // (the centre and the end both rounded to the last digit printed)
        if (std::abs(radius(got[j]) - r) > 2 * tol) {
          std::ostringstream o;
          o << "move " << i << " (arc): point " << j << " (" << got[j].transpose()
            << ") off its circle about " << m.centre->transpose() << ", radius " << r << " mm, by "
            << radius(got[j]) - r << " mm";
          return o.str();
        }
        ++j;
      }
    }
    if (j >= got.size() || (got[j] - m.end).norm() >= tol) {
      std::ostringstream o;
      o << "move " << i << ": LinuxCNC ends at " << m.end.transpose() << ", tolver at ";
      if (j < got.size()) o << got[j].transpose();
      return o.str();
    }
    ++j;
  }
  if (j != got.size()) return std::to_string(got.size() - j) + " point(s) after LinuxCNC's last";
  return "";
}

// Cutter radius compensation against LinuxCNC's own interpreter: its tests/ccomp programs (entry
// by line and by arc, outside corners rounded, inside corners drawn back, Z moves held in a
// corner, G90/G91/G92 mixed) and the canonical moves it printed for them
// (tests/fixtures/gcode/linuxcnc_ccomp). Before, G41/G42 were refused.
TEST(GcodeReader, LinuxCncCutterRadiusCompensationAsItsInterpreterRunsIt) {
  const Machine m = machine("resources/machines/linuxcnc_xyzac_trt.xml", 0.0);
  const std::string dir = "tests/fixtures/gcode/linuxcnc_ccomp/";
  GcodeReadOptions o;
  o.tool_diameter_mm = readLinuxCncToolTable(test::sourcePath(dir + "tool_mm.tbl"), 1.0);
  for (const char* name :
       {"mill-line-arc-entry", "mill-zchanges", "mill-g90g91g92", "inside-corners", "cam-nisley",
        "inverse-time-with-comp", "crazy-paths"}) {
    SCOPED_TRACE(name);
    // LinuxCNC starts at 0 0 0 (these programs leave axes unnamed until they move them).
    const std::string text =
        "G21 G0 X0 Y0 Z0\n" + test::readText(test::sourcePath(dir + name + ".ngc"));
    const ClProgram p = parseGcode(text, name, m.model, o);
    const std::vector<CanonMove> want = canonMoves(dir + name + "_expected.txt");
    ASSERT_GT(want.size(), 8u);
    EXPECT_EQ(followsCanonMoves(p, want), "");
    EXPECT_TRUE(hasNote(p, "cutter radius compensation carried out"));
    EXPECT_GT(p.radius_comp_line, 0);
    // A held move's points belong to the line that made them, not to the line read when they
    // came (the written CL's "$$ line"), in a program without subs.
    if (p.flow_line == 0) {
      for (const AptStatement& st : p.statements)
        for (int k = st.first_point; k < st.first_point + st.point_count; ++k)
          EXPECT_EQ(p.path[k].line, st.first_line) << k;
    }
  }
}

// LinuxCNC reads Fanuc's M98 P L / M99 subprograms too (they were refused there): its
// tests/interp/m98m99 programs against the moves its interpreter printed; M97 (HAAS's) refused.
TEST(GcodeReader, LinuxCncM98SubprogramsAsItsInterpreterRunsThem) {
  const Machine m = machine("resources/machines/linuxcnc_xyzac_trt.xml", 0.0);
  const std::string dir = "tests/fixtures/gcode/linuxcnc_m98m99/";
  for (const char* name : {"01-basics", "05-M98-loops"}) {
    SCOPED_TRACE(name);
    const std::string text =
        "G21 G0 X0 Y0 Z0\n" + test::readText(test::sourcePath(dir + name + ".ngc"));
    const ClProgram p = parseGcode(text, name, m.model);
    const std::vector<CanonMove> want = canonMoves(dir + name + "_expected.txt");
    ASSERT_GT(want.size(), 10u);
    EXPECT_EQ(followsCanonMoves(p, want), "");
  }
  EXPECT_NE(refusal("G21\nG0 X0 Y0 Z0\nM97 P10\nM30\nN10 G0 X1\nM99\n", m.model).find("HAAS"),
            std::string::npos);
}

// What LinuxCNC refuses under cutter radius compensation is refused by name at its line; a
// zero radius (tool 0, G41.1 D0) leaves the path as programmed; a negative diameter swaps the
// side; other controls' G41/G42 stay refused; a table names its errors.
TEST(GcodeReader, CutterRadiusCompensationRefusalsAndSides) {
  const Machine m = machine("resources/machines/linuxcnc_xyzac_trt.xml", 0.0);
  const std::string head = "G21 G90 G17\nG0 X-10 Y-10 Z5\n";
  auto refused = [&](const std::string& body) {
    try {
      parseGcode(head + body, "c.ngc", m.model);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  const std::string on = "G41.1 D6 G1 X0 Y0 F100\n";
  EXPECT_NE(refused(on + "G55\nG1 X10\n").find("c.ngc:4:1: G55: G55 under cutter radius"),
            std::string::npos);
  EXPECT_NE(refused(on + "T2 M6\n").find("c.ngc:4:4: M6: a tool change"), std::string::npos);
  EXPECT_NE(refused(on + "G81 X5 Y5 Z-1 R1\n").find("c.ngc:4"), std::string::npos);
  EXPECT_NE(refused(on + "G1 X10 A5\n").find("a move with rotary words"), std::string::npos);
  EXPECT_NE(refused(on + "G19\n").find("G19 under cutter radius compensation"), std::string::npos);
  EXPECT_NE(refused(on + "G41.1 D6\n").find("already on (line 3)"), std::string::npos);
  EXPECT_NE(refused(on + "G1 X20\nG40\nG2 X30 I5\n").find("c.ngc:6: G2: an arc as the first"),
            std::string::npos);
  EXPECT_NE(refused("G41.1 D30 G1 X0 Y0 F100\n").find("entry move"), std::string::npos);
  // A step into a corner narrower than the tool: LinuxCNC's gouge refusal.
  EXPECT_NE(refused(on + "G1 X10\nG1 Y1\nG1 X20\nG1 Y-20\n").find("gouging"), std::string::npos);
  EXPECT_NE(refused(on + "G1 X10\nG18\n").find("G18 under cutter radius"), std::string::npos);
  EXPECT_NE(refused(on + "G64 P0.01\n").find("G64 under cutter radius"), std::string::npos);
  EXPECT_NE(refused(on + "G43 H1\n").find("tool length offset change"), std::string::npos);
  // The plane in force again, and a unit change, LinuxCNC allows under compensation.
  EXPECT_EQ(refused(on + "G17 G1 X10\nG20 G1 X1\nG21 G40 G1 X30 Y-10\n"), "accepted");
  EXPECT_NE(refused("G19 G41.1 D6\n").find("G19"), std::string::npos);
  EXPECT_NE(refused("G41 G1 X0 Y0\n").find("--tool-table"), std::string::npos);
  // The program's own G10 L1 P R sets the radius G41 compensates by (no table needed).
  const ClProgram by_g10 = parseGcode(
      head + "G10 L1 P3 R3\nT3 M6\nG41 G1 X0 Y0 F100\nG1 X40\nG40 G1 X50 Y50\n", "e", m.model);
  const ClProgram by_d =
      parseGcode(head + "G41.1 D6 G1 X0 Y0 F100\nG1 X40\nG40 G1 X50 Y50\n", "f", m.model);
  ASSERT_EQ(by_g10.path.size(), by_d.path.size());
  for (size_t i = 0; i < by_d.path.size(); ++i)
    EXPECT_LT((by_g10.path[i].p_w - by_d.path[i].p_w).norm(), 1e-12) << i;
  // G41 without D takes the tool in the spindle, not one selected after it (T4 waits for M6).
  const ClProgram loaded = parseGcode(
      head + "G10 L1 P3 R3\nG10 L1 P4 R9\nT3 M6\nT4\nG41 G1 X0 Y0 F100\nG1 X40\nG40 G1 X50 Y50\n",
      "h", m.model);
  ASSERT_EQ(loaded.path.size(), by_d.path.size());
  for (size_t i = 0; i < by_d.path.size(); ++i)
    EXPECT_LT((loaded.path[i].p_w - by_d.path[i].p_w).norm(), 1e-12) << i;
  // D0: no radius, the path as programmed; D-6: the other side of the path (G42's).
  const std::string square = "G1 X40\nG1 Y30\nG40 G1 X50 Y50\nM2\n";
  const ClProgram none = parseGcode(head + "G41.1 D0 G1 X0 Y0 F100\n" + square, "a", m.model);
  const ClProgram plain = parseGcode(head + "G1 X0 Y0 F100\n" + square, "b", m.model);
  ASSERT_EQ(none.path.size(), plain.path.size());
  for (size_t i = 0; i < none.path.size(); ++i)
    EXPECT_LT((none.path[i].p_w - plain.path[i].p_w).norm(), 1e-12) << i;
  const ClProgram right = parseGcode(head + "G42.1 D6 G1 X0 Y0 F100\n" + square, "c", m.model);
  const ClProgram swapped = parseGcode(head + "G41.1 D-6 G1 X0 Y0 F100\n" + square, "d", m.model);
  ASSERT_EQ(right.path.size(), swapped.path.size());
  for (size_t i = 0; i < right.path.size(); ++i)
    EXPECT_LT((right.path[i].p_w - swapped.path[i].p_w).norm(), 1e-12) << i;
  // G42 going +X puts the tool at Y = -3.
  bool below = false;
  for (const ClPoint& c : right.path) below = below || std::abs(c.p_w.y() + 3.0) < 1e-9;
  EXPECT_TRUE(below);
  // On other controls G41/G42 stay refused, naming --cutter-comp wear; G41.1 is Fanuc's normal
  // direction control there.
  const Machine vmc = machine("resources/machines/vmc_3axis_iso.xml", 0.0);
  EXPECT_NE(refusal("G21\nG0 X0 Y0 Z0\nG41 D1 G1 X10\n", vmc.model).find("--cutter-comp wear"),
            std::string::npos);
  EXPECT_NE(refusal("G21\nG0 X0 Y0 Z0\nG41.1 G1 X10\n", vmc.model).find("normal direction"),
            std::string::npos);
  // The tool table: LinuxCNC's words, a comment, units; errors name the line and column.
  const auto t =
      parseLinuxCncToolTable("T1 P1 Z0.5 D0.25 ;a\n\n; only a comment\nt2 p2 d.5\n", "t.tbl", 25.4);
  ASSERT_EQ(t.size(), 2u);
  EXPECT_DOUBLE_EQ(t.at(1), 6.35);
  EXPECT_DOUBLE_EQ(t.at(2), 12.7);
  EXPECT_TRUE(std::isnan(parseLinuxCncToolTable("T5 P5 D1 Q2\n", "t.tbl", 1.0).at(5)));
  auto tableError = [](const std::string& text) {
    try {
      parseLinuxCncToolTable(text, "t.tbl", 1.0);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_NE(tableError("T1 P1 D6\nT2 P2 Dx\n").find("t.tbl:2:7: D"), std::string::npos);
  EXPECT_NE(tableError("T1 P1 D6\nT1 P2 D6\n").find("already on line 1"), std::string::npos);
  EXPECT_NE(tableError("P1 D6\n").find("t.tbl:1:1: T"), std::string::npos);
  EXPECT_NE(tableError("T1 P1 K6\n").find("t.tbl:1:7: K"), std::string::npos);
  EXPECT_NE(tableError("; nothing\n").find("no tools"), std::string::npos);
}

// LinuxCNC's polar coordinates (were refused): @ the distance from the program origin, ^ the
// angle from +X; in G91 each adds to the current point's distance or angle about the origin
// (interp_find.cc find_ends). Six holes on a 20 mm circle by "G91 ^60"; the refusals LinuxCNC
// makes; other controls name the dialect.
TEST(GcodeReader, LinuxCncPolarCoordinates) {
  const Machine m = machine("resources/machines/linuxcnc_xyzac_trt.xml", 0.0);
  std::string text = "G21 G90\nG0 X0 Y0 Z5\nG0 @20 ^0\nG91\n";
  for (int k = 0; k < 5; ++k) text += "G0 ^60\n";
  text += "G0 @-5\nG90 G0 ^90\nM2\n";
  const ClProgram p = parseGcode(text, "p.ngc", m.model);
  ASSERT_EQ(p.path.size(), 9u);
  for (int k = 0; k < 6; ++k) {
    const double a = degToRad(60.0 * k);
    EXPECT_LT((p.path[1 + k].p_w - Eigen::Vector3d(20 * std::cos(a), 20 * std::sin(a), 5)).norm(),
              1e-9)
        << k;
  }
  const double a = degToRad(300.0);  // @-5 shortens the distance, keeps the angle
  EXPECT_LT((p.path[7].p_w - Eigen::Vector3d(15 * std::cos(a), 15 * std::sin(a), 5)).norm(), 1e-9);
  EXPECT_LT((p.path[8].p_w - Eigen::Vector3d(0, 15, 5)).norm(),
            1e-9);  // G90 ^90: the distance kept
  EXPECT_NE(refusal("G21\nG0 X0 Y0 Z0\nG0 @5 ^0 X1\n", m.model).find("X or Y with polar"),
            std::string::npos);
  EXPECT_NE(refusal("G21\nG0 X0 Y0 Z0\nG91 G0 ^30\n", m.model).find("at the origin"),
            std::string::npos);
  EXPECT_NE(refusal("G21\nG0 X0 Y0 Z0\nG0 @5\n", m.model).find("angle is not known"),
            std::string::npos);
  const Machine vmc = machine("resources/machines/vmc_3axis_iso.xml", 0.0);
  EXPECT_NE(refusal("G21\nG0 X0 Y0 Z0\nG0 @5 ^0\n", vmc.model).find("dialect=\"linuxcnc\""),
            std::string::npos);
}

// LinuxCNC's turned coordinate systems (G10 L2 Pn R, were refused): machine = Rz(R) program +
// G5x (emccanon.cc rotate_and_offset_pos), arcs turned with them, each system its own rotation;
// G92 in a turned system as LinuxCNC takes it; G10 L20 there refused.
TEST(GcodeReader, LinuxCncTurnedCoordinateSystems) {
  const Machine m = machine("resources/machines/linuxcnc_xyzac_trt.xml", 0.0);
  const ClProgram p = parseGcode(
      "G21 G90\nG10 L2 P1 X10 Y5 Z0 R90\nG10 L2 P2 X10 Y5 Z0\nG54 G0 X2 Y0 Z0\nG3 X0 Y2 I-2\n"
      "G55 G0 X2 Y0\nG54 G0 X1 Y1\nM2\n",
      "r.ngc", m.model);
  auto xyz = [&](size_t i) {
    return Eigen::Vector3d(p.joints[i][0], p.joints[i][1], p.joints[i][2]);
  };
  ASSERT_GT(p.path.size(), 10u);
  EXPECT_LT((xyz(0) - Eigen::Vector3d(10, 7, 0)).norm(), 1e-9);  // (2, 0) turned 90 deg
  size_t k = 1;
  for (; k < p.path.size() && p.path[k].line == 5; ++k)  // the arc, turned: about (10, 5)
    EXPECT_NEAR((xyz(k) - Eigen::Vector3d(10, 5, 0)).norm(), 2.0, 1e-9) << k;
  EXPECT_LT((xyz(k - 1) - Eigen::Vector3d(8, 5, 0)).norm(), 1e-9);  // (0, 2) turned
  EXPECT_LT((xyz(k) - Eigen::Vector3d(12, 5, 0)).norm(), 1e-9);     // G55: not turned
  EXPECT_LT((xyz(k + 1) - Eigen::Vector3d(9, 6, 0)).norm(), 1e-9);  // back in G54: (1, 1) turned
  // G92 in a turned system: its offset taken before the turn (convert_axis_offsets).
  const ClProgram g92 = parseGcode(
      "G21\nG10 L2 P1 X10 Y5 Z0 R90\nG54 G0 X1 Y0 Z0\nG92 X0 Y0\nG0 X0 Y1\nM2\n", "g.ngc", m.model);
  ASSERT_EQ(g92.path.size(), 2u);
  EXPECT_LT((Eigen::Vector3d(g92.joints[1][0], g92.joints[1][1], g92.joints[1][2]) -
             Eigen::Vector3d(9, 6, 0))
                .norm(),
            1e-9);
  EXPECT_NE(refusal("G21\nG10 L2 P1 R30\nG54 G0 X0 Y0 Z0\nG10 L20 P1 X0\n", m.model).find("turned"),
            std::string::npos);
  const Machine vmc = machine("resources/machines/vmc_3axis_iso.xml", 0.0);
  EXPECT_NE(refusal("G21\nG10 L2 P1 R30\nG54 G0 X0 Y0 Z0\n", vmc.model).find("not supported"),
            std::string::npos);
}

// A feed beyond any machine's (LinuxCNC's trajectory tests write F1e9 for "as fast as it goes")
// places no point: read as unknown, with a note, where the whole program was refused; a length
// that large is still refused.
TEST(GcodeReader, AHugeFeedIsTheControlsFastest) {
  const Machine m = machine("resources/machines/linuxcnc_xyzac_trt.xml", 0.0);
  const ClProgram p =
      parseGcode("G21\nG0 X0 Y0 Z0\nG1 X10 F999999999\nG1 X20 F600\n", "f.ngc", m.model);
  ASSERT_EQ(p.path.size(), 3u);
  EXPECT_TRUE(std::isnan(p.path[1].feed_mm_min));  // unknown
  EXPECT_EQ(p.path[2].feed_mm_min, 600.0f);
  EXPECT_TRUE(hasNote(p, "feeds beyond any machine's (first at line 3)"));
  EXPECT_NE(refusal("G21\nG0 X0 Y0 Z0\nG1 X999999999\n", m.model).find("plausible length"),
            std::string::npos);
}

// An arc block with its centre words and no axis word is a full circle back to its start (the
// hole-milling circle, "G2 I-5." on Fanuc and HAAS, "G2 I1" on LinuxCNC): it was read as no move.
TEST(GcodeReader, AnArcWithOnlyItsCentreIsAFullCircle) {
  for (const char* file :
       {"resources/machines/linuxcnc_xyzac_trt.xml", "resources/machines/vmc_3axis_iso.xml"}) {
    SCOPED_TRACE(file);
    const Machine m = machine(file, 0.0);
    const ClProgram p =
        parseGcode("G21 G90 G17\nG0 X10 Y0 Z0\nG2 I-5. F100\nG1 X20\n", "f.nc", m.model);
    double xmin = 1e9, ymax = -1e9;
    int on_circle = 0;
    for (const ClPoint& c : p.path) {
      xmin = std::min(xmin, c.p_w.x());
      ymax = std::max(ymax, c.p_w.y());
      if (c.line == 3) {
        ++on_circle;
        EXPECT_NEAR((c.p_w - Eigen::Vector3d(5, 0, 0)).norm(), 5.0, 1e-9);
      }
    }
    EXPECT_GT(on_circle, 20);
    EXPECT_NEAR(xmin, 0.0, 1e-3);  // the far side of the circle
    EXPECT_NEAR(ymax, 5.0, 1e-3);
    // A lone centre word under a drilling cycle or G1 is still no move.
    EXPECT_EQ(parseGcode("G21\nG0 X10 Y0 Z0\nG1 I-5. F100\nG1 X20\n", "g.nc", m.model).path.size(),
              2u);
  }
}

// Fanuc's G10 L10 P R (memory C: the tool length's geometry; HAAS alike) sets the length a later
// G43 H applies, G91 adds to it; L12/L13 (radius) are noted, L1/L11 with R refused (memory A's
// single offset or a wear, by the control's memory type). "G10 L1 P1 R100." was read as
// LinuxCNC's radius and the length 100 dropped.
TEST(GcodeReader, FanucToolLengthByG10L10) {
  Machine vmc = machine("resources/machines/vmc_3axis_iso.xml", 0.0);
  Machine preset = vmc;
  preset.model.setup.tool_lengths[1] = 100.0;
  const std::string moves = "G0 X0 Y0 Z0\nG43 H1 Z10\n";
  const ClProgram by_setup = parseGcode("G21\n" + moves, "a.nc", preset.model);
  const ClProgram by_g10 = parseGcode("G21\nG10 L10 P1 R100.\n" + moves, "b.nc", vmc.model);
  const ClProgram added =
      parseGcode("G21\nG10 L10 P1 R90.\nG91 G10 L10 P1 R10.\nG90\n" + moves, "c.nc", vmc.model);
  ASSERT_EQ(by_g10.path.size(), by_setup.path.size());
  EXPECT_NE(parseGcode("G21\n" + moves, "e.nc", vmc.model).joints.back(), by_setup.joints.back());
  for (size_t i = 0; i < by_setup.path.size(); ++i) {
    EXPECT_EQ(by_g10.joints[i], by_setup.joints[i]) << i;
    EXPECT_EQ(added.joints[i], by_setup.joints[i]) << i;
  }
  EXPECT_TRUE(hasNote(parseGcode("G21\nG10 L12 P1 R5.\n" + moves, "d.nc", vmc.model),
                      "G10 L12 (tool radius)"));
  EXPECT_NE(refusal("G21\nG10 L1 P1 R100.\n" + moves, vmc.model).find("memory type"),
            std::string::npos);
  EXPECT_NE(refusal("G21\nG10 L11 P1 R0.1\n" + moves, vmc.model).find("memory type"),
            std::string::npos);
}

// HAAS's additional work offsets G154 Pn and G110-G129 (= G154 P1-P20, HAAS 96-8000) are Fanuc's
// G54.1 Pn: one offset each, from the set-up's g54.1pN_mm or set by G10 L20 Pn (Fanuc 0i-MF; on
// LinuxCNC L20 Pn is G54..G59.3). They were noted as unknown codes and the moves read in G54.
// G10 L2 P0 (Fanuc's external offset) is refused on an ISO control.
TEST(GcodeReader, HaasAdditionalWorkOffsetsAreFanucsG541) {
  Machine vmc = machine("resources/machines/vmc_3axis_iso.xml", 0.0);
  vmc.model.setup.work_offsets["G54"] = Eigen::Vector3d(-300, -200, -250);
  vmc.model.setup.work_offsets["G54.1P5"] = Eigen::Vector3d(-310, -190, -240);
  vmc.model.setup.work_offsets["G54.1P2"] = Eigen::Vector3d(-320, -180, -230);
  const auto p = [&](const std::string& text) {
    return parseGcode("G21 G90\nG54 G0 X0 Y0 Z0\n" + text, "w.nc", vmc.model).path.back().p_w;
  };
  const Eigen::Vector3d g54 = p("");
  const Eigen::Vector3d g541p5 = p("G54.1 P5 G0 X0 Y0 Z0\n");
  // Work offset 5 (310, 190, 240 against 300, 200, 250) moves the point by 10 mm on each axis.
  EXPECT_NEAR((g541p5 - g54).norm(), std::sqrt(300.0), 1e-9);
  EXPECT_LT((p("G154 P5 G0 X0 Y0 Z0\n") - g541p5).norm(), 1e-12);
  EXPECT_LT((p("G111 G0 X0 Y0 Z0\n") - p("G54.1 P2 G0 X0 Y0 Z0\n")).norm(), 1e-12);
  EXPECT_NEAR((p("G111 G0 X0 Y0 Z0\n") - g54).norm(), std::sqrt(1200.0), 1e-9);
  // G10 L20 P5 sets its values on an ISO control (as L2 sets G54's): given G54's values, the
  // point lands where G54 puts it.
  EXPECT_LT((p("G10 L20 P5 X-300 Y-200 Z-250\nG154 P5 G0 X0 Y0 Z0\n") - g54).norm(), 1e-9);
  EXPECT_NE(refusal("G21\nG10 L2 P0 X1 Y1 Z1\n", vmc.model).find("external work offset"),
            std::string::npos);
  EXPECT_NE(refusal("G21\nG154 P0\n", vmc.model).find("P1 to P99"), std::string::npos);
}

// Returns to a reference point: G30's second reference point is a setting of the control that no
// machine file carries, so it is refused by name at its line (it was read as G28, machine zero);
// a G28 without axis words homes every axis (HAAS, LinuxCNC), said in a note on an ISO control,
// whose Fanuc reading moves none (a training template, stcline/CNC_Training, ends with a bare G28).
TEST(GcodeReader, ReferencePointReturnsAsTheControlsDocumentThem) {
  const Machine vmc = machine("resources/machines/vmc_3axis_iso.xml", 0.0);
  const std::string g30 = refusal("G21\nG0 X1 Y2 Z5\nG91 G30 Z0\n", vmc.model);
  EXPECT_NE(g30.find("r.nc:3"), std::string::npos) << g30;
  EXPECT_NE(g30.find("second reference point"), std::string::npos) << g30;
  const ClProgram iso = parseGcode("G21\nG0 X1 Y2 Z5\nG28\nM30\n", "bare.nc", vmc.model);
  EXPECT_TRUE(hasNote(iso,
                      "G28 without axis words (first at line 3) read as every axis to "
                      "machine zero"));
  ASSERT_FALSE(iso.path.empty());
  const Machine lcnc = machine("resources/machines/linuxcnc_xyzbc_trt.xml", 0.0);
  const ClProgram l = parseGcode("G21\nG0 X1 Y2 Z5 B0 C0\nG28\nM30\n", "bare.ngc", lcnc.model);
  for (const std::string& n : l.notes) EXPECT_EQ(n.find("G28 without"), std::string::npos) << n;
  // G28 naming an axis homes that axis only, with no note.
  const ClProgram named = parseGcode("G21\nG0 X1 Y2 Z5\nG91 G28 Z0\n", "z.nc", vmc.model);
  for (const std::string& n : named.notes) EXPECT_EQ(n.find("G28 without"), std::string::npos) << n;
}

// Motion codes some control gives a meaning tolver does not carry out are refused by name: their
// words were read as moves of the modal G0/G1 (LinuxCNC's nc_files/nurbs/G5/butterfly-xy.ngc:
// the NURBS control points read as a path, no word of warning). An unknown code beside axis
// words is refused too; without axis words it stays a note, and Fanuc's G5.1 Q1 (AI contour
// control) is harmless on an ISO control.
TEST(GcodeReader, MotionCodesItCannotCarryOutAreRefusedByName) {
  const Machine vmc = machine("resources/machines/vmc_3axis_iso.xml", 0.0);
  // LinuxCNC's O-words on an ISO machine: the refusal names the dialect that carries them out.
  EXPECT_NE(refusal("G21\no100 sub\nG0 X1\no100 endsub\n", vmc.model)
                .find("declares dialect=\"linuxcnc\""),
            std::string::npos);
  const Machine lcnc = machine("resources/machines/linuxcnc_xyzbc_trt.xml", 0.0);
  try {
    readGcodeFile(test::sourcePath("tests/fixtures/gcode/linuxcnc_nurbs_butterfly-xy.ngc"),
                  vmc.model);
    ADD_FAILURE() << "NURBS read";
  } catch (const InputError& e) {
    EXPECT_EQ(e.line(), 12) << e.what();
    EXPECT_NE(std::string(e.what()).find("G5.2: NURBS (G5.2-G5.3, LinuxCNC)"), std::string::npos)
        << e.what();
  }
  const std::string head = "G21 G90\nG0 X1 Y2 Z5 B0 C0\n";
  struct Case {
    const MachineModel* model;
    const char* block;
    const char* says;
  };
  const Case cases[] = {
      {&lcnc.model, "G5 X2 Y3 I1 J0 P1 Q0\n", "G5: cubic spline (G5, LinuxCNC)"},
      {&lcnc.model, "G5.1 X2 Y3 I1 J0\n", "G5.1: quadratic spline"},
      {&lcnc.model, "G33.1 Z-5 K1\n", "G33.1: rigid tapping"},
      {&lcnc.model, "G71 Q100 D1\n", "G71: lathe finishing and roughing cycles"},
      {&vmc.model, "G6.2 P3 X2 Y3 R1 K0\n", "G6.2: NURBS (G6.2, Fanuc)"},
      {&vmc.model, "G12.1\n", "G12.1: polar coordinate interpolation"},
      {&vmc.model, "G13 I0.5 K2 Q0.1 D1 F10\n", "G13: circular pocket milling (G12/G13, HAAS)"},
      {&vmc.model, "G81 Z-1 R1 F10 L0\nG70 I2 J0 L6\n", "G70: bolt-hole patterns"},
      {&vmc.model, "G31 X10 F100\n",
       "G31: a code tolver does not know, in a block with axis "
       "words (X)"},
  };
  for (const Case& c : cases) {
    const std::string text =
        c.model == &vmc.model ? "G21 G90\nG0 X1 Y2 Z5\n" + std::string(c.block) : head + c.block;
    const std::string r = refusal(text, *c.model);
    EXPECT_NE(r.find(c.says), std::string::npos) << c.block << " -> " << r;
    EXPECT_NE(r.find(c.model == &vmc.model && c.block[1] == '8' ? "r.nc:4" : "r.nc:3"),
              std::string::npos)
        << r;
  }
  const ClProgram ok =
      parseGcode("G21 G90\nG5.1 Q1\nG0 X1 Y2 Z5\nG1 X3\nG71\nM30\n", "ok.nc", vmc.model);
  EXPECT_EQ(ok.path.size(), 2u);
  for (const std::string& n : ok.notes) EXPECT_EQ(n.find("G5.1"), std::string::npos) << n;
  EXPECT_EQ(ok.units, "MM");
}

// Parameter settings anywhere in a line (LinuxCNC: after a line number, beside words), set once
// the line is read: "#1=-2 G0 X-1" lost its move (the line ended at the setting), and "N0050
// #<tube-cut>=1" (a PlasmaC post) was refused. Polar words are named.
TEST(GcodeReader, ParameterSettingsAnywhereInTheLine) {
  const Machine vmc = machine("resources/machines/vmc_3axis_iso.xml", 0.0);
  const ClProgram p = parseGcode(
      "G21 G90\nN0050 #<tube-cut>=1\n#1=-2 G0 X-1 Y-1 Z-5\n#1=-7 #2=[#1-10] G1 X#1 Y[#1*6]\n"
      "G1 X#1 Y#2 Z-#<tube-cut>\nM30\n",
      "set.ngc", vmc.model);
  ASSERT_EQ(p.path.size(), 3u);
  EXPECT_EQ(p.path[0].line, 3);
  // Line 4: X#1, Y[#1*6] and #2=[#1-10] read #1 = -2, the value before the line.
  EXPECT_NEAR(p.path[1].p_w.x(), -2.0, 1e-12);
  EXPECT_NEAR(p.path[1].p_w.y(), -12.0, 1e-12);
  EXPECT_NEAR(p.path[2].p_w.x(), -7.0, 1e-12);
  EXPECT_NEAR(p.path[2].p_w.y(), -12.0, 1e-12);
  EXPECT_NEAR(p.path[2].p_w.z(), -1.0, 1e-12);
  // LinuxCNC's functions (degrees) and binary operators inside brackets, against <cmath>.
  const ClProgram f = parseGcode(
      "G21 G90\n#<r> = [2 * SQRT[2]]\nG0 X[#<r> * COS[45]] Y[#<r>*SIN[45]] Z[ATAN[1]/[-1]]\n"
      "G1 X[2 ** 3] Y[-7 MOD 3] Z[ROUND[-2.5] + FIX[-0.5] + FUP[0.2] + EXISTS[#<r>]]\n"
      "G1 X[ABS[-1] + LN[EXP[2]] + ACOS[0] + ASIN[1] + TAN[45]] Y[1 + 2 * 3 ** 2]\nM30\n",
      "f.ngc", vmc.model);
  ASSERT_EQ(f.path.size(), 3u);
  EXPECT_NEAR(f.path[0].p_w.x(), 2.0, 1e-12);
  EXPECT_NEAR(f.path[0].p_w.y(), 2.0, 1e-12);
  EXPECT_NEAR(f.path[0].p_w.z(), 135.0, 1e-12);
  EXPECT_NEAR(f.path[1].p_w.x(), 8.0, 1e-12);
  EXPECT_NEAR(f.path[1].p_w.y(), 2.0, 1e-12);  // LinuxCNC's MOD is never negative
  EXPECT_NEAR(f.path[1].p_w.z(), -3.0 - 1.0 + 1.0 + 1.0, 1e-12);
  EXPECT_NEAR(f.path[2].p_w.x(), 1.0 + 2.0 + 90.0 + 90.0 + 1.0, 1e-9);
  EXPECT_NEAR(f.path[2].p_w.y(), 19.0, 1e-12);
  EXPECT_NE(refusal("G21\nG0 X[FOO[1]] Y1 Z1\n", vmc.model).find("not a function"),
            std::string::npos);
  EXPECT_NE(refusal("G21\nG0 X[SQRT[-1]] Y1 Z1\n", vmc.model).find("SQRT of -1: no value"),
            std::string::npos);
  EXPECT_NE(refusal("G21\nG0 X[1 MOD 0] Y1 Z1\n", vmc.model).find("MOD by zero"),
            std::string::npos);
  EXPECT_NE(refusal("G21\nG0 X1 Y1 Z1\nG1 @.5 ^90\n", vmc.model).find("r.nc:3:4: @: polar"),
            std::string::npos);
  EXPECT_NE(refusal("G21\nG0 X1 #1 G1\n", vmc.model).find("expected '#parameter = value'"),
            std::string::npos);
  // A lathe program (X and Z only) on a mill: its moves are named, not "no moves".
  const std::string lathe = refusal("G21 G18\nG0 X10 Z1\nG1 Z-5 F50\nM30\n", vmc.model);
  EXPECT_NE(lathe.find("r.nc:2: 2 move(s), lines 2-3, and none where the tool's position is "
                       "known: the program never commands Y (a lathe program, X and Z only?)"),
            std::string::npos)
      << lathe;
}

// A Grbl sender's file opening with Grbl's own commands (marcio-pessoa/Escriba,
// Examples/calibration.gcode: "$I", "$G", "$$", "?"): refused at the first, naming it as Grbl's
// (some move the machine: $H homes), not as a stray character.
TEST(GcodeReader, GrblSystemCommandsAreRefusedByName) {
  const Machine vmc = machine("resources/machines/vmc_3axis_iso.xml", 0.0);
  for (const char* text : {"$I  ; View build info\nG21\nG0 X1 Y2 Z5\n", "?\nG21\nG0 X1\n",
                           "G21\nG0 X1 Y2 Z5\n  $H\n"}) {
    const std::string r = refusal(text, vmc.model);
    EXPECT_NE(r.find("is a Grbl system command"), std::string::npos) << r;
    EXPECT_NE(r.find(text[0] == 'G' ? "r.nc:3:3" : "r.nc:1:1"), std::string::npos) << r;
  }
  // A HAAS NGC '$' line (donpayne/cnc lathe_jaws_o4001.cnc: "$AddRegPart 1 X2.925 Y2.005") is
  // a control's own command, not Grbl's.
  const std::string haas = refusal("%\n$AddRegPart 1 X2.925 Y2.005\nG0 X1\n", vmc.model);
  EXPECT_NE(haas.find("a control's own command line"), std::string::npos) << haas;
  EXPECT_EQ(haas.find("Grbl"), std::string::npos) << haas;
  // '$' inside a block is still a stray character, named as such.
  EXPECT_NE(refusal("G21\nG0 X1 $2\n", vmc.model).find("expected a word letter"),
            std::string::npos);
}

// The program's end (M30, M2, a second '%') leaves what follows unread: said in a note, and
// named when nothing was read before it. Fusion's MPCNC post writes remarks as '%' lines
// ("% vfd enable", "% LED ON" before the first move: richcreations/Ghettotator,
// models/wiggler-8-back0125drill.gcode, shortened); on an ISO control the second '%' ends the
// tape there, and tolver said only "the program has no moves".
TEST(GcodeReader, WhatFollowsTheEndIsNamed) {
  const Machine m = machine("resources/machines/vmc_3axis_iso.xml", 0.0);
  const std::string mpcnc =
      "%\n(Fusion CAM 2.0.18961)\n( Posts processor: MPCNC21.cps)\n% vfd enable\nM6 T0\n"
      "% LED ON\nM62 P0\nM3 S5000\nG0 Z3 F300\nX77.688 Y49.688 F7500\nG1 Z-3 F1000\n"
      "G0 Z3\n% LED Off\nM63 P0\n%%\n";
  const std::string why = refusal(mpcnc, m.model);
  EXPECT_NE(why.find("r.nc:6: '%': the program ends here with no moves before it"),
            std::string::npos)
      << why;
  EXPECT_NE(why.find("from line 7"), std::string::npos) << why;
  EXPECT_NE(why.find("not a comment"), std::string::npos) << why;
  // Blocks after M30 (a subprogram nothing calls): read up to M30, the rest noted.
  const ClProgram p = parseGcode("G21 G90\nG0 X1 Y1 Z5\nG1 Z-1 F100\nM30\nO2000\nG1 X50\nM99\n%\n",
                                 "e.nc", m.model);
  EXPECT_TRUE(hasNote(p,
                      "the program ends at line 4 (M30); 3 line(s) after it, from line 5, "
                      "are not read"))
      << (p.notes.empty() ? "" : p.notes.back());
  EXPECT_EQ(p.path.back().line, 3);
  // A letter without a number (Marlin's "G28 X", as in blackjetrock/experimental-computer-for-
  // schools, mechanical/front_panel_62mm_name_recess_only.gcode): named, not "a number is
  // missing"; a space between letter and number stays a word.
  EXPECT_NE(refusal("G21\nG0 X1 Y1 Z5\nG28  X         ; home X\n", m.model)
                .find("r.nc:3:6: X: the word has no value"),
            std::string::npos);
  EXPECT_EQ(parseGcode("G21\nG00 X 24.9 Y 26.8 Z 5\n", "s.nc", m.model).path.back().p_w.x(), 24.9);
  // A comment holding parentheses (norn93/gcode, 3_heatsink_peck_pockets.gcode:
  // "( Drilling hole at (61.045, 67.745) )", and "cut(s)"): read up to the parenthesis that
  // balances it, with a note (it read as a stray ')' or, from "cut(s) at", as words A and T);
  // LinuxCNC refuses it, as LinuxCNC does.
  const std::string nested =
      "G21 G90\n( Drilling hole at (61.045, 67.745) )\nG0 X61.045 Y67.745 Z5 (the cut(s) at 2)\n";
  const ClProgram n = parseGcode(nested, "n.nc", m.model);
  EXPECT_EQ(n.path.back().p_w.x(), 61.045);
  EXPECT_TRUE(hasNote(n, "2 comment(s) with parentheses inside (the first at line 2)"));
  EXPECT_NE(refusal(nested, machine("resources/machines/linuxcnc_xyzac_trt.xml", 0.0).model)
                .find("r.nc:2:20: (: a comment inside a comment"),
            std::string::npos);
  EXPECT_EQ(commentEnd("(a (b) c) X1", 0), 8u);
  EXPECT_EQ(commentEnd("(a) (b)", 0), 2u);
  EXPECT_EQ(commentEnd("(a (b) X1", 0), 5u);  // never balanced: the first ')'
  // Only '%' and comments after the end: nothing to say.
  const ClProgram q = parseGcode("%\nG21 G90\nG0 X1 Y1 Z5\nM30\n(end)\n%\n", "f.nc", m.model);
  for (const std::string& note : q.notes)
    EXPECT_EQ(note.find("program ends at"), std::string::npos) << note;
}

// Text before the first '%' is the tape leader (NX writes its listing there); O numbers and
// names, ':' numbers and a name at the program start are the program's name, not subprograms.
TEST(GcodeReader, TapeLeaderAndProgramNamesAreNotBlocks) {
  const Machine m = machine("resources/machines/vmc_3axis_iso.xml", 0.0);
  const ClProgram p = parseGcode(
      "Information listing created by : someone\nDate : 1/2/2020\n\n%\nOFinal ToolPath\n"
      "N10 G21 G90 G54\nN20 G0 X10 Y20 Z30\n/N30 G1 Z-1 F100 ; block delete: the control runs "
      "it\n%\n",
      "leader.nc", m.model);
  EXPECT_TRUE(hasNote(p, "tape leader")) << (p.notes.empty() ? "" : p.notes[0]);
  EXPECT_EQ(p.part_name, "Final ToolPath");
  ASSERT_EQ(p.path.size(), 2u);
  EXPECT_EQ(p.path[0].line, 7);
  EXPECT_EQ(p.path[1].line, 8);
  // Lines that read as blocks before a closing '%' are the program, not a leader.
  const ClProgram q = parseGcode("G21\nG0 X1 Y2 Z3\nG1 X2\n%\n", "noleader.nc", m.model);
  EXPECT_EQ(q.path.size(), 2u);
  EXPECT_FALSE(hasNote(q, "tape leader"));
  EXPECT_EQ(parseGcode(":1234\nG21\nG0 X1 Y2 Z3\n", "colon.nc", m.model).path.size(), 1u);
  EXPECT_EQ(parseGcode("O<boat>\nG21\nG0 X1 Y2 Z3\n", "named.nc", m.model).path.size(), 1u);
  // Control flow is still refused, naming it; a name in the middle of the program too.
  EXPECT_NE(refusal("G21\nO100 sub\n", m.model).find("O-word sub"), std::string::npos);
  EXPECT_NE(refusal("G21\nG0 X1 Y2 Z3\nONAME\n", m.model).find("r.nc:3"), std::string::npos);
}

// Arc end points: the control's rule, never tighter than the program's printed resolution.
TEST(GcodeReader, ArcEndPointChecksFollowTheControlAndThePrintedResolution) {
  const Machine haas = machine("resources/machines/vmc_3axis_iso.xml", 0.0);
  // Four decimals in inches (2.54 um a step): an end radius 0.0002 in (5.08 um) off, as NX's
  // HAAS post prints it, is read (RS274NGC alone would allow 0.0002 in exactly).
  const ClProgram ok =
      parseGcode("G20\nG0 X0 Y0 Z0\nG2 X1.0002 Y-1.0000 I0 J-1.0000\n", "inch.nc", haas.model);
  EXPECT_GT(ok.path.size(), 10u);
  EXPECT_LT((ok.path.back().p_w - Eigen::Vector3d(25.40508, -25.4, 0)).norm(), 1e-9);
  EXPECT_NE(refusal("G20\nG0 X0 Y0 Z0\nG2 X1.0006 Y-1.0000 I0 J-1.0000\n", haas.model)
                .find("15.24 um, more than the 10.16 um"),
            std::string::npos);
  // 0.05 mm off in a 3-decimal mm program: refused, with the figures.
  const std::string bad =
      refusal("G21\nG0 X0 Y0 Z0\nG2 X10.050 Y-10.000 I0 J-10.000\n", haas.model);
  EXPECT_NE(bad.find("r.nc:3"), std::string::npos) << bad;
  EXPECT_NE(bad.find("differs from the start's by 50"), std::string::npos) << bad;
  // LinuxCNC as interp_arc.cc checks it: t = 0.02 sqrt 2 mm (28.28 um) always, 0.1 % of the
  // radius up to 100 t (2.83 mm); its tests/interp/good and bad arcs on either side.
  const Machine lcnc = machine("resources/machines/linuxcnc_xyzac_trt.xml", 0.0);
  auto lcncArc = [&](const std::string& arc) { return "G21\nG0 X0 Y0 Z0 A0 C0\n" + arc + "\n"; };
  EXPECT_GT(parseGcode(lcncArc("G2 X100.09 Y-100 I0 J-100"), "l.ngc", lcnc.model).path.size(), 10u);
  EXPECT_GT(parseGcode(lcncArc("G2 X10.028 Y-10 I0 J-10"), "l.ngc", lcnc.model).path.size(), 10u);
  EXPECT_NE(refusal(lcncArc("G2 X10.029 Y-10 I0 J-10"), lcnc.model).find("LinuxCNC's rule"),
            std::string::npos);
  // good-arc.big.metric.center-format.ngc: 2.80 mm off a 3 m radius (0.093 %) runs; 3 mm off
  // 5 m (0.06 %, beyond 100 t) does not.
  EXPECT_GT(parseGcode("G21\nG0 X0 Y0 Z0 A0 C0\nG2 X6000 I[3000 + [100 * [0.0099 * SQRT[2]]]]\n",
                       "g.ngc", lcnc.model)
                .path.size(),
            10u);
  EXPECT_NE(refusal(lcncArc("G2 X5003 Y-5000 I0 J-5000"), lcnc.model).find("2828.43 um"),
            std::string::npos);
  // LinuxCNC's P: full turns of a helix.
  const ClProgram helix =
      parseGcode("G21\nG0 X10 Y0 Z0 A0 C0\nG3 X10 Y0 Z-3 I-10 J0 P3\n", "h.ngc", lcnc.model);
  double turned = 0.0;
  for (size_t i = 1; i < helix.path.size(); ++i) {
    const Eigen::Vector2d a = helix.path[i - 1].p_w.head<2>(), b = helix.path[i].p_w.head<2>();
    turned += std::atan2(a.x() * b.y() - a.y() * b.x(), a.dot(b));
  }
  EXPECT_NEAR(turned, 3 * 2 * M_PI, 1e-6);
  EXPECT_NEAR(helix.path.back().p_w.z(), -3.0, 1e-12);
}

// Modes end where the control ends them: a group-08 word ends G234 (G43 replaces it), HAAS G28
// cancels tool length compensation and so TCP, M30 ends everything; G53 moves in machine
// coordinates under DWO without ending it.
TEST(GcodeReader, ModesEndWhereTheControlEndsThem) {
  Machine m = machine("resources/machines/umc_bc_trunnion.xml", 76.2);
  m.model.setup.work_offsets["G54"] = Eigen::Vector3d(-381, 0, -300);
  const ClProgram p = parseGcode(
      "G20\nG0 G90 G54 X0 Y0 Z1. B0 C0\nG234 H1\nG1 X0.5 Y0 Z0.5 F10.\nG43 H1\nG1 X0.5 Y0 Z1.\n"
      "G234 H1\nG1 X0 Y0 Z1.\nG28 G91 Z0\nG90 G0 X0 Y0 Z1.\nG0 B30. C0\nG254\nG0 X0 Y0 Z1.\n"
      "G53 G0 Z0\nG0 X0.1 Y0 Z1.\nG255\nM30\n",
      "modes.nc", m.model);
  std::map<int, char> mode;
  for (size_t i = 0; i < p.path.size(); ++i) mode[p.path[i].line] = p.tcp[i];
  EXPECT_EQ(mode[4], ClProgram::kTcpWords);
  EXPECT_EQ(mode[6], ClProgram::kJointWords);  // G43 ended G234
  EXPECT_EQ(mode[8], ClProgram::kTcpWords);
  EXPECT_EQ(mode[9], ClProgram::kMachineCoordinates);
  EXPECT_EQ(mode[10], ClProgram::kJointWords);  // G28 cancelled G234
  EXPECT_EQ(mode[13], ClProgram::kTcpWords);    // G254
  EXPECT_EQ(mode[14], ClProgram::kMachineCoordinates);
  EXPECT_EQ(mode[15], ClProgram::kTcpWords);  // G53 did not end G254
}

// Canned cycles G73, G81-G86, G88, G89 (and G74, G76 on ISO controls) are expanded; G87 (back
// boring) is refused naming it.
TEST(GcodeReader, CannedCyclesAreExpandedOrRefusedByName) {
  const Machine m = machine("resources/machines/vmc_3axis_iso.xml", 0.0);
  for (const char* g :
       {"G73", "G81", "G82", "G83", "G84", "G85", "G86", "G88", "G89", "G74", "G76"}) {
    const ClProgram p = parseGcode(
        std::string("G21\nG0 X0 Y0 Z20\nG99 ") + g + " X5 Y6 Z-3 R2 Q1 P100 F100\nX8\nG80\n",
        "c.nc", m.model);
    ASSERT_EQ(p.path.size(), 9u) << g;
    EXPECT_LT((p.path[3].p_w - Eigen::Vector3d(5, 6, -3)).norm(), 1e-12) << g;
    EXPECT_LT((p.path[4].p_w - Eigen::Vector3d(5, 6, 2)).norm(), 1e-12) << g;  // G99: to R
    EXPECT_EQ(p.cycle_holes, 2) << g;
  }
  EXPECT_NE(refusal("G21\nG0 X0 Y0 Z20\nG87 X5 Y6 Z-3 R2 Q1\n", m.model).find("back boring"),
            std::string::npos);
  const Machine lcnc = machine("resources/machines/linuxcnc_xyzac_trt.xml", 0.0);
  EXPECT_NE(refusal("G21\nG0 X0 Y0 Z20 A0 C0\nG76 P1 Z-3 I1 J1 K1\n", lcnc.model).find("threading"),
            std::string::npos);
}

// A move before every axis has a commanded position is not a point of the path: the tool's
// position there is not in the program (a first "G0 Z15" leaves X and Y wherever they were).
TEST(GcodeReader, MovesBeforeEveryAxisIsKnownAreNotInventedPoints) {
  const Machine m = machine("resources/machines/vmc_3axis_iso.xml", 0.0);
  const ClProgram p = parseGcode("G21\nG0 Z15\nG0 X1 Y2\nG1 Z-1\n", "start.nc", m.model);
  ASSERT_EQ(p.path.size(), 2u);
  EXPECT_EQ(p.path[0].line, 3);
  EXPECT_TRUE(hasNote(p, "1 move(s) before every axis had a commanded position (lines 2-2)"));
}

// Fanuc M98 P<program> L<times> and HAAS M97 P<block>: subprograms after the main program's
// M30, each ending in M99 (Fanuc 0i-MF "Subprogram"; HAAS "M97 Local Sub-Program Call").
// Positions by hand: two calls of G91 X5 from X0 give X5, X10; M97 P100 runs N100..M99.
TEST(GcodeReader, IsoSubprogramsAfterTheMainProgram) {
  const Machine m = machine("resources/machines/vmc_3axis_iso.xml", 0.0);
  const std::string main_part = "%\nO1000 (MAIN)\nG21 G90 G17\nG0 X0 Y0 Z-5\n";
  const std::string subs =
      "M30\nO1001 (SUB)\nG91 G1 X5 F100\nG90\nM99\nN100 G1 Y7\nG1 Y8\nM99\n%\n";
  const ClProgram p = parseGcode(main_part + "M98 P1001 L2\nG0 X20 Y0\nM97 P100\nG0 Z-10\n" + subs,
                                 "s.nc", m.model);
  const std::vector<Eigen::Vector3d> want = {{0, 0, -5},  {5, 0, -5},  {10, 0, -5}, {20, 0, -5},
                                             {20, 7, -5}, {20, 8, -5}, {20, 8, -10}};
  ASSERT_EQ(p.path.size(), want.size());
  for (size_t i = 0; i < want.size(); ++i) EXPECT_LT((p.path[i].p_w - want[i]).norm(), 1e-9) << i;
  EXPECT_EQ(p.path[1].line, 11);  // made by the subprogram's G91 G1 X5
  EXPECT_EQ(p.flow_line, 5);
  EXPECT_EQ(p.statements[4].point_count, 2);  // the call's statement holds its points
  for (const std::string& n : p.notes) EXPECT_EQ(n.find("not read"), std::string::npos) << n;
  // Refused by name.
  EXPECT_NE(refusal(main_part + "M98 P2000\n" + subs, m.model).find("no program O2000"),
            std::string::npos);
  EXPECT_NE(refusal(main_part + "G1 X1 M98 P1001\n" + subs, m.model).find("other words"),
            std::string::npos);
  EXPECT_NE(refusal(main_part + "M99\n", m.model).find("never ends"), std::string::npos);
  EXPECT_NE(refusal(main_part + "M98 P1001\nM30\nO1001\nG1 X1 F10\nM99 P20\n", m.model)
                .find("M99 P returns"),
            std::string::npos);
  EXPECT_NE(refusal(main_part + "M98 P31001\n" + subs, m.model).find("write the repeats as L"),
            std::string::npos);
  // The subprogram as a tape of its own after the main one's ("%" ... "%" "%" O1001 ... "%").
  const ClProgram two = parseGcode(
      main_part + "M98 P1001\nG0 Z-1\nM30\n%\n%\nO1001\nG1 X4 F50\nM99\n%\n", "two.nc", m.model);
  ASSERT_EQ(two.path.size(), 3u);
  EXPECT_NEAR(two.path[1].p_w.x(), 4.0, 1e-12);
  // A block number longer than any control's after the end is no subprogram (and no crash).
  const ClProgram longn =
      parseGcode(main_part +
                     "M98 P1001\nM30\nN123456789012345678901 G1 X1\nM99\nO1001\n"
                     "G1 X2 F5\nM99\n",
                 "n.nc", m.model);
  ASSERT_EQ(longn.path.size(), 2u);
  EXPECT_NEAR(longn.path[1].p_w.x(), 2.0, 1e-12);
  // Peter Smid's pattern (CNC Programming Handbook): a cycle stored with L0 where the tool is
  // (no hole there), the holes' positions in a subprogram: two holes, not three.
  const ClProgram smid = parseGcode(
      "%\nO0003\nG21 G17 G40 G80\nG90 G54 G00 X7.0 Y7.0 Z25.0\n"
      "G99 G82 R2.5 Z-3.4 P200 F200.0 L0\nM98 P1002\nG80 G0 Z25\nM30\nO1002\nX20 Y7\n"
      "X30 Y7\nM99\n%\n",
      "smid.nc", m.model);
  EXPECT_EQ(smid.cycle_holes, 2);
  for (const ClPoint& c : smid.path)
    EXPECT_FALSE(std::abs(c.p_w.x() - 7.0) < 1e-9 && c.p_w.z() < 0) << "a hole at X7";
  EXPECT_TRUE(hasNote(smid, "L0/K0: the cycle stored, no hole made there"));
  EXPECT_NE(refusal(main_part + "G81 X5 Y5 R1 Z-2 F50 L0\n", m.model).find("new position"),
            std::string::npos);
}

// A work offset the program sets itself fixes, in machine coordinates, only the axes its G10
// names (LinuxCNC "G10 L2": axes not given are not changed; "G10 L20": the current point takes
// the words' values): a touch-off `G10 L20 P1 Z0` fixes Z when the tool's Z is itself fixed, and
// `G10 L2 P1 R90` (a turn alone, LinuxCNC's sam_vel_violation.ngc) fixes none. Every axis was
// taken as fixed before: setup then wrote nothing ("the program places every point itself") for
// a program whose X and Y came from the control's G54.
TEST(GcodeReader, OwnWorkOffsetsFixOnlyTheAxesTheySet) {
  const Machine m = machine("resources/machines/linuxcnc_xyzac_trt.xml", 0.0);
  auto masks = [&](const std::string& text) {
    const ClProgram p = parseGcode(text, "o.ngc", m.model);
    return std::vector<int>(p.fixed_axes.begin(), p.fixed_axes.end());
  };
  EXPECT_EQ(masks("G21\nG10 L2 P1 X5 Y5 Z0\nG54 G0 X0 Y0 Z0\nG1 X1\n"), (std::vector<int>{7, 7}));
  EXPECT_EQ(masks("G21\nG10 L2 P1 R90\nG54 G0 X0 Y0 Z0\nG1 X1\n"), (std::vector<int>{0, 0}));
  EXPECT_EQ(masks("G21\nG10 L2 P1 Z-20\nG54 G0 X0 Y0 Z0\n"), (std::vector<int>{4}));
  // L20 where the tool's Z is in the offset (moves with the set-up): nothing fixed; after a G53
  // move (Z in machine coordinates), Z fixed; X given in the offset as before.
  EXPECT_EQ(masks("G21\nG54 G0 X0 Y0 Z5\nG10 L20 P1 Z0\nG0 X1 Z2\n"), (std::vector<int>{0, 0}));
  EXPECT_EQ(masks("G21\nG54 G0 X0 Y0\nG53 G0 Z-10\nG10 L20 P1 Z0\nG0 X1 Z2\n"),
            (std::vector<int>{4, 4}));  // the G53 move's, then Z2 in the offset set there
  // The offset's other axes still come from the set-up: its note stays.
  const ClProgram turned = parseGcode("G21\nG10 L2 P1 R90\nG54 G0 X1 Y0 Z0\n", "r.ngc", m.model);
  EXPECT_TRUE(hasNote(turned, "G54 (first used at line 2) is not in the set-up"));
}

// G92 (LinuxCNC and Fanuc "coordinate system setting"): the current point takes the words'
// values; the offset holds in every work offset; G92.2 suspends it, G92.3 restores it, G92.1
// clears it. Positions by hand: at (10, 10), G92 X0 Y0 puts X5 Y5 at (15, 15).
TEST(GcodeReader, G92OffsetsShiftEveryWorkOffset) {
  const Machine m = machine("resources/machines/linuxcnc_xyzac_trt.xml", 0.0);
  const ClProgram p = parseGcode(
      "G21 G90\nG0 X10 Y10 Z5\nG92 X0 Y0\nG1 X5 Y5 F100\nG55\nG1 X1 Y1\nG54\nG92.2\n"
      "G1 X1 Y1\nG92.3\nG1 X2 Y2\nG92.1\nG1 X3 Y3\nG92 Z0\nG1 Z-1\nM2\n",
      "g.ngc", m.model);
  const std::vector<double> x = {10, 15, 11, 1, 12, 3, 3};
  ASSERT_EQ(p.path.size(), x.size());
  for (size_t i = 0; i < x.size(); ++i) EXPECT_NEAR(p.path[i].p_w.x(), x[i], 1e-12) << i;
  EXPECT_NEAR(p.path.back().p_w.z(), 4.0, 1e-12);  // Z5 became Z0: Z-1 is 1 below it
  EXPECT_TRUE(hasNote(p, "G92 offsets (first at line 3)"));
  EXPECT_NE(refusal("G21\nG92 X0\n", m.model).find("before the program gave its position"),
            std::string::npos);
  EXPECT_NE(refusal("G21\nG0 X0 Y0 Z0 A0 C0\nG92 A5\n", m.model).find("rotary axis A"),
            std::string::npos);
  // G10 L2 R turns the work coordinate system (LinuxCNC's tests/interp/g10/g10-with-g92),
  // the G92 offset inside the turn: machine = Rz(R) (program + G92) + G5x.
  const ClProgram turned =
      parseGcode("G21\nG10 L2 P1 X0 Y0 Z0\nG54 G0 X0 Y0 Z0\nG92 X1\nG10 L2 P0 R90\nG0 X2 Y0\n",
                 "r.ngc", m.model);
  ASSERT_EQ(turned.path.size(), 2u);
  EXPECT_NEAR(turned.joints[1][0], 0.0, 1e-9);
  EXPECT_NEAR(turned.joints[1][1], 1.0, 1e-9);
  // G10 L1 P Z sets the tool length a later G43 applies (as the HEMA programs of a LinuxCNC
  // shop write it, with R, the radius, beside it): 20 mm of length lifts the gauge point 20 mm
  // over the tip.
  const ClProgram tl =
      parseGcode("G21\nG10 L1 P1 Z20 R3\nT1 M6\nG43 H1\nG0 X0 Y0 Z0\n", "t.ngc", m.model);
  const ClProgram t0 =
      parseGcode("G21\nG10 L1 P1 Z0 R3\nT1 M6\nG43 H1\nG0 X0 Y0 Z0\n", "t.ngc", m.model);
  ASSERT_EQ(tl.joints.size(), 1u);
  ASSERT_EQ(t0.joints.size(), 1u);
  EXPECT_NEAR(std::abs(tl.joints[0][2] - t0.joints[0][2]), 20.0, 1e-9);
  EXPECT_NE(refusal("G21\nG10 L1 P1 X2 Z20\n", m.model).find("other than its length"),
            std::string::npos);
}

// LinuxCNC's O-words, carried out as its interpreter does. Against LinuxCNC itself: its test
// tests/interp/flowsnake (recursive subs, if/else, named parameters, calls with five arguments)
// and the end points its interpreter printed for it (the fixture's expected list).
TEST(GcodeReader, LinuxCncOWordsAsItsInterpreterRunsThem) {
  const Machine m = machine("resources/machines/linuxcnc_xyzac_trt.xml", 0.0);
  // #<_value> and #<_value_returned> are 0 before any sub returns (LinuxCNC's tests/interp/
  // return-value: "test that #<_value> is accessible and is 0").
  const ClProgram initial =
      parseGcode("G21\nG0 X[#<_value> + 1] Y[#<_value_returned>] Z0 A0 C0\n", "v.ngc", m.model);
  ASSERT_EQ(initial.path.size(), 1u);
  EXPECT_NEAR(initial.joints[0][0], 1.0, 1e-12);
  const ClProgram snake =
      readGcodeFile(test::sourcePath("tests/fixtures/gcode/linuxcnc_flowsnake.ngc"), m.model);
  std::ifstream f(test::sourcePath("tests/fixtures/gcode/linuxcnc_flowsnake_expected.txt"));
  std::vector<Eigen::Vector3d> expected;
  for (std::string l; std::getline(f, l);) {
    if (l.empty() || l[0] == '#') continue;
    std::istringstream is(l);
    Eigen::Vector3d p;
    is >> p.x() >> p.y() >> p.z();
    expected.push_back(p);
  }
  ASSERT_EQ(expected.size(), 196u);
  // Its first move (g0 z1) comes before X and Y have a position: not a point here.
  ASSERT_EQ(snake.path.size(), expected.size() - 1);
  for (size_t i = 0; i < snake.path.size(); ++i)
    EXPECT_LT((snake.path[i].p_w - expected[i + 1]).cwiseAbs().maxCoeff(), 0.6e-4) << i;
  EXPECT_EQ(snake.flow_line, 36);  // the first call
  // The other constructs: repeat, while, if/elseif/else, do-while with break, return values,
  // global (#<_...>) and local parameters.
  const std::string text =
      "G21 G90 G17\n"
      "o<square> sub\n"
      "  G1 X[#1] Y0 F100\n  G1 X[#1] Y[#1]\n  G1 X0 Y[#1]\n  G1 X0 Y0\n"
      "  #<_sq> = [#<_sq> + 1]\n  #<local> = 99\n"
      "o<square> endsub [#1 * 4]\n"
      "#<_sq> = 0\n#<local> = 7\n"
      "G0 X0 Y0 Z5\nG1 Z-1 F50\n"
      "o100 repeat [2]\n  o<square> call [10]\no100 endrepeat\n"
      "#1 = 0\n"
      "o101 while [#1 LT 3]\n  G1 X[#1] Y-5\n"
      "  o102 if [#1 EQ 1]\n    G1 Z-2\n  o102 elseif [#1 EQ 2 AND 1]\n    G1 Z-3\n"
      "  o102 else\n    G1 Z-1.5\n  o102 endif\n  #1 = [#1 + 1]\no101 endwhile\n"
      "o103 do\n  G1 X[#1] Y-9\n  #1 = [#1 - 1]\n"
      "  o104 if [#1 LE 1]\n    o103 break\n  o104 endif\no103 while [#1 GT 0]\n"
      "G0 Z5\nG0 X[#<_value>] Y[#<_sq>] Z[#<local>]\nM2\n";
  const ClProgram p = parseGcode(text, "o.ngc", m.model);
  std::vector<Eigen::Vector3d> want = {{0, 0, 5}, {0, 0, -1}};
  for (int k = 0; k < 2; ++k)
    for (const Eigen::Vector3d& c : {Eigen::Vector3d(10, 0, -1), Eigen::Vector3d(10, 10, -1),
                                     Eigen::Vector3d(0, 10, -1), Eigen::Vector3d(0, 0, -1)})
      want.push_back(c);
  for (const Eigen::Vector3d& c :
       {Eigen::Vector3d(0, -5, -1), Eigen::Vector3d(0, -5, -1.5), Eigen::Vector3d(1, -5, -1.5),
        Eigen::Vector3d(1, -5, -2), Eigen::Vector3d(2, -5, -2), Eigen::Vector3d(2, -5, -3),
        Eigen::Vector3d(3, -9, -3), Eigen::Vector3d(2, -9, -3), Eigen::Vector3d(2, -9, 5),
        Eigen::Vector3d(40, 2, 7)})  // #<_value> = 10 * 4, two squares, the caller's #<local>
    want.push_back(c);
  ASSERT_EQ(p.path.size(), want.size());
  for (size_t i = 0; i < want.size(); ++i) EXPECT_LT((p.path[i].p_w - want[i]).norm(), 1e-9) << i;
  EXPECT_EQ(p.path[2].line, 3);  // a point made in the sub keeps the sub's line
  // The construct's points belong to its first line's statement (statements one per line).
  ASSERT_EQ(p.statements.size(), p.lines.size());
  EXPECT_EQ(p.statements[13].point_count, 8);  // o100 repeat: the two squares
  // Subs may follow the main program (LinuxCNC's tests/interp/subs-follow-main); spaces are
  // ignored ("o <name> call", "end sub"); a sub only defined is no move.
  const ClProgram after = parseGcode(
      "G21\nG0 X0 Y0 Z0\no <later> call [2]\nM30\no<later> sub\nG1 X[#1] F10\n"
      "o<later> end sub\n",
      "a.ngc", m.model);
  ASSERT_EQ(after.path.size(), 2u);
  EXPECT_NEAR(after.path[1].p_w.x(), 2.0, 1e-12);
  EXPECT_EQ(after.path[1].line, 6);
  // #1-#30 beyond the arguments are 0 in the sub (LinuxCNC zeroes them), whatever the caller's.
  const ClProgram zero = parseGcode(
      "G21\n#2 = 9\no<z> sub\nG1 X[#2] F10\no<z> endsub\nG0 X5 Y0 Z0\no<z> call [7]\n"
      "G1 Y[#2]\n",
      "z.ngc", m.model);
  ASSERT_EQ(zero.path.size(), 3u);
  EXPECT_NEAR(zero.path[1].p_w.x(), 0.0, 1e-12);
  EXPECT_NEAR(zero.path[2].p_w.y(), 9.0, 1e-12);  // the caller's #2 restored
  // Refused by name.
  EXPECT_NE(refusal("G21\nG0 X0 Y0 Z0\no<elsewhere> call\n", m.model)
                .find("r.nc:3:1: O: o<elsewhere> call: no o<elsewhere> sub"),
            std::string::npos);
  EXPECT_NE(refusal("G21\nG0 X0 Y0 Z0\no1 while [1]\nG1 X1\n", m.model)
                .find("o1 while without its o1 endwhile"),
            std::string::npos);
  EXPECT_NE(refusal("G21\nG0 X0 Y0 Z0\no1 endif\n", m.model).find("outside the construct"),
            std::string::npos);
  // A loop whose variables come back to an earlier pass's never ends: said at its first repeat
  // (it ran a million passes first, seconds); one whose variables move on is bounded.
  EXPECT_NE(refusal("G21\nG0 X0 Y0 Z0\no1 while [1]\n(nothing)\no1 endwhile\n", m.model)
                .find("o1 while: a loop that does not end (its variables come back"),
            std::string::npos);
  EXPECT_NE(refusal("G21\nG0 X0 Y0 Z0\n#1=0\no1 while [1]\n#1=[#1+1]\no1 endwhile\n", m.model)
                .find("ran 1000000 times"),
            std::string::npos);
  // A sub's loop starts afresh at each call: the same variables at its first pass of two calls
  // are no repeat.
  const ClProgram twice = parseGcode(
      "G21\nG0 X0 Y0 Z0 A0 C0\no2 sub\n#3=0\no3 while [#3 LT 2]\nG1 X[#3] F100\n#3=[#3+1]\n"
      "o3 endwhile\no2 endsub\no2 call\no2 call\nM2\n",
      "twice.ngc", m.model);
  EXPECT_EQ(twice.path.size(), 5u);
  EXPECT_NE(refusal("G21\no1 sub\nG0 X1\no1 endsub\n", m.model).find("calls none"),
            std::string::npos);
  // Bounded: constructs nested 200 deep, loops within loops that would run 10^12 lines.
  std::string deep = "G21\nG0 X0 Y0 Z0\n";
  for (int k = 1; k <= 200; ++k) deep += "o" + std::to_string(k) + " if [1]\n";
  for (int k = 200; k >= 1; --k) deep += "o" + std::to_string(k) + " endif\n";
  EXPECT_NE(refusal(deep, m.model).find("nested deeper than 100"), std::string::npos);
  EXPECT_NE(refusal("G21\nG0 X0 Y0 Z0\no1 repeat [1000000]\no2 repeat [1000000]\n(x)\n"
                    "o2 endrepeat\no1 endrepeat\n",
                    m.model)
                .find("carried out 10000000 lines"),
            std::string::npos);
  // Spaces before a function's bracket; M68's E (an analog output's number, as LinuxCNC's
  // plasma posts write it) is no axis.
  const ClProgram fn =
      parseGcode("G21\nG0 X0 Y0 Z0\nM68 E3 Q0\nG1 X[TAN [45]] F10\n", "t.ngc", m.model);
  ASSERT_EQ(fn.path.size(), 2u);
  EXPECT_NEAR(fn.path[1].p_w.x(), 1.0, 1e-12);
  EXPECT_NE(refusal("G21\nG0 X0 Y0 Z0 E3\n", m.model).find("E word"), std::string::npos);
  // Other controls keep refusing O-word flow.
  const Machine iso = machine("resources/machines/vmc_3axis_iso.xml", 0.0);
  EXPECT_NE(refusal("G21\nG0 X0 Y0 Z0\nO100 WHILE [1]\n", iso.model).find("O-word while"),
            std::string::npos);
}

// SINUMERIK arithmetic (840D sl Programming Manual, Job Planning, "Arithmetic functions") and
// dimensions (Fundamentals: AC, IC, DC, ACP, ACN): values against <cmath> and the manual's own
// ATAN2 example (20.8455 deg); the remainders and whole parts as the manual's DIV and MOD give
// them (7 DIV 0.4 = 17, 7 MOD 4.1 = 2.9); spaces inside an expression ("X = 100 - 10 * 2").
TEST(GcodeReader, SinumerikArithmeticAndDimensions) {
  const Machine m = sinumerikMachine();
  const std::string head = "N10 G54 G90 G0 X0 Y0 Z50 B0 C0 D1\n";
  const std::vector<std::pair<std::string, double>> cases = {
      {"X=SIN(30)", 0.5},
      {"X=ATAN2(30.5, 80.1)", std::atan2(30.5, 80.1) * 180.0 / M_PI},
      {"X=SQRT(POT(3)+POT(4))", 5.0},
      {"X=7 DIV 0.4", 17.0},
      {"X=7 MOD 4.1", std::fmod(7.0, 4.1)},
      {"X=1+7 MOD 4", 4.0},
      {"X = 100 - 10 * 2 + 5", 85.0},
      {"X=BOUND(0, 10, 12)", 10.0},
      {"X=MINVAL(3, -2)+MAXVAL(1, 4)", 2.0},
      {"X=TRUNC(-2.7)+ROUNDUP(2.1)+ROUND(2.5)", -2.0 + 3.0 + 3.0},
      {"X=ACOS(0.5)+ASIN(0.5)+TAN(45)", 60.0 + 30.0 + 1.0},
  };
  for (const auto& [expr, want] : cases) {
    const ClProgram p = parseGcode(head + "N20 G1 " + expr + " F100\n", "e.mpf", m.model);
    ASSERT_EQ(p.path.size(), 2u) << expr;
    EXPECT_NEAR(p.path[1].p_w.x() - p.path[0].p_w.x(), want, 1e-9) << expr;  // from X0
  }
  EXPECT_NEAR(std::atan2(30.5, 80.1) * 180.0 / M_PI, 20.8455, 1e-4);  // the manual's example
  // IC and AC against the modal G90/G91; a STRING variable takes text and moves nothing.
  const ClProgram d = parseGcode(head +
                                     "N15 DEF STRING[8] TAG = \"A-7\"\nN20 G1 X10 F100\n"
                                     "N30 X=IC(5)\nN40 G91 X=AC(2)\nN50 X3\nN60 TAG = \"B-2\"\n",
                                 "d.mpf", m.model);
  ASSERT_EQ(d.path.size(), 5u);
  EXPECT_NEAR(d.path[2].p_w.x() - d.path[0].p_w.x(), 15.0, 1e-12);
  EXPECT_NEAR(d.path[3].p_w.x() - d.path[0].p_w.x(), 2.0, 1e-12);
  EXPECT_NEAR(d.path[4].p_w.x() - d.path[0].p_w.x(), 5.0, 1e-12);
  // An arc centre given absolutely in one coordinate (I=AC) and relatively in the other.
  const ClProgram a =
      parseGcode(head + "N20 G17 G1 X10 Y0 F100\nN30 G3 X-10 Y0 I=AC(0) J0\n", "a.mpf", m.model);
  double top = -1e9;
  for (const ClPoint& c : a.path) top = std::max(top, c.p_w.y() - a.path[0].p_w.y());
  EXPECT_NEAR(top, 10.0, 1e-9);  // the half circle about the origin, not about X20
  // DC, ACP, ACN turn the endless C from 10 deg to 350 the short way (-10), then to 5 in the
  // positive sense (5), then to 10 in the negative sense (-350). Joint = nc_sign (-1) x word.
  const ClProgram r = parseGcode(
      "N10 G54 G90 G0 X0 Y0 Z50 B0 C10 D1\nN20 G0 C=DC(350)\nN30 C=ACP(5)\nN40 C=ACN(10)\n",
      "r.mpf", m.model);
  ASSERT_EQ(r.path.size(), 4u);
  constexpr double deg = M_PI / 180.0;
  EXPECT_NEAR(r.joints[1][4], 10.0 * deg, 1e-12);
  EXPECT_NEAR(r.joints[2][4], -5.0 * deg, 1e-12);
  EXPECT_NEAR(r.joints[3][4], 350.0 * deg, 1e-12);
  // G75 (fixed point, machine data): not a point; Z unknown until commanded again.
  const ClProgram fp = parseGcode(
      head + "N20 G1 X5 F100\nN30 G75 FP=1 Z0\nN40 G0 X7\nN50 Z40\nN60 X8\n", "f.mpf", m.model);
  ASSERT_EQ(fp.path.size(), 4u);  // X0, X5, then Z40 (X7 waits for Z), X8
  EXPECT_EQ(fp.path[2].line, 5);
  EXPECT_NEAR(fp.path[2].p_w.x() - fp.path[0].p_w.x(), 7.0, 1e-12);
  EXPECT_TRUE(hasNote(fp, "G75 (first at line 3)"));
  EXPECT_NE(refusal(head + "N20 G75 C0\n", m.model).find("$MA_FIX_POINT_POS"), std::string::npos);
  // A jump label marks a block and does nothing (a jump to it is refused where written).
  const ClProgram lb =
      parseGcode(head + "N20 WERKZEUG_1_1: G1 X5 F100\nRESTART:\n", "l.mpf", m.model);
  ASSERT_EQ(lb.path.size(), 2u);
  EXPECT_NEAR(lb.path[1].p_w.x() - lb.path[0].p_w.x(), 5.0, 1e-12);
  EXPECT_NE(refusal(head + "N20 GOTOF ELSEWHERE\nRESTART:\n", m.model)
                .find("GOTOF ELSEWHERE: no such label"),
            std::string::npos);
  // What it cannot be sure of is refused, naming it.
  EXPECT_NE(refusal(head + "N20 TRANS X10\nN30 G1 X=IC(5) F100\n", m.model).find("MD 42440"),
            std::string::npos);
  EXPECT_NE(refusal(head + "N20 G1 X=-7 MOD 3 F100\n", m.model).find("negative"),
            std::string::npos);
  EXPECT_NE(refusal(head + "N20 G1 X=1+IC(2) F100\n", m.model).find("whole axis word"),
            std::string::npos);
  EXPECT_NE(refusal(head + "N20 G1 B=DC(5) F100\n", m.model).find("modulo rotary axis"),
            std::string::npos);
  EXPECT_NE(refusal(head + "N15 DEF STRING[4] S\nN20 G1 X=S F100\n", m.model).find("STRING"),
            std::string::npos);
}

// SINUMERIK control flow (Job Planning, "Program jumps and branches", "Control structures"),
// against the expected outputs of an independent interpreter (CEAD-group/nc-gcode-interpreter's
// examples goto, for_loop, repeat, logic_operators, whose X, Y and angles are asserted here).
TEST(GcodeReader, SinumerikJumpsAndControlStructures) {
  const Machine m = sinumerikMachine();
  const std::string head = "N1 G54 G90 G0 X0 Y0 Z50 B0 C0 D1\n";
  auto xs = [](const ClProgram& p) {
    std::vector<double> v;
    for (const ClPoint& c : p.path) v.push_back(c.p_w.x() - p.path[0].p_w.x());
    return v;
  };
  // Jumps: GOTOF to a label after, GOTOB back while R4 > 0, GOTOF to a block number (bare or
  // with N), GOTOC to a label nowhere (goes on), GOTO searching forward then back.
  const ClProgram g = parseGcode(
      head +
          "N10 R1=30 R2=10 R4=3\nN20 GOTOF MIDDLE\nN30 X=999\nN40 REPEAT_HERE: X=R1\n"
          "N50 R1=R1+R2 R4=R4-1\nN60 IF R4>0 GOTOB REPEAT_HERE\nN70 GOTOF 90\nN80 X=999\n"
          "N90 GOTOC NOWHERE\nN100 GOTO FINISH\nN110 X=999\nN120 FINISH: M30\n"
          "MIDDLE: Y=1\nGOTOB REPEAT_HERE\n",
      "g.mpf", m.model);
  EXPECT_EQ(xs(g), (std::vector<double>{0, 0, 30, 40, 50}));
  EXPECT_NEAR(g.path[1].p_w.y() - g.path[0].p_w.y(), 1.0, 1e-12);
  EXPECT_EQ(g.path[2].line, 5);  // X=R1 at N40, the line that made it
  EXPECT_EQ(g.flow_line, 3);     // from the first control word on
  // FOR, REPEAT ... UNTIL, WHILE, LOOP with a jump out, IF/ELSE with AND OR XOR NOT, a
  // comparison's value in an assignment.
  const ClProgram f = parseGcode(
      head +
          "DEF INT COUNTER, NUMBER=3\nDEF INT TRACK_X=1, TRACK_Y=0\n"
          "FOR COUNTER=0 TO NUMBER\nG1 X=10*COUNTER F100\nENDFOR\n"
          "COUNTER=0\nREPEAT\nX=100+COUNTER\nCOUNTER=COUNTER+1\nUNTIL COUNTER>1\n"
          "WHILE COUNTER < 4\nX=200+COUNTER\nCOUNTER=COUNTER+1\nENDWHILE\n"
          "LOOP\nX=300\nGOTOF OUT\nENDLOOP\nOUT:\n"
          "IF (TRACK_X == 1 AND TRACK_Y == 1)\nX=999\nELSE\nX=400\nENDIF\n"
          "IF NOT TRACK_Y\nX=401\nENDIF\nIF ((TRACK_X == 1) XOR (TRACK_Y == 1))\nX=402\nENDIF\n"
          "R11 = COUNTER >= 4\nX = 500 + R11\n",
      "f.mpf", m.model);
  EXPECT_EQ(xs(f),
            (std::vector<double>{0, 0, 10, 20, 30, 100, 101, 202, 203, 300, 400, 401, 402, 501}));
  // Refused by name.
  EXPECT_NE(refusal(head + "WHILE 1\nX1\n", m.model).find("WHILE without its end"),
            std::string::npos);
  EXPECT_NE(refusal(head + "ENDIF\n", m.model).find("ENDIF without its IF"), std::string::npos);
  EXPECT_NE(refusal(head + "CASE R1 OF 1 GOTOF A DEFAULT GOTOF B\n", m.model).find("CASE"),
            std::string::npos);
  EXPECT_NE(refusal(head + "LOOP\nX1\nENDLOOP\n", m.model)
                .find("LOOP: a loop that does not end (its variables come back"),
            std::string::npos);
  EXPECT_NE(refusal(head + "R1 = 6 B_AND 3\n", m.model).find("bit operator B_AND"),
            std::string::npos);
  EXPECT_NE(refusal(head + "X=$AA_IW[X]\n", m.model).find("system variable $AA_IW"),
            std::string::npos);
}

// Sinumerik's G153 (frames and base frame suppressed) is a move in machine coordinates, as SUPA
// and G53: it was ignored and its block read in the work offset. G53/SUPA/G153 alone move
// nothing (they added a point). G641's ADIS=/ADISPOS= (rounding distances) are ignored, G110-G112
// (poles of polar coordinates) refused by name.
TEST(GcodeReader, SinumerikFrameSuppressionAndRounding) {
  const Machine m = sinumerikMachine();
  const std::string head = "G710\nG54\nTRAFOOF\nG0 X0 Y0 Z-5 B0 C0\n";
  const ClProgram g153 = parseGcode(head + "G153 G0 Z0\nM30\n", "g153.mpf", m.model);
  const ClProgram supa = parseGcode(head + "SUPA G0 Z0\nM30\n", "supa.mpf", m.model);
  ASSERT_EQ(g153.path.size(), 2u);
  ASSERT_EQ(supa.path.size(), 2u);
  EXPECT_EQ(g153.tcp[1], ClProgram::kMachineCoordinates);
  EXPECT_EQ(g153.joints[1][2], supa.joints[1][2]);
  for (const char* alone : {"G153\n", "SUPA\n"})
    EXPECT_EQ(parseGcode(head + alone + "M30\n", "a.mpf", m.model).path.size(), 1u) << alone;
  const ClProgram adis =
      parseGcode(head + "G641 ADIS=0.5 ADISPOS=1\nG0 X1\nM30\n", "r.mpf", m.model);
  EXPECT_TRUE(hasNote(adis, "ADIS="));
  EXPECT_NE(refusal(head + "G111 X0 Y0\n", m.model).find("pole of polar coordinates"),
            std::string::npos);
  const Machine vmc = machine("resources/machines/vmc_3axis_iso.xml", 0.0);
  EXPECT_EQ(parseGcode("G21\nG0 X0 Y0 Z-5\nG53\nG0 X1\n", "g53.nc", vmc.model).path.size(), 2u);
  // Spindle and bookkeeping words no path depends on are ignored (they were refused); TRAORI(1)
  // is TRAORI, TRAORI(2) another kinematics, refused.
  const ClProgram words =
      parseGcode(head +
                     "SPOS=0\nS1=1000 M1=3\nFGROUP(X,Y,Z)\nGROUP_BEGIN(0,\"x\",0,0)\nSETPIECE(1)\n"
                     "GROUP_END(0,0)\nG0 X1\nM30\n",
                 "w.mpf", m.model);
  EXPECT_EQ(words.path.size(), 2u);
  EXPECT_TRUE(hasNote(words, "SPOS="));
  EXPECT_NE(refusal(head + "M1=6\n", m.model).find("M function of spindle 1"), std::string::npos);
  const ClProgram traori =
      parseGcode("G710\nG54\nTRAORI(1)\nG0 X0 Y0 Z10 B0 C0\nTRAFOOF\nM30\n", "t.mpf", m.model);
  EXPECT_EQ(traori.tcp.front(), ClProgram::kTcpWords);
  EXPECT_NE(refusal("G710\nTRAORI(2)\n", m.model).find("transformation data set 2"),
            std::string::npos);
  // A DEF'd variable named like a spindle word stays a variable.
  const ClProgram var = parseGcode(head + "DEF REAL S1\nS1=7\nG0 X=S1\nM30\n", "v.mpf", m.model);
  EXPECT_NEAR(var.joints.back()[0] - var.joints.front()[0], 7.0, 1e-9);
}

// Sinumerik 840D as NX posts it: DEF, assignments, ADDR=expression, SUPA, TRAFOOF, T="name",
// D0/D1, MSG, CYCLE832, MCALL CYCLE81: the real program reads, every construct carried out.
TEST(GcodeReader, SinumerikProgramAsNxPostsIt) {
  const Machine m = sinumerikMachine();
  const ClProgram p =
      readGcodeFile(test::sourcePath("tests/fixtures/gcode/nx_sin840d_Keychain.mpf"), m.model);
  EXPECT_EQ(p.cycles, 1);
  EXPECT_EQ(p.cycle_holes, 1);
  // T="name" then M6: the tools by their names (a --tools file gives their geometry).
  ASSERT_GE(p.cutters.size(), 2u);
  EXPECT_EQ(p.cutters[0].kind, "ENTFRAESER_D8_N_90GRAD");
  EXPECT_EQ(p.cutters.back().kind, "BOHRER_D3.3_VHM");
  // N190 SUPA G0 X=_X_HOME Y=_Y_HOME ...: machine coordinates -365, 224 (Z=_Z_HOME 610 before).
  bool supa = false;
  for (size_t i = 0; i < p.path.size(); ++i)
    if (p.path[i].line == 19) {
      supa = true;
      EXPECT_EQ(p.tcp[i], ClProgram::kMachineCoordinates);
      EXPECT_NEAR(p.joints[i][0], -365.0, 1e-12);
      EXPECT_NEAR(p.joints[i][1], 224.0, 1e-12);
      EXPECT_NEAR(p.joints[i][2], 610.0, 1e-12);
      EXPECT_EQ(p.fixed_axes[i], 7);
    }
  EXPECT_TRUE(supa);
  // N330 G0 X-10.46 Y-22.721 Z16. in G54: the tip at (-10.46, -22.721, 16) in the part frame
  // (part zero at the G54 origin), joints = word + offset.
  for (size_t i = 0; i < p.path.size(); ++i)
    if (p.path[i].line == 33) {
      EXPECT_NEAR(p.joints[i][0], -10.46 - 300, 1e-9);
      EXPECT_NEAR(p.joints[i][2], 16 + 200, 1e-9);
    }
  // The drilled hole: MCALL CYCLE81(10.,0.,3.,-6.1835) at X-12.5 Y-58.: in to -6.1835.
  double deepest = 1e9;
  for (const ClPoint& c : p.path)
    if (c.line == 633) deepest = std::min(deepest, c.p_w.z());
  EXPECT_NEAR(deepest, -6.1835 + (0.0), 1e-6);
  EXPECT_TRUE(hasNote(p, "CYCLE832"));
  // What it cannot carry out is refused naming the construct and the line.
  const std::string base = "N10 DEF REAL _A\nN20 _A=5\n";
  EXPECT_NE(refusal(base + "N30 GOTOF MARK\n", m.model).find("GOTOF"), std::string::npos);
  EXPECT_NE(refusal(base + "N30 WHILE _A>0\n", m.model).find("WHILE"), std::string::npos);
  EXPECT_NE(refusal(base + "N30 G0 X=SINH(30)\n", m.model).find("not a SINUMERIK arithmetic"),
            std::string::npos);
  EXPECT_NE(refusal(base + "N30 G0 X=_B\n", m.model).find("_B has no value"), std::string::npos);
  EXPECT_NE(refusal(base + "N30 CYCLE86(10,0,2,-5)\n", m.model).find("CYCLE86"), std::string::npos);
  // 3+2 as NX posts it: the table positioned, TRAORI, the frame turned with AROT: the tool axis
  // B90 gives is the turned frame's z (this machine file's senses, ISO 841), and the program's
  // Z words run along it. With the senses the other way the program is refused, naming them.
  const std::string tilted =
      "N10 G54 G0 X0 Y0 Z50 B0 C0 D1\nN20 G0 B90. C0.0\nN30 TRAORI\n"
      "N40 AROT Y90.\nN50 G0 X5. Y-15. Z100.\nN60 G1 Z2.\n";
  const ClProgram tp = parseGcode(tilted, "tilted.mpf", m.model);
  ASSERT_EQ(tp.path.size(), 4u);
  EXPECT_LT((tp.path[2].u_w - Eigen::Vector3d(1, 0, 0)).norm(), 1e-12);
  // Z100 -> Z2 in the turned frame: 98 mm down its z, which is the part's +x.
  EXPECT_LT((tp.path[3].p_w - tp.path[2].p_w - Eigen::Vector3d(-98, 0, 0)).norm(), 1e-9);
  Machine flipped = m;
  for (Axis& a : flipped.model.axes)
    if (a.isRotary()) a.nc_sign = -a.nc_sign;
  EXPECT_NE(refusal(tilted, flipped.model).find("rotary senses or zeros"), std::string::npos);
  // TRANS moves the work frame; G0 X=_A*2 evaluates.
  const ClProgram t = parseGcode(
      base + "N25 G54 G0 X0 Y0 Z50 D1\nN30 TRANS X10 Y5\nN40 G0 X=_A*2 Y0 Z10\n", "t.mpf", m.model);
  ASSERT_EQ(t.path.size(), 2u);
  EXPECT_NEAR(t.joints[1][0], -300 + 10 + 10, 1e-9);  // G54 + TRANS + _A*2
  EXPECT_NEAR(t.joints[1][1], 5, 1e-9);
  EXPECT_LT((t.path[1].p_w - t.path[0].p_w - Eigen::Vector3d(20, 5, -40)).norm(), 1e-9);
  // ROT RPL=90 turns the working plane (G17: about Z) as ROT Z90 does.
  const ClProgram rpl = parseGcode(
      base + "N25 G54 G17 G0 X0 Y0 Z50 D1\nN30 ROT RPL=90\nN40 G0 X10 Y0 Z10\n", "r.mpf", m.model);
  const ClProgram rz = parseGcode(
      base + "N25 G54 G17 G0 X0 Y0 Z50 D1\nN30 ROT Z90\nN40 G0 X10 Y0 Z10\n", "z.mpf", m.model);
  ASSERT_EQ(rpl.path.size(), 2u);
  EXPECT_LT((rpl.path[1].p_w - rz.path[1].p_w).norm(), 1e-12);
  EXPECT_NEAR(rpl.path[1].p_w.y() - rpl.path[0].p_w.y(), 10, 1e-9);
  EXPECT_NE(refusal(base + "N30 SCALE X2 Y2\n", m.model).find("SCALE"), std::string::npos);
  EXPECT_NE(refusal(base + "N30 MIRROR X0\n", m.model).find("MIRROR"), std::string::npos);
  EXPECT_NE(refusal(base + "N30 LIMS=3000\n", m.model).find("LIMS= is neither a variable"),
            std::string::npos);
  EXPECT_EQ(parseGcode(base + "N30 R1=4 R2=R1*2\nN40 G54 G0 X=R2 Y0 Z10 D1\n", "r.mpf", m.model)
                .joints[0][0],
            -300 + 8);
}

// CYCLE800 (SINUMERIK 840D sl, "Swivel plane - CYCLE800"): the swivel frame TRANS X0 : rotation :
// TRANS X1, the rotaries turning the tool along its z, the points held in it, against the same
// operation written with the frame instructions (TRANS, AROT, ATRANS) and TRAORI with the rotary
// words posted by hand (ISO 841 senses: B+30 tilts the tool towards +x).
TEST(GcodeReader, Cycle800SwivelsThePlaneAsTheFrameInstructionsDo) {
  const Machine m = sinumerikMachine();
  const std::string head = "N10 G54 G0 X0 Y0 Z80 B0 C0 D1\n";
  const std::string ops = "N50 G0 X5 Y-15 Z40\nN60 G1 Z2 F500\nN70 X25 Y10\nN80 G0 Z40\n";
  // The points from the first in the swivelled plane on (the frame version has one more: the
  // rotary positioning block).
  auto same = [](const ClProgram& a, const ClProgram& b) {
    ASSERT_EQ(a.path.size() + 1, b.path.size());
    for (size_t i = 1; i < a.path.size(); ++i) {
      EXPECT_LT((a.path[i].p_w - b.path[i + 1].p_w).norm(), 1e-9) << i;
      EXPECT_LT((a.path[i].u_w - b.path[i + 1].u_w).norm(), 1e-12) << i;
    }
  };
  // Axis by axis X, Y, Z (_MODE 57), 30 deg about y, reference point X10 and zero point X5 Z-3.
  const ClProgram c =
      parseGcode(head + "N20 CYCLE800(1,\"TC1\",0,57,10,0,0,0,30,0,5,0,-3,1,100,1)\n" + ops +
                     "N90 CYCLE800()\nN100 G0 X0 Y0 Z80\n",
                 "c800.mpf", m.model);
  const ClProgram f = parseGcode(head +
                                     "N20 G0 B30 C0\nN25 TRAORI\nN30 TRANS X10\nN35 AROT Y30\n"
                                     "N40 ATRANS X5 Z-3\n" +
                                     ops + "N90 TRAFOOF\nN95 TRANS\nN100 G0 X0 Y0 Z80\n",
                                 "frames.mpf", m.model);
  same(c, f);
  ASSERT_EQ(c.path.size(), 6u);
  const Eigen::Vector3d z30(std::sin(30 * kDeg), 0, std::cos(30 * kDeg));
  EXPECT_LT((c.path[1].u_w - z30).norm(), 1e-12);
  // Z40 -> Z2: 38 mm down the swivelled z; _DIR +1 took the higher B (B30 C0).
  EXPECT_LT((c.path[2].p_w - c.path[1].p_w + 38 * z30).norm(), 1e-9);
  EXPECT_NEAR(c.joints[1][3], -30 * kDeg, 1e-12);  // B word 30, nc_sign -1
  EXPECT_EQ(c.tcp[1], ClProgram::kTcpWords);
  // After CYCLE800() the plane is the settable frame again and the axes are joints (the
  // rotaries stay where the swivel put them).
  EXPECT_EQ(c.tcp[5], ClProgram::kJointWords);
  EXPECT_NEAR(c.joints[5][0], -300, 1e-9);
  EXPECT_NEAR(c.joints[5][2], 280, 1e-9);
  // _DIR -1: the other solution (B-30, C turned half a turn), the same points.
  const ClProgram d =
      parseGcode(head + "N20 CYCLE800(1,\"TC1\",0,57,10,0,0,0,30,0,5,0,-3,-1,100,1)\n" + ops,
                 "c800.mpf", m.model);
  ASSERT_EQ(d.path.size(), 5u);
  EXPECT_NEAR(d.joints[1][3], 30 * kDeg, 1e-12);
  EXPECT_NEAR(std::abs(d.joints[1][4]), M_PI, 1e-12);
  for (size_t i = 1; i < d.path.size(); ++i)
    EXPECT_LT((d.path[i].p_w - c.path[i].p_w).norm(), 1e-9);
  // Z, Y, X (_MODE 27): 90 about z then 30 about the turned y, as AROT Z90 then AROT Y30.
  const ClProgram zyx = parseGcode(
      head + "N20 CYCLE800(1,\"\",0,27,0,0,0,90,30,0,0,0,0,1,100,1)\n" + ops, "zyx.mpf", m.model);
  const ClProgram zyx_f =
      parseGcode(head + "N20 G0 B30 C90\nN25 TRAORI\nN30 AROT Z90\nN35 AROT Y30\n" + ops,
                 "zyx_f.mpf", m.model);
  same(zyx, zyx_f);
  // Rotary axes direct (_MODE 192): rotary axis 1 is the tilting B; the frame turns with it.
  const ClProgram direct =
      parseGcode(head + "N20 CYCLE800(0,\"T\",0,192,0,0,0,30,0,0,0,0,0,0,100,1)\n" + ops,
                 "direct.mpf", m.model);
  same(direct,
       parseGcode(head + "N20 G0 B30 C0\nN25 TRAORI\nN35 AROT Y30\n" + ops, "d.mpf", m.model));
  // Additive (_ST 1): a second swivel turns the first one further.
  const ClProgram add = parseGcode(head +
                                       "N20 CYCLE800(1,\"\",0,57,0,0,0,0,20,0,0,0,0,1,100,1)\n"
                                       "N30 CYCLE800(1,\"\",1,57,0,0,0,0,10,0,0,0,0,1,100,1)\n" +
                                       ops,
                                   "add.mpf", m.model);
  const ClProgram once = parseGcode(
      head + "N20 CYCLE800(1,\"\",0,57,0,0,0,0,30,0,0,0,0,1,100,1)\n" + ops, "once.mpf", m.model);
  ASSERT_EQ(add.path.size(), once.path.size());
  for (size_t i = 1; i < add.path.size(); ++i)
    EXPECT_LT((add.path[i].p_w - once.path[i].p_w).norm(), 1e-9);
  // Refused by name: solid angles, a plane the rotaries cannot reach, a mode naming no axis.
  EXPECT_NE(refusal(head + "N20 CYCLE800(1,\"\",0,64,0,0,0,0,30,0,0,0,0,1,100,1)\n", m.model)
                .find("solid angles"),
            std::string::npos);
  EXPECT_NE(refusal(head + "N20 CYCLE800(1,\"\",0,57,0,0,0,0,120,0,0,0,0,1,100,1)\n", m.model)
                .find("outside travel"),
            std::string::npos);
  EXPECT_NE(refusal(head + "N20 CYCLE800(1,\"\",0,3,0,0,0,0,30,0,0,0,0,1,100,1)\n", m.model)
                .find("names no axis"),
            std::string::npos);
  // _DIR 0 leaves the rotaries where the program puts them: not turned, the check refuses.
  EXPECT_NE(refusal(head + "N20 CYCLE800(1,\"\",0,57,0,0,0,0,30,0,0,0,0,0,100,1)\n" + ops, m.model)
                .find("rotated frame"),
            std::string::npos);
}

// G68.2 (Fanuc, HAAS NGC): the feature coordinate system X Y Z I J K (Euler Z, X, Z), G53.1
// turns the tool along its Z, the points held in it until G69: the same path as G234 with the
// rotary words and the XYZ words computed by the documented formula p = o + R p_feature.
TEST(GcodeReader, TiltedWorkingPlaneG682AsItsTcpTwin) {
  Machine m = machine("resources/machines/umc_bc_trunnion.xml", 76.2);
  const std::string head = "G21 G90 G54\nT1 M6\nG0 G43 H1 X0 Y0 Z50 B0 C0\n";
  const ClProgram a =
      parseGcode(head +
                     "G68.2 X10 Y0 Z2 I20 J30 K-40\nG53.1\nG0 X5 Y5 Z20\nG1 Z0 F500\n"
                     "G1 X15 Y-5\nG69\nG0 Z200\nM30\n",
                 "g682.nc", m.model);
  ASSERT_EQ(a.path.size(), 5u);
  const Eigen::Matrix3d R = (Eigen::AngleAxisd(20 * kDeg, Eigen::Vector3d::UnitZ()) *
                             Eigen::AngleAxisd(30 * kDeg, Eigen::Vector3d::UnitX()) *
                             Eigen::AngleAxisd(-40 * kDeg, Eigen::Vector3d::UnitZ()))
                                .toRotationMatrix();
  const Eigen::Vector3d o(10, 0, 2);
  // The tool along the plane's Z.
  EXPECT_LT((a.path[1].u_w - R.col(2)).norm(), 1e-12);
  EXPECT_EQ(a.tcp[1], ClProgram::kTcpWords);
  EXPECT_EQ(a.tcp[4], ClProgram::kJointWords);  // after G69
  // The twin: G234 with the rotary words G53.1 chose and the XYZ words o + R p.
  const double b = -a.joints[1][3] / kDeg, c = -a.joints[1][4] / kDeg;  // nc_sign -1
  std::string twin = head + "G234 H1\n";
  const Eigen::Vector3d pts[3] = {{5, 5, 20}, {5, 5, 0}, {15, -5, 0}};
  char buf[200];
  for (int k = 0; k < 3; ++k) {
    const Eigen::Vector3d p = o + R * pts[k];
    std::snprintf(buf, sizeof buf, "%s X%.12f Y%.12f Z%.12f B%.12f C%.12f\n", k == 0 ? "G0" : "G1",
                  p.x(), p.y(), p.z(), b, c);
    twin += buf;
  }
  const ClProgram t = parseGcode(twin, "twin.nc", m.model);
  ASSERT_EQ(t.path.size(), 4u);
  for (int k = 0; k < 3; ++k) {
    EXPECT_LT((a.path[k + 1].p_w - t.path[k + 1].p_w).norm(), 1e-9) << k;
    EXPECT_LT((a.path[k + 1].u_w - t.path[k + 1].u_w).norm(), 1e-12) << k;
  }
  EXPECT_TRUE(hasNote(a, "G53.1 turns the rotaries"));
  // P1: roll, pitch, yaw about the fixed axes.
  const ClProgram rpy =
      parseGcode(head + "G68.2 P1 X0 Y0 Z0 I0 J30 K90\nG53.1\nG0 X5 Y5 Z20\n", "rpy.nc", m.model);
  const Eigen::Matrix3d R1 = (Eigen::AngleAxisd(90 * kDeg, Eigen::Vector3d::UnitZ()) *
                              Eigen::AngleAxisd(30 * kDeg, Eigen::Vector3d::UnitY()))
                                 .toRotationMatrix();
  EXPECT_LT((rpy.path.back().u_w - R1.col(2)).norm(), 1e-12);
  // Refused: other forms, G53.1 without a plane, a plane the rotaries cannot reach.
  EXPECT_NE(refusal(head + "G68.2 P2 X0 Y0 Z0 I0 J30 K0\n", m.model).find("G68.2 P2"),
            std::string::npos);
  EXPECT_NE(refusal(head + "G53.1\n", m.model).find("without a tilted"), std::string::npos);
  EXPECT_NE(refusal(head + "G68.2 X0 Y0 Z0 I0 J120 K0\nG53.1\n", m.model).find("outside travel"),
            std::string::npos);
}

// Sinumerik orientation vectors (A3= B3= C3=, ORIWKS) under TRAORI give the tool direction in the
// workpiece coordinates: the same path as the rotary words a post computes for it; CR= arcs are
// the ISO R arcs; what changes the path unseen (RND=, orientation angles, ORIMKS vectors) is
// refused.
TEST(GcodeReader, SinumerikOrientationVectorsAndRadiusArcs) {
  const Machine m = sinumerikMachine();
  const std::string head = "N10 G54 G0 X0 Y0 Z80 B0 C0 D1\nN20 TRAORI\n";
  const double s30 = std::sin(30 * kDeg), c30 = std::cos(30 * kDeg);
  char v[200];
  std::snprintf(v, sizeof v,
                "N30 G1 X20 Y5 Z3 A3=%.12f B3=0 C3=%.12f F500\nN40 X25 Y0 A3=0 B3=%.12f C3=%.12f\n",
                s30, c30, s30, c30);
  const ClProgram vec = parseGcode(head + v, "vec.mpf", m.model);
  // B+30 tilts the tool towards +x (ISO 841); towards +y it is C90 then B30 (C turns the tool about
  // z).
  const ClProgram words =
      parseGcode(head + "N30 G1 X20 Y5 Z3 B30 C0 F500\nN40 X25 Y0 B30 C90\n", "w.mpf", m.model);
  ASSERT_EQ(vec.path.size(), words.path.size());
  for (size_t i = 0; i < vec.path.size(); ++i) {
    EXPECT_LT((vec.path[i].p_w - words.path[i].p_w).norm(), 1e-9) << i;
    EXPECT_LT((vec.path[i].u_w - words.path[i].u_w).norm(), 1e-9) << i;
  }
  EXPECT_LT((vec.path.back().u_w - Eigen::Vector3d(0, s30, c30)).norm(), 1e-9);
  // CR= is the radius form: a quarter circle as with I J.
  const std::string arc0 = "N10 G54 G0 X10 Y0 Z5 D1\nN20 G17 G1 Z0 F100\n";
  const ClProgram cr = parseGcode(arc0 + "N30 G3 X0 Y10 CR=10\n", "cr.mpf", m.model);
  const ClProgram ij = parseGcode(arc0 + "N30 G3 X0 Y10 I-10 J0\n", "ij.mpf", m.model);
  ASSERT_EQ(cr.path.size(), ij.path.size());
  for (size_t i = 0; i < cr.path.size(); ++i)
    EXPECT_LT((cr.path[i].p_w - ij.path[i].p_w).norm(), 1e-9);
  // Refused, named.
  EXPECT_NE(refusal(arc0 + "N30 G1 X20 RND=2\nN40 Y20\n", m.model).find("RND"), std::string::npos);
  EXPECT_NE(refusal(head + "N30 G1 X0 A2=10 B2=20 C2=0\n", m.model).find("A2"), std::string::npos);
  EXPECT_NE(refusal(head + "N25 ORIMKS\nN30 G1 X0 A3=0 B3=0 C3=1\n", m.model).find("ORIMKS"),
            std::string::npos);
  EXPECT_NE(refusal("N10 G54 G0 X0 Y0 Z80 D1\nN30 G1 X0 A3=0 B3=0 C3=1\n", m.model)
                .find("outside TRAORI"),
            std::string::npos);
  EXPECT_NE(refusal(head + "N30 G1 X0 A3=1 B3=0 C3=-0.6\n", m.model).find("outside travel"),
            std::string::npos);
}

// TURN= (Sinumerik's helix: full circles added to the arc, 0 to 999; NX's Sinumerik post writes
// TURN=0 on helical ramps, as in ElMoe's bottle opener): TURN=0 is the arc alone; TURN=2 runs two
// full circles and then the arc, the infeed linear in the angle over the whole helix (checked
// against the helix's own formula); a fraction, or TURN= on a line, is refused naming TURN.
TEST(GcodeReader, SinumerikTurnAddsFullCirclesToAHelix) {
  const Machine m = sinumerikMachine();
  const std::string head = "N10 G54 G0 X10 Y0 Z5 B0 C0 D1\nN20 G17 G1 Z0 F100\n";
  const ClProgram plain = parseGcode(head + "N30 G3 X0 Y10 Z-2 I-10 J0\n", "a.mpf", m.model);
  const ClProgram zero = parseGcode(head + "N30 G3 X0 Y10 Z-2 I-10 J0 TURN=0\n", "b.mpf", m.model);
  ASSERT_EQ(plain.path.size(), zero.path.size());
  for (size_t i = 0; i < plain.path.size(); ++i)
    EXPECT_EQ(plain.path[i].p_w, zero.path[i].p_w) << i;
  const ClProgram two = parseGcode(head + "N30 G3 X0 Y10 Z-2 I-10 J0 TURN=2\n", "c.mpf", m.model);
  // The helix's points: angle from 0 to 2 * 2 pi + pi / 2 about (0, 0), counter-clockwise, z from
  // 0 to -2 in proportion to the angle; in the part frame, the work offset and machine aside:
  // compared through the first point (the start of the helix).
  std::vector<Eigen::Vector3d> helix;
  size_t first = 0;
  while (first < two.path.size() && two.path[first].line != 3) ++first;
  ASSERT_LT(first, two.path.size());
  const Eigen::Vector3d origin = two.path[first - 1].p_w - Eigen::Vector3d(10, 0, 0);
  const double total = 2 * 2 * M_PI + M_PI / 2;
  double last_angle = 0;
  for (size_t i = first; i < two.path.size(); ++i) {
    const Eigen::Vector3d q = two.path[i].p_w - origin;
    EXPECT_NEAR(std::hypot(q.x(), q.y()), 10.0, 1e-9) << i;
    double angle = std::atan2(q.y(), q.x());
    while (angle < last_angle - 1e-9) angle += 2 * M_PI;  // unwrapped, never backwards
    EXPECT_NEAR(q.z(), -2.0 * angle / total, 1e-9) << i;
    last_angle = angle;
  }
  EXPECT_NEAR(last_angle, total, 1e-9);
  EXPECT_GT(two.path.size() - first, 8 * (plain.path.size() - first));
  EXPECT_NE(refusal(head + "N30 G3 X0 Y10 Z-2 I-10 J0 TURN=1.5\n", m.model).find("TURN"),
            std::string::npos);
  EXPECT_NE(refusal(head + "N30 G1 X0 Y10 TURN=2\n", m.model).find("TURN"), std::string::npos);
}

// Two more programs of the Keychain's data set (ElMoe/Production-Data-Set-for-Five-Axis-CNC-
// Milling-with-Multiple-Changeovers, NC_code: NX's Sinumerik 840D post, B/C table), byte for
// byte: the bottle opener ramps down on 234 helices written with TURN=0, refused before TURN=
// was read; the coordinate-system part swivels the table (B-90, C up to -270). Both read whole;
// the bottle opener's first helix (N1540 G3 ... Z-12. TURN=0) descends from -11.82 to -12.
TEST(GcodeReader, SinumerikProgramsOfTheSameDataSetRead) {
  const Machine m = sinumerikMachine();
  const ClProgram bottle =
      readGcodeFile(test::sourcePath("tests/fixtures/gcode/nx_sin840d_Bottle_opener.txt"), m.model);
  EXPECT_EQ(bottle.arcs_expanded, 1553);
  double z_first = NAN, z_last = NAN, z_before = 1e9;
  for (const ClPoint& c : bottle.path) {
    if (c.line != 154) continue;
    if (std::isnan(z_first)) z_first = c.p_w.z();
    EXPECT_LE(c.p_w.z(), z_before + 1e-12);
    z_before = z_last = c.p_w.z();
  }
  EXPECT_GT(z_first, -12.0);
  EXPECT_LT(z_first, -11.82);
  EXPECT_NEAR(z_last, -12.0, 1e-9);
  const ClProgram cross =
      readGcodeFile(test::sourcePath("tests/fixtures/gcode/nx_sin840d_Achskreuz.mpf"), m.model);
  EXPECT_EQ(cross.arcs_expanded, 696);
  EXPECT_GT(cross.path.size(), 20000u);
}

// Tools per operation: M6 switches the cutter to the selected T; its geometry comes from the
// post's tool comments (Fusion, LinuxCNC posts); posts that write no M6 change tools at T.
TEST(GcodeReader, ToolChangesCarryTheCommentsGeometry) {
  const Machine m = machine("resources/machines/vmc_3axis_iso.xml", 0.0);
  const ClProgram p = parseGcode(
      "(T1 D=6 CR=0 - flat end mill)\n(T2 D=3 CR=1.5 - ball end mill)\nG21\nT1 M6\n"
      "G0 X0 Y0 Z10\nG1 Z-1 F100\nT3\nT2 M6\nG0 X5 Y5 Z10\nG1 Z-1\nT3 M6\nG0 Z20\nM30\n",
      "tools.nc", m.model);
  ASSERT_EQ(p.cutters.size(), 3u);
  EXPECT_EQ(p.cutters[0].kind, "T1");
  EXPECT_EQ(p.cutters[0].line, 4);
  EXPECT_EQ(p.cutters[0].values, (std::vector<double>{6, 0}));
  EXPECT_EQ(p.cutters[1].kind, "T2");  // T3 preselected at line 7 did not change the tool
  EXPECT_EQ(p.cutters[1].line, 8);
  EXPECT_EQ(p.cutters[1].values, (std::vector<double>{3, 1.5}));
  EXPECT_EQ(p.cutters[2].kind, "T3");
  EXPECT_TRUE(p.cutters[2].values.empty());  // no comment gives T3's geometry
  // The real Fusion program: "T1" without M6, its tool in a comment.
  const ClProgram f =
      readGcodeFile(test::sourcePath("tests/fixtures/gcode/fusion_led-floor_1124_jig.nc"), m.model);
  ASSERT_EQ(f.cutters.size(), 1u);
  EXPECT_EQ(f.cutters[0].values, (std::vector<double>{2.8, 0}));
  // LinuxCNC's boat post: "( TOOL: T1 = 10.0 dia. ENDMILL... )" then T1 M6.
  const Machine l = machine("resources/machines/linuxcnc_xyzac_trt.xml", 0.0);
  const ClProgram b =
      readGcodeFile(test::sourcePath("tests/fixtures/gcode/linuxcnc_boat-xyzac.ngc"), l.model);
  ASSERT_EQ(b.cutters.size(), 1u);
  EXPECT_EQ(b.cutters[0].values, (std::vector<double>{10, 0}));
  // Mastercam's Fanuc/HAAS posts, in inches: "( name TOOL - n DIA. OFF. - n LEN. - n DIA. - d )".
  const ClProgram mc = parseGcode(
      "%\nO0001\n( 1/16 FLAT ENDMILL TOOL - 1 DIA. OFF. - 1 LEN. - 1 DIA. - .0625)\n"
      "( TOOL - 6 2\"  FACE MILL    DIA. OFF. - 6  LEN. - 6  DIA. - 2. )\n"
      "( 1/8 BALL ENDMILL TOOL - 14 DIA. OFF. - 14 LEN. - 14 TOOL DIA. - .125 )\nG20\n"
      "T1 M6\nG0 X0 Y0 Z1\nG1 Z-.01 F10\nT6 M6\nG0 Z1\nG1 Z-.01\nT14 M6\nG0 Z1\nG1 Z-.01\nM30\n%\n",
      "mastercam.nc", m.model);
  ASSERT_EQ(mc.cutters.size(), 3u);
  EXPECT_NEAR(mc.cutters[0].values.at(0), 0.0625 * 25.4, 1e-12);
  EXPECT_EQ(mc.cutters[0].values.at(1), 0.0);
  EXPECT_NEAR(mc.cutters[1].values.at(0), 2 * 25.4, 1e-12);
  EXPECT_NEAR(mc.cutters[2].values.at(0), 0.125 * 25.4, 1e-12);
  EXPECT_NEAR(mc.cutters[2].values.at(1), 0.0625 * 25.4, 1e-12);  // a ball
  // CamBam's tool list "( T0 : 1.0 )" (the diameter alone), then "T0 M6": the head and end of a
  // real CamBam program (winder/Universal-G-Code-Sender, test_files/enclosure.nc: lines 1-40 and
  // its last three). T0 was taken as the empty spindle and the program had no cutter.
  // A fixture's one cutter: its tool, line and geometry.
  auto oneCutter = [&](const std::string& fixture, const std::string& kind, int line,
                       const std::vector<double>& values) {
    const ClProgram read =
        readGcodeFile(test::sourcePath("tests/fixtures/gcode/" + fixture), m.model);
    EXPECT_EQ(read.cutters.size(), 1u) << fixture;
    if (read.cutters.empty()) return read;
    EXPECT_EQ(read.cutters[0].kind, kind) << fixture;
    if (line > 0) {
      EXPECT_EQ(read.cutters[0].line, line) << fixture;
    }
    EXPECT_EQ(read.cutters[0].values, values) << fixture;
    return read;
  };
  const ClProgram cb = oneCutter("cambam_enclosure_head.nc", "T0", 7, {1.0, 0});
  EXPECT_TRUE(hasNote(cb, "T0 (line 7): the program's tool list gives its diameter only"));
  // Without a tool list, T0 still empties the spindle; a CamBam tool of no diameter (the
  // corpus's "( T0 : 0.0 )") gives no geometry.
  EXPECT_TRUE(parseGcode("G21\nT0 M6\nG0 X0 Y0 Z1\n", "t0.nc", m.model).cutters.empty());
  EXPECT_TRUE(readGcodeFile(test::sourcePath("tests/fixtures/gcode/cambam_contour1.nc"), m.model)
                  .cutters.empty());
  // Fabex: "T2M06" then "(Tool: D = 6.0 mm  type BALLNOSE flutes 2)" (the corpus program), or
  // the comment alone (its grbl post, as in blendercam's tests/test_data), in the comment's own
  // unit ('' is inches); a shape it does not give is named, with no geometry.
  oneCutter("fabex_Op_Plane_1.tap", "T2", 0, {6, 3});
  const ClProgram grbl = parseGcode(
      "G21\n(G-code Generated with Fabex and NC library)\nG17G90\n"
      "(Tool: D = 3.0 mm  type END flutes 2)\nS12000M03\nG00 Z2.0\nG0X0Y0Z2\nG1Z-1F500\n"
      "(Tool: D = 3.0 mm  type END flutes 2)\nG1X5\n(Tool: D = 0.125'' type BALLNOSE flutes 2)\n"
      "G1X6\n(Tool: D = 0.25'' type VCARVE flutes 2)\nG1X7\n",
      "fabex.gcode", m.model);
  ASSERT_EQ(grbl.cutters.size(), 3u);  // the repeated END is the same tool
  EXPECT_EQ(grbl.cutters[0].line, 4);
  EXPECT_EQ(grbl.cutters[0].values, (std::vector<double>{3, 0}));
  EXPECT_NEAR(grbl.cutters[1].values.at(0), 3.175, 1e-12);
  EXPECT_NEAR(grbl.cutters[1].values.at(1), 1.5875, 1e-12);
  EXPECT_EQ(grbl.cutters[2].kind, "Fabex VCARVE");
  EXPECT_TRUE(grbl.cutters[2].values.empty());
  EXPECT_TRUE(hasNote(grbl, "line 13: Fabex's tool comment names a VCARVE cutter"));
  // Fusion's personal-use post for a hobby machine: the tool list "(T1  D=2 CR=0 - ...)" and no
  // T word at all (shooshx/led_floor, cad/nc/6mm_1004.nc, whole): the only tool listed cuts.
  const ClProgram one = oneCutter("fusion_led-floor_6mm_1004.nc", "T1", 2, {2, 0});
  EXPECT_TRUE(hasNote(one, "T1 (listed in a comment at line 2) is the only tool"));
  // Malformed tool comments give no geometry, never a part of their digits: an exponent
  // ("1e999" read as 1 mm before), a negative or missing diameter, a Fabex size in no unit.
  for (const char* bad : {"(T1 D=1e999 CR=0)\nT1 M6\n", "( T0 : nan )\nT0 M6\n",
                          "(T1 D=-3 CR=0)\nT1 M6\n", "(Tool: D = -3 mm type END flutes 2)\n",
                          "(Tool: D = 3 type END flutes 2)\n", "(Tool: D = 1e9 mm type END)\n"}) {
    const ClProgram read =
        parseGcode(std::string("G21\n") + bad + "G0 X0 Y0 Z1\n", "bad.nc", m.model);
    for (const CutterSpec& c : read.cutters) EXPECT_TRUE(c.values.empty()) << bad;
  }
  // Two tools listed and none selected: which cuts is not known.
  EXPECT_TRUE(parseGcode("(T1 D=2 CR=0)\n(T2 D=4 CR=0)\nG21\nG0 X0 Y0 Z1\n", "two.nc", m.model)
                  .cutters.empty());
}

// Every shipped machine with a control: a program in tool-centre-point mode and its joint-space
// twin (the joints the TCP reading gives, posted as machine coordinates less the work offset,
// rotary words in the control's sense) give the same tool path to 1 nm: TCP and joint words,
// work offsets and the rotary senses agree in the reader (issue 32, point 4).
TEST(GcodeReader, TcpProgramAndItsJointTwinGiveTheSamePath) {
  struct Case {
    const char* file;
    const char* on;
    const char* off;
  };
  const Case cases[] = {{"resources/machines/umc_bc_trunnion.xml", "G234 H1", "G49"},
                        {"resources/machines/sinumerik_bc_table.xml", "TRAORI", "TRAFOOF"},
                        {"resources/machines/linuxcnc_xyzac_trt.xml", "M428", "M429"},
                        {"resources/machines/linuxcnc_xyzbc_trt.xml", "M428", "M429"}};
  std::mt19937 rng(32);
  std::uniform_real_distribution<double> xy(-20, 20), z(0, 30), tilt(-30, 30), turn(-170, 170);
  for (const Case& c : cases) {
    SCOPED_TRACE(c.file);
    Machine m = machine(c.file, 50.0);
    m.model.setup.work_offsets["G54"] = Eigen::Vector3d(-3, 4, -5);
    for (Axis& ax : m.model.axes)  // travel is not the subject here: every tip reachable
      if (!ax.isRotary()) ax.travel_min = -1e4, ax.travel_max = 1e4;
    std::vector<int> rotary;
    for (size_t a = 0; a < m.model.axes.size(); ++a)
      if (m.model.axes[a].isRotary()) rotary.push_back(static_cast<int>(a));
    ASSERT_EQ(rotary.size(), 2u);
    // The TCP program: tips and rotary words (the tilting axis first in the file's order).
    std::string tcp = "G21\nG90 G54\n" + std::string(c.on) + "\n";
    char buf[200];
    for (int k = 0; k < 20; ++k) {
      const double w0 = tilt(rng), w1 = turn(rng);
      std::snprintf(buf, sizeof buf, "G1 X%.4f Y%.4f Z%.4f %s%.4f %s%.4f F500\n", xy(rng), xy(rng),
                    z(rng), m.model.axes[rotary[0]].name.c_str(), w0,
                    m.model.axes[rotary[1]].name.c_str(), w1);
      tcp += buf;
    }
    tcp += std::string(c.off) + "\n";
    const ClProgram a = parseGcode(tcp, "tcp.nc", m.model);
    ASSERT_EQ(a.path.size(), 20u);
    // Its twin in joint words: machine coordinates (nc_sign x joint) less G54, rotary words.
    const std::array<int, 3> order = prismaticWordOrder(m.model);
    std::string twin = "G21\nG90 G54\n";
    for (size_t i = 0; i < a.path.size(); ++i) {
      const JointVector& q = a.joints[i];
      double w[3];
      for (int k = 0; k < 3; ++k)
        w[k] = m.model.axes[order[k]].nc_sign * q[order[k]] - m.model.setup.work_offsets["G54"][k];
      std::snprintf(buf, sizeof buf, "G1 X%.9f Y%.9f Z%.9f %s%.9f %s%.9f\n", w[0], w[1], w[2],
                    m.model.axes[rotary[0]].name.c_str(),
                    m.model.axes[rotary[0]].nc_sign * q[rotary[0]] / kDeg,
                    m.model.axes[rotary[1]].name.c_str(),
                    m.model.axes[rotary[1]].nc_sign * q[rotary[1]] / kDeg);
      twin += buf;
    }
    const ClProgram b = parseGcode(twin, "twin.nc", m.model);
    ASSERT_EQ(b.path.size(), a.path.size());
    for (size_t i = 0; i < a.path.size(); ++i) {
      EXPECT_EQ(a.tcp[i], ClProgram::kTcpWords);
      EXPECT_EQ(b.tcp[i], ClProgram::kJointWords);
      EXPECT_LT((a.path[i].p_w - b.path[i].p_w).norm(), 1e-6) << i;
      EXPECT_LT((a.path[i].u_w - b.path[i].u_w).norm(), 1e-9) << i;
    }
  }
}

// An exponent is not a G-code number (issue 37: Y1e5 was read as Y1 and E5 ignored): refused at
// its line, by predict and compensate alike.
TEST(GcodeReader, AnExponentIsRefusedNotReadAsItsMantissa) {
  const Machine v = machine("resources/machines/vmc_3axis_iso.xml", 0.0);
  const std::string e = refusal("G21\nG90\nG1 X0 Y0 Z0 F100\nG1 Y1e5\n", v.model);
  EXPECT_NE(e.find(":4:"), std::string::npos) << e;
  EXPECT_NE(e.find("no exponent"), std::string::npos) << e;
}

// F words: per minute in the program's unit under G94 (every control's default), unknown under
// inverse time (G93) and per revolution (G95); modal.
TEST(GcodeReader, FeedRatesFollowTheFeedMode) {
  const Machine m = machine("resources/machines/linuxcnc_xyzac_trt.xml", 0.0);
  const ClProgram p = parseGcode(
      "G21\nG0 X0 Y0 Z0 A0 C0\nG1 X1 F600\nX2\nG20 G1 X0.1 F10\nG93 G1 X0.2 F2\nG94 G21 G1 X3 "
      "F100\nG95 G1 X4 F0.1\n",
      "feeds.ngc", m.model);
  ASSERT_EQ(p.path.size(), 7u);
  EXPECT_TRUE(std::isnan(p.path[0].feed_mm_min));
  EXPECT_FLOAT_EQ(p.path[1].feed_mm_min, 600.0f);
  EXPECT_FLOAT_EQ(p.path[2].feed_mm_min, 600.0f);
  EXPECT_FLOAT_EQ(p.path[3].feed_mm_min, 254.0f);
  EXPECT_TRUE(std::isnan(p.path[4].feed_mm_min));
  EXPECT_FLOAT_EQ(p.path[5].feed_mm_min, 100.0f);
  EXPECT_TRUE(std::isnan(p.path[6].feed_mm_min));
}

// The operations the posts name in comments: FreeCAD's "(begin operation: Profile)", NX's
// Sinumerik ";Operation : CURVE_DRIVE", the Creo-style "( OPERATION=  ROUGH7  Z LEVEL ...)".
TEST(GcodeReader, NamesTheProgramsOperations) {
  const Machine vmc = machine("resources/machines/vmc_3axis_iso.xml");
  const ClProgram freecad = readGcodeFile(
      test::sourcePath("tests/fixtures/gcode/freecad_grbl_platteyz-helix.nc"), vmc.model);
  ASSERT_GE(freecad.operations.size(), 2u);
  EXPECT_EQ(freecad.operations[0].name, "Fixture");
  EXPECT_EQ(freecad.operations[1].name, "Profile");
  EXPECT_EQ(operationAt(freecad.operations, freecad.path.back().line),
            freecad.operations.back().name);
  const ClProgram nx =
      readGcodeFile(test::sourcePath("tests/fixtures/gcode/nx_sin840d_Keychain.mpf"),
                    machine("resources/machines/sinumerik_bc_table.xml").model);
  ASSERT_EQ(nx.operations.size(), 3u);
  EXPECT_EQ(nx.operations[0].name, "CURVE_DRIVE");
  EXPECT_EQ(nx.operations[2].name, "DRILLING");
  EXPECT_EQ(nx.operations[2].line, 617);
  const ClProgram boat =
      readGcodeFile(test::sourcePath("tests/fixtures/gcode/linuxcnc_boat-xyzbc.ngc"),
                    machine("resources/machines/linuxcnc_xyzbc_trt.xml").model);
  ASSERT_EQ(boat.operations.size(), 1u);
  EXPECT_EQ(boat.operations[0].name, "FINISH1 FLOWLINE SRF_MILL1");
}

}  // namespace
}  // namespace tolver
