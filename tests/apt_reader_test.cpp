#include "io/program/apt_reader.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>

#include "core/path/tool_motion.h"
#include "geometry/cutter.h"
#include "io/common/io_error.h"
#include "io/common/text_util.h"
#include "test_support.h"

namespace tolver {
namespace {

ClProgram fixture(const std::string& name) {
  return readAptFile(test::sourcePath("tests/fixtures/cl/" + name));
}

// Points that a GOTO/FROM statement itself gave (the last point of each motion statement).
std::vector<ClPoint> statementEndPoints(const ClProgram& p) {
  std::vector<ClPoint> out;
  for (const AptStatement& s : p.statements)
    if (s.point_count > 0) out.push_back(p.path[s.first_point + s.point_count - 1]);
  return out;
}

void expectNear(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double tol = 1e-9) {
  EXPECT_LT((a - b).norm(), tol) << a.transpose() << " vs " << b.transpose();
}

// Read with --absolute-msys: the points in NX's absolute frame through the MSYS.
TEST(AptReader, SiemensNxVariableContourWithMsysAndModalToolAxis) {
  AptReadOptions absolute;
  absolute.absolute_msys = true;
  const ClProgram p = readAptFile(test::sourcePath("tests/fixtures/cl/nx_ust_a.cls"), absolute);
  EXPECT_EQ(p.path.size(), 546u);  // 546 GOTO, no arcs
  EXPECT_TRUE(p.multiax);
  // MSYS: origin (-120.2591, -1196.5, 142.5), x axis = j, y axis = i, so z = -k.
  expectNear(p.path.front().p_w, Eigen::Vector3d(-120.2591 + 222.6719, -1196.5, 142.5 + 177.5));
  expectNear(p.path.front().u_w, Eigen::Vector3d(0, 0, 1));
  EXPECT_EQ(p.path.front().line, 11);
  EXPECT_TRUE(p.path.front().rapid);
  EXPECT_FALSE(p.path[3].rapid);
  // The tool axis is modal: line 12's GOTO has three values and keeps line 11's axis.
  expectNear(p.path[1].u_w, p.path[0].u_w);
  // Last: GOTO/784.0000,3.6875,-97.5000 with the axis of the last six-value GOTO.
  expectNear(p.path.back().p_w, Eigen::Vector3d(-120.2591 + 3.6875, -1196.5 + 784.0, 142.5 + 97.5));
  ASSERT_EQ(p.cutters.size(), 1u);
  Cutter c;
  ASSERT_TRUE(cutterFromApt(p.cutters[0].source, p.cutters[0].values, &c));
  EXPECT_EQ(c.type, CutterType::BullNose);
  EXPECT_DOUBLE_EQ(c.diameter, 32.0);
  EXPECT_DOUBLE_EQ(c.corner_radius, 5.0);
  EXPECT_EQ(p.unknown_count, 0);
}

TEST(AptReader, SiemensNxCircleRecordsAreExpandedWithinTheChordalTolerance) {
  AptReadOptions opt;
  opt.chordal_tolerance_mm = 0.001;
  opt.absolute_msys = true;  // the centre below is in NX's absolute frame
  const ClProgram p = readAptFile(test::sourcePath("tests/fixtures/cl/nx_cutcom.clsf"), opt);
  EXPECT_EQ(p.arcs_expanded, 140);
  EXPECT_EQ(statementEndPoints(p).size(), 566u);
  EXPECT_GT(p.path.size(), 566u);
  // Every point of the first arc (centre 5.3162, 23, 70 in MSYS, radius 12.5) lies on it.
  const AptStatement* arcEnd = nullptr;
  for (const auto& s : p.statements)
    if (s.first_line == 20) arcEnd = &s;
  ASSERT_NE(arcEnd, nullptr);
  ASSERT_GT(arcEnd->point_count, 10);
  const Eigen::Vector3d o(-255.9551, 15.9993, 77.0124);
  const Eigen::Vector3d x(0.9975352, -0.0701679, 0), y(-0.0701679, -0.9975352, 0);
  const Eigen::Vector3d centre = o + 5.3162 * x.normalized() + 23.0 * y.normalized() +
                                 70.0 * x.normalized().cross(y.normalized());
  for (int k = arcEnd->first_point; k < arcEnd->first_point + arcEnd->point_count; ++k) {
    const Eigen::Vector3d d = p.path[k].p_w - centre;
    EXPECT_NEAR(std::hypot(d.x(), d.y()), 12.5, 2e-4);
  }
  // Sagitta between consecutive points within the tolerance: chord <= 2 sqrt(2 r tol).
  for (int k = arcEnd->first_point; k < arcEnd->first_point + arcEnd->point_count; ++k)
    EXPECT_LE((p.path[k].p_w - p.path[k - 1].p_w).norm(), 2 * std::sqrt(2 * 12.5 * 0.001) + 1e-6);
}

TEST(AptReader, SolidWorksCamUnitCutterCsysAndFeedAfterValue) {
  const ClProgram p = fixture("swcam_Teste-Metrologia.apt");
  EXPECT_EQ(p.units, "MM");
  EXPECT_EQ(statementEndPoints(p).size(), 454u);
  EXPECT_EQ(p.arcs_expanded, 65);
  expectNear(p.path.front().p_w, Eigen::Vector3d(-8.856356, -17.5, 25.0));
  Cutter c;
  ASSERT_TRUE(cutterFromApt(p.cutters[0].source, p.cutters[0].values, &c));
  EXPECT_EQ(c.type, CutterType::FlatEnd);
  EXPECT_DOUBLE_EQ(c.diameter, 14.0);
  EXPECT_DOUBLE_EQ(c.length, 84.0);
  // Line 276 turns the tool plane (CSYS after TRNTYP/WORLD); the GOTOs that follow stay in
  // world coordinates: line 278 GOTO/250.,35.8375,-12.1625,1.,0,0 approaches the +x face.
  EXPECT_TRUE(p.multiax);
  EXPECT_EQ(p.tool_planes, 4);
  EXPECT_EQ(p.frames.size(), 2u);  // initial and UNIT: no CSYS applied
  bool seen = false;
  for (const ClPoint& pt : p.path) {
    if (pt.line != 278) continue;
    seen = true;
    expectNear(pt.p_w, Eigen::Vector3d(250, 35.8375, -12.1625));
    expectNear(pt.u_w, Eigen::Vector3d(1, 0, 0));
  }
  EXPECT_TRUE(seen);
  EXPECT_TRUE(p.path[1].u_w.isApprox(Eigen::Vector3d(0, 0, 1)));
}

TEST(AptReader, SolidWorksLongProgramAndThreePlusTwo) {
  const ClProgram glue = fixture("swcam_Interface-glue.apt");
  EXPECT_EQ(statementEndPoints(glue).size(), 6311u);
  EXPECT_EQ(glue.arcs_expanded, 50);
  EXPECT_EQ(glue.cutters.size(), 4u);
  const ClProgram rot = fixture("swcam_RotateThick.apt");
  EXPECT_EQ(statementEndPoints(rot).size(), 482u);
  EXPECT_EQ(rot.arcs_expanded, 108);
}

TEST(AptReader, CreoPseudoCommentsContinuationsAndSpacesAroundSlash) {
  const ClProgram p = fixture("creo_profile_milling.ncl");
  EXPECT_EQ(statementEndPoints(p).size(), 52u);
  EXPECT_EQ(p.arcs_expanded, 20);
  ASSERT_EQ(p.cutters.size(), 1u);  // from "$$-> CUTTER / 3.000000"
  EXPECT_DOUBLE_EQ(p.cutters[0].values[0], 3.0);
  EXPECT_EQ(p.frames.size(), 3u);  // initial, UNITS, $$-> CSYS
  expectNear(p.path.front().p_w, Eigen::Vector3d(0, 1.5, 2.0));
  expectNear(p.path.back().p_w, statementEndPoints(p).back().p_w);
  // CYCLE / DEEP, DEPTH 3.5, STEP 1, CLEAR 1 (continued with `$`) at two holes whose tops are
  // at z 0.5: each expanded into clearance, depth and retract along the tool axis.
  const ClProgram d = fixture("creo_drilling.ncl");
  EXPECT_EQ(d.cycles, 1);
  EXPECT_EQ(d.cycle_holes, 2);
  ASSERT_EQ(d.path.size(), 8u);
  expectNear(d.path[1].p_w, Eigen::Vector3d(-7.2290790757, -23.0, 1.5));
  EXPECT_TRUE(d.path[1].rapid);
  expectNear(d.path[2].p_w, Eigen::Vector3d(-7.2290790757, -23.0, -3.0));
  EXPECT_FALSE(d.path[2].rapid);
  expectNear(d.path[3].p_w, Eigen::Vector3d(-7.2290790757, -23.0, 1.5));
  expectNear(d.path[5].p_w, Eigen::Vector3d(-16.7803891180, -23.0, -3.0));
  expectNear(d.path.back().p_w, Eigen::Vector3d(-16.7803891180, -23.0, 2.0));
}

// Pro/CLFILE 9.0 writes its pseudo-comments as `REMARK -> CUTTER / 6.000000` (version 8: `$$->`),
// and APT's REMARK is a comment: the head and end of a real five-axis finish
// (4r19415/5-axis-Rotation-tool-center-point-RTCP-, assets/finition.ncl: lines 1-101 and the last
// three). The cutter came from nowhere before (every REMARK an unknown statement, the cutter
// missing); its GPOST vocabulary table (PPWORD) declares words and moves nothing.
TEST(AptReader, Creo9RemarkPseudoCommentsAndComments) {
  AptReadOptions mm;
  mm.unit_mm = 1.0;
  mm.unit_given = true;  // the file says INCHES and holds mm (its extent: 332 mm)
  const ClProgram p =
      readAptFile(test::sourcePath("tests/fixtures/cl/creo9_finition_head.ncl"), mm);
  ASSERT_EQ(p.cutters.size(), 1u);
  EXPECT_EQ(p.cutters[0].line, 73);
  EXPECT_DOUBLE_EQ(p.cutters[0].values[0], 6.0);
  EXPECT_EQ(p.unknown_names, (std::vector<std::string>{"CAMERA"}));
  ASSERT_FALSE(p.operations.empty());
  EXPECT_EQ(p.operations[0].name, "feature 1014");  // REMARK -> FEATNO / 1014
  ASSERT_EQ(p.path.size(), 9u);                     // the GOTOs of lines 82-101
  EXPECT_TRUE(p.multiax);
  expectNear(p.path.front().p_w, Eigen::Vector3d(245.1295775618, -22.7813938898, 43.5028538928));
  expectNear(p.path.front().u_w, Eigen::Vector3d(0.9997838891, -0.0000009626, 0.0207888211));
  // A plain REMARK is one line whatever it holds; `REMARK/` too; REMARKS is another word.
  const std::string text =
      "UNITS / MM\nREMARK MACHID=MACHIN / UNCX01, 1\nREMARK/ $\nREMARKS / 1\n"
      "GOTO / 1, 2, 3\nFINI\n";
  const ClProgram q = parseApt(text, "remarks.apt");
  EXPECT_EQ(q.unknown_names, (std::vector<std::string>{"REMARKS"}));
  ASSERT_EQ(q.path.size(), 1u);
  EXPECT_EQ(q.path[0].line, 5);
}

// NX's TLDATA/DRILL,MILL,d,r,length,point angle,flute length (HumMan/CLSFProcessor,
// samples/_5_SVERL_63_N2_116.cls, whole: a 63 mm insert drill, 178 deg): the flat end of its
// diameter and length, and a note with the height its point leaves, 31.5 / tan(89 deg). The
// point angle was read as TLDATA/MILL's taper (178 deg) and the tool described no cutter.
TEST(AptReader, NxDrillIsItsFlatEndWithThePointSaid) {
  const ClProgram p = fixture("nx_5_SVERL_63_N2_116.cls");
  ASSERT_EQ(p.cutters.size(), 1u);
  EXPECT_EQ(p.cutters[0].kind, "DRILL");
  EXPECT_EQ(p.cutters[0].values, (std::vector<double>{63, 0, 239}));
  const std::string height = formatWith("%.3g", 31.5 / std::tan(89.0 * M_PI / 180.0));
  EXPECT_EQ(height, "0.55");
  bool said = false;
  for (const std::string& n : p.notes)
    said = said || (n.find("TLDATA/DRILL at line 2") != std::string::npos &&
                    n.find("(178 deg)") != std::string::npos &&
                    n.find(height + " mm") != std::string::npos);
  EXPECT_TRUE(said);
}

// NX writes the GOTOs in the MCS the MSYS names; the first MSYS is the part frame. A three-axis
// operation in an MCS whose z points down in the CAD's absolute frame (x = j, y = i) keeps its
// vertical tool axis and its numbers (issue 32: read through the MSYS it needed A = 180 deg).
TEST(AptReader, NxPointsStayInTheMainMcs) {
  const ClProgram p = fixture("nx_10_KONTUR_125_N2_162.cls");
  // FROM/650,-393,964 is the start, not a point; the first is line 10's GOTO.
  expectNear(p.path.front().p_w, Eigen::Vector3d(1232.5388, -353.2220, 961));
  expectNear(p.path.front().u_w, Eigen::Vector3d(0, 0, 1));
  for (const ClPoint& c : p.path) expectNear(c.u_w, Eigen::Vector3d(0, 0, 1));
  // CIRCLE ... TIMES,2 at line 16: a helix of two full turns and the arc to its end point,
  // from z 416 down to 413, every point on the circle of radius 56.25 about (1287.5, -341.25).
  int helix = 0;
  double turned = 0.0;
  Eigen::Vector2d prev(1232.5388 - 1287.5, -353.2220 + 341.25);
  for (const ClPoint& h : p.path) {
    if (h.line != 17) continue;
    ++helix;
    const Eigen::Vector2d d(h.p_w.x() - 1287.5, h.p_w.y() + 341.25);
    EXPECT_NEAR(d.norm(), 56.25, 2e-3);
    EXPECT_GE(h.p_w.z(), 413.0 - 1e-9);
    EXPECT_LE(h.p_w.z(), 416.0 + 1e-9);
    turned += std::atan2(prev.x() * d.y() - prev.y() * d.x(), prev.dot(d));
    prev = d;
  }
  EXPECT_GT(helix, 100);
  // Clockwise seen from +z (axis -k): two turns and the 282 deg from start to end.
  EXPECT_NEAR(
      turned,
      -(2 * 2 * M_PI + std::atan2(-11.972, -54.9612) - std::atan2(-56.25, -0.0108) + 2 * M_PI),
      0.02);
  // --absolute-msys: the same points through the MSYS (origin 393, -297.5, 3; z down).
  AptReadOptions absolute;
  absolute.absolute_msys = true;
  const ClProgram a =
      readAptFile(test::sourcePath("tests/fixtures/cl/nx_10_KONTUR_125_N2_162.cls"), absolute);
  expectNear(a.path.front().p_w, Eigen::Vector3d(393 - 353.2220, -297.5 + 1232.5388, 3 - 961));
  expectNear(a.path.front().u_w, Eigen::Vector3d(0, 0, -1));
}

// A second MSYS is a 3+2 set-up relative to the first: its points are moved by the first's
// inverse times its own; the first's points stay as written.
TEST(AptReader, LaterMsysIsRelativeToTheMainMcs) {
  const ClProgram p = parseApt(
      "MSYS/100,0,0,1,0,0,0,1,0\n"
      "GOTO/1,2,3,0,0,1\n"
      "MSYS/100,0,50,1,0,0,0,0,1\n"  // x along x, y along z: the MCS turned -90 deg about x
      "GOTO/1,2,3,0,0,1\n",
      "two_msys.cls");
  ASSERT_EQ(p.path.size(), 2u);
  expectNear(p.path[0].p_w, Eigen::Vector3d(1, 2, 3));
  expectNear(p.path[0].u_w, Eigen::Vector3d(0, 0, 1));
  // main^-1 * second: origin (0, 0, 50), x = i, y = k, z = x cross y = -j.
  expectNear(p.path[1].p_w, Eigen::Vector3d(1, -3, 52));
  expectNear(p.path[1].u_w, Eigen::Vector3d(0, -1, 0));
}

// CL drilling cycles are expanded at each GOTO until CYCLE/OFF, along the tool axis: the
// SolidWorks CAM part's 16 holes (FEDTO 10, RAPTO 3, RTRCTO 25) and NX's DEEP cycle.
TEST(AptReader, DrillingCyclesAreExpandedNeverSkipped) {
  const ClProgram p = fixture("swcam_basemach.apt");
  EXPECT_EQ(p.cycles, 1);
  EXPECT_EQ(p.cycle_holes, 16);
  // The first hole: GOTO/29.06066,116.93934,0 with the tool along +z.
  int k = 0;
  while (p.path[k].line != 18) ++k;
  expectNear(p.path[k].p_w, Eigen::Vector3d(29.06066, 116.93934, 25.0));
  expectNear(p.path[k + 1].p_w, Eigen::Vector3d(29.06066, 116.93934, 3.0));
  expectNear(p.path[k + 2].p_w, Eigen::Vector3d(29.06066, 116.93934, -10.0));
  EXPECT_FALSE(p.path[k + 2].rapid);
  expectNear(p.path[k + 3].p_w, Eigen::Vector3d(29.06066, 116.93934, 25.0));
  EXPECT_TRUE(p.path[k + 3].rapid);
  const ClProgram nx = fixture("nx_deep_drill.clsf");
  EXPECT_EQ(nx.cycle_holes, 2);
  // An unknown cycle is an error naming it.
  try {
    parseApt("GOTO/0,0,10\nCYCLE/SHAPE,FEDTO,5\nGOTO/0,0,0\n", "c.apt");
    ADD_FAILURE() << "accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("SHAPE"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("c.apt:2"), std::string::npos) << e.what();
  }
}

// SolidWorks CAM writes a bare CYCLE/CLEAR before a cycle's definition (aamorim1913/
// AptPostProcessor, parts-2022/SupPetriLED.apt, line 16); it was refused as an unknown cycle.
// It clears the cycle state: the DEEP cycle after it drills its six holes, and a cycle in force
// when it comes ends there, with a note (read as nothing, the next GOTO would be a hole).
TEST(AptReader, CycleClearEndsTheCycleInForce) {
  const ClProgram p = fixture("swcam_SupPetriLED.apt");
  EXPECT_EQ(p.cycle_holes, 12);
  int k = 0;
  while (p.path[k].line != 18) ++k;
  // GOTO/59.5,99.5,-24 with DEEP FEDTO 3.301, RAPTO 29, RTRCTO 49: retract, clearance, depth.
  expectNear(p.path[k].p_w, Eigen::Vector3d(59.5, 99.5, 25.0));
  expectNear(p.path[k + 1].p_w, Eigen::Vector3d(59.5, 99.5, 5.0));
  expectNear(p.path[k + 2].p_w, Eigen::Vector3d(59.5, 99.5, -27.301));
  const ClProgram q =
      parseApt("GOTO/0,0,10\nCYCLE/DRILL,FEDTO,5,RAPTO,2\nGOTO/0,0,0\nCYCLE/CLEAR\nGOTO/5,0,0\n",
               "clear.apt");
  EXPECT_EQ(q.cycle_holes, 1);
  ASSERT_FALSE(q.path.empty());
  EXPECT_EQ(q.path.back().line, 5);
  expectNear(q.path.back().p_w, Eigen::Vector3d(5, 0, 0));
  bool said = false;
  for (const auto& n : q.notes) said |= n.find("CYCLE/CLEAR at line 4 ended the DRILL cycle") == 0;
  EXPECT_TRUE(said);
}

TEST(AptReader, ShortNxPathWithTldataAndEndOfPath) {
  const ClProgram p = fixture("nx_TORETC_250_BOK.cls");
  EXPECT_EQ(p.path.size(), 10u);
  Cutter c;
  ASSERT_TRUE(cutterFromApt(p.cutters[0].source, p.cutters[0].values, &c));
  EXPECT_DOUBLE_EQ(c.diameter, 250.0);
}

TEST(AptReader, NurbsBlocksAreRefusedWithTheirLine) {
  try {
    fixture("nx_nurbs.clsf");
    FAIL() << "NURBS accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.line(), 13);
    EXPECT_NE(std::string(e.what()).find("NURBS"), std::string::npos);
  }
}

TEST(AptReader, InchesAreConvertedToMillimetres) {
  const ClProgram p = parseApt("UNITS/INCHES\nGOTO/1,2,3\nCUTTER/0.5\n", "inch.apt");
  expectNear(p.path[0].p_w, Eigen::Vector3d(25.4, 50.8, 76.2));
  EXPECT_DOUBLE_EQ(p.cutters[0].values[0], 12.7);
  EXPECT_EQ(p.units, "INCH");
}

TEST(AptReader, CatiaMatrixAppliesToTheFollowingPoints) {
  const std::string text =
      "$$*CATIA0\n$$*Manufacturing Program.1\n"
      "$$*   0.00000   -1.00000   0.00000   10.00000\n"
      "$$*   1.00000    0.00000   0.00000   20.00000\n"
      "$$*   0.00000    0.00000   1.00000   30.00000\n"
      "MULTAX\nGOTO/1,0,0,1,0,0\n";
  const ClProgram p = parseApt(text, "catia.aptsource");
  expectNear(p.path[0].p_w, Eigen::Vector3d(10, 21, 30));
  expectNear(p.path[0].u_w, Eigen::Vector3d(0, 1, 0));
}

TEST(AptReader, CsysWithoutTrntypWorldIsApplied) {
  const ClProgram p = parseApt("CSYS/0,-1,0,5,1,0,0,0,0,0,1,0\nGOTO/1,0,0\n", "c.apt");
  expectNear(p.path[0].p_w, Eigen::Vector3d(5, 1, 0));
}

TEST(AptReader, CaseSpacingGodltaFromAndTlaxis) {
  const ClProgram p = parseApt(
      "  from / 0 , 0 , 10\ntlaxis/0,0,2\ngoto/1,2,3\nGODLTA/1,1,1\nGodlta/-4\n", "mixed.apt");
  ASSERT_EQ(p.path.size(), 3u);  // FROM names the start: not a point of the path
  expectNear(p.path[1].p_w, Eigen::Vector3d(2, 3, 4));
  expectNear(p.path[2].p_w, Eigen::Vector3d(2, 3, 0));
  expectNear(p.path[2].u_w, Eigen::Vector3d(0, 0, 1));
}

TEST(AptReader, UnknownStatementsAreCountedNotFatal) {
  const ClProgram p = parseApt("FOO/1,2\nGOTO/1,2,3\nBAR\nFOO/3\n", "u.apt");
  EXPECT_EQ(p.path.size(), 1u);
  EXPECT_EQ(p.unknown_count, 3);
  EXPECT_EQ(p.unknown_names, (std::vector<std::string>{"FOO", "BAR"}));
}

// Statements that change which points the CL holds or where they are (APT's COPY, TRACUT,
// REFSYS, incremental MODE) are refused by name: skipped as unknown, the copies were missing and
// the points untransformed. Post-processor words that do not (ORIGIN, ROTABL, MODE/ABSOL,
// TRACUT/NOMORE) stay counted as unknown.
TEST(AptReader, StatementsThatMoveThePointsAreRefusedByName) {
  const std::string head = "UNITS/MM\nGOTO/0,0,10\n";
  for (const char* st : {"COPY/1,SAME,5", "TRACUT/1,0,0,5,0,1,0,0,0,0,1,0",
                         "REFSYS/1,0,0,0,0,1,0,0,0,0,1,0", "MODE/INCR", "SET/MODE,INCR"}) {
    try {
      parseApt(head + st + "\nGOTO/1,0,10\n", "m.apt");
      ADD_FAILURE() << st;
    } catch (const InputError& e) {
      EXPECT_EQ(e.line(), 3) << st;
      EXPECT_NE(std::string(e.what()).find(std::string(st).substr(0, std::string(st).find('/'))),
                std::string::npos)
          << e.what();
    }
  }
  for (const char* st : {"ORIGIN/1,2,3", "ROTABL/30,AAXIS", "MODE/ABSOL", "TRACUT/NOMORE"}) {
    const ClProgram p = parseApt(head + st + "\nGOTO/1,0,10\n", "ok.apt");
    EXPECT_EQ(p.path.size(), 2u) << st;
    EXPECT_EQ(p.unknown_count, 1) << st;
  }
}

struct BadCase {
  const char* text;
  int line;
  int column;
  const char* needle;
};

TEST(AptReader, BadInputNamesFileLineAndColumn) {
  const BadCase cases[] = {
      {"GOTO/1.0,2.0,\n", 1, 14, "missing value"},                   // truncated line
      {"GOTO/1,2,3\nGOTO/1.0,2.x5,3\n", 2, 10, "malformed number"},  // letters in a number
      {"", 0, 0, "empty file"},
      {"  \n\n", 0, 0, "empty file"},
      {"UNITS/FURLONG\nGOTO/1,2,3\n", 1, 7, "unknown unit"},
      {"GOTO/1,2,3,0,0\n", 1, 0, "3 values"},
      {"GOTO/1,2,3,0,0,0\n", 1, 12, "zero-length"},
      {"GOTO/1,2, $\n", 1, 0, "past the end"},
      {"GOTO/1,2,3\nCIRCLE/0,0,0,0,0,1,1\nGOTO/5,0,0\n", 2, 0, "not on one circle"},
      // An arc whose start is FROM (no point before it): the message names FROM's line (a
      // fuzzer found the message read the missing point).
      {"FROM/1,0,0\nCIRCLE/0,0,0,0,0,1,1\nGOTO/5,0,0\n", 2, 0, "(lines 1 and 3)"},
      // A circle of 9e8 mm: refused before any point is expanded.
      {"GOTO/900000000,0,0\nCIRCLE/0,0,0,0,0,1,900000000\nGOTO/0,900000000,0\n", 2, 0,
       "more than a million"},
      {"CSYS/1,0,0,0,0,2,0,0,0,0,1,0\n", 1, 0, "orthonormal"},
      {"UNITS/INCHES\nGOTO/1e300,0,0\n", 2, 6, "out of range"},
      {"GOTO/1,2,3\nNURBS/\nKNOT/0,1\n", 2, 0, "NURBS"},
  };
  for (const BadCase& c : cases) {
    try {
      parseApt(c.text, "bad.apt");
      ADD_FAILURE() << "accepted: " << c.text;
    } catch (const InputError& e) {
      EXPECT_EQ(e.file(), "bad.apt");
      EXPECT_EQ(e.line(), c.line) << e.what();
      if (c.column) {
        EXPECT_EQ(e.column(), c.column) << e.what();
      }
      EXPECT_NE(std::string(e.what()).find(c.needle), std::string::npos) << e.what();
    }
  }
}

// Hostile input: random byte edits of real files either parse to finite points or throw an
// InputError; never a crash, a hang or a NaN.
TEST(AptReader, MutatedFilesFailCleanly) {
  std::mt19937 rng(2024);
  const char* alphabet = "GOTO/,.$-+e0123456789 \n\tCIRCLE";
  for (const char* name : {"nx_ust_a.cls", "creo_profile_milling.ncl", "swcam_RotateThick.apt"}) {
    const std::string original =
        readFile(test::sourcePath(std::string("tests/fixtures/cl/") + name));
    int failed = 0;
    for (int n = 0; n < 300; ++n) {
      std::string text = original;
      std::uniform_int_distribution<int> edits(1, 8);
      for (int e = edits(rng); e > 0; --e) {
        std::uniform_int_distribution<size_t> at(0, text.size() - 1);
        const size_t i = at(rng);
        switch (rng() % 4) {
          case 0:
            text.erase(i, 1 + rng() % 5);
            break;
          case 1:
            text.insert(i, 1, alphabet[rng() % std::strlen(alphabet)]);
            break;
          case 2:
            text[i] = static_cast<char>(rng() % 256);
            break;
          default:
            text.resize(i);
            break;
        }
        if (text.empty()) text = "X";
      }
      try {
        const ClProgram p = parseApt(text, name);
        for (const ClPoint& c : p.path) {
          ASSERT_TRUE(c.p_w.allFinite());
          ASSERT_TRUE(c.u_w.allFinite());
        }
      } catch (const InputError& e) {
        ++failed;
        EXPECT_EQ(e.file(), name);
      }
    }
    EXPECT_GT(failed, 0);
  }
}

}  // namespace
}  // namespace tolver

namespace tolver {
namespace {

// A UTF-8 byte-order mark before a leading UNITS/INCHES: the units hold.
TEST(AptReader, ByteOrderMarkBeforeTheFirstStatementIsSkipped) {
  const ClProgram p =
      parseApt("\xEF\xBB\xBFUNITS/INCHES\nMULTAX\nGOTO/0.5,0.5,0.2,0,0,1\n", "bom.apt", {});
  ASSERT_EQ(p.path.size(), 1u);
  EXPECT_EQ(p.units, "INCH");
  EXPECT_NEAR(p.path[0].p_w.x(), 0.5 * 25.4, 1e-12);
}

// A 3 kB malformed number: the message quotes 60 characters of it.
TEST(AptReader, MessagesQuoteAtMostSixtyCharactersOfABadToken) {
  const std::string token(3000, '9');
  try {
    parseApt("GOTO/1,2,3,0,0,1\nGOTO/" + token + "x,2,3,0,0,1\n", "long.apt", {});
    FAIL() << "accepted";
  } catch (const InputError& e) {
    const std::string m = e.what();
    EXPECT_LT(m.size(), 200u) << m.size();
    EXPECT_NE(m.find("long.apt:2"), std::string::npos) << m;
    EXPECT_NE(m.find(std::string(60, '9') + "..."), std::string::npos) << m;
  }
  // An apostrophe inside a word opens no quotation: the sentence after it is kept whole.
  const std::string sentence =
      "the program's cut fits the part with the zero of C half a turn away, "
      "so set the zero of C in the machine file to the control's convention";
  const InputError e("m.xml", 0, 0, "convention", sentence + ": '" + token + "'");
  const std::string m = e.what();
  EXPECT_NE(m.find(sentence), std::string::npos) << m;
  EXPECT_NE(m.find(std::string(60, '9') + "..."), std::string::npos) << m;
  EXPECT_LT(m.size(), 400u);
}

}  // namespace
}  // namespace tolver

namespace tolver {
namespace {

// Every GOTO written "GOTO /" instead of "GOTO/": the reader's plain-GOTO path is not taken.
std::string generalGotos(const std::string& text) {
  std::string out;
  for (const std::string& l : splitLines(text))
    out += (l.rfind("GOTO/", 0) == 0 ? "GOTO /" + l.substr(5) : l) + "\n";
  return out;
}

// A one-line GOTO of plain numbers is read by a shorter path than other statements; it makes
// the same program, bit for bit, as the general path does (real programs from NX, Creo,
// SolidWorks CAM, with cycles, frames, arcs and modal tool axes), and leaves every refusal to the
// general path, with its message.
TEST(AptReader, PlainGotoLinesReadAsTheGeneralPathReadsThem) {
  for (const char* f :
       {"samples/sculptured_finish.apt", "tests/fixtures/cl/creo_drilling.ncl",
        "tests/fixtures/cl/nx_cutcom.clsf", "tests/fixtures/cl/swcam_RotateThick.apt",
        "tests/fixtures/cl/nx_ust_a.cls"}) {
    const std::string text = readFile(test::sourcePath(f));
    const ClProgram plain = parseApt(text, f), general = parseApt(generalGotos(text), f);
    ASSERT_EQ(plain.path.size(), general.path.size()) << f;
    ASSERT_GT(plain.path.size(), 5u) << f;
    for (size_t i = 0; i < plain.path.size(); ++i) {
      ASSERT_EQ(std::memcmp(plain.path[i].p_w.data(), general.path[i].p_w.data(), 24), 0) << f;
      ASSERT_EQ(std::memcmp(plain.path[i].u_w.data(), general.path[i].u_w.data(), 24), 0) << f;
      ASSERT_EQ(plain.path[i].line, general.path[i].line) << f;
      ASSERT_EQ(plain.path[i].rapid, general.path[i].rapid) << f;
      ASSERT_EQ(plain.point_frame[i], general.point_frame[i]) << f;
    }
    ASSERT_EQ(plain.statements.size(), general.statements.size()) << f;
    for (size_t k = 0; k < plain.statements.size(); ++k) {
      EXPECT_EQ(plain.statements[k].major, general.statements[k].major) << f;
      EXPECT_EQ(plain.statements[k].first_point, general.statements[k].first_point) << f;
      EXPECT_EQ(plain.statements[k].point_count, general.statements[k].point_count) << f;
    }
    EXPECT_EQ(plain.multiax, general.multiax) << f;
    EXPECT_EQ(plain.notes, general.notes) << f;
  }
  // Refusals come from the general path, the same message either way.
  for (const char* bad : {"GOTO/1,2,3,0,0,0\n", "GOTO/1,2\n", "GOTO/1,2,3e12\n", "GOTO/1,,3\n",
                          "GOTO/1,2,x\n", "GOTO/1,2,3,0,0,1,5\n"}) {
    std::string a, b;
    try {
      parseApt(std::string("MULTAX/ON\n") + bad, "bad.apt");
    } catch (const InputError& e) {
      a = e.what();
    }
    try {
      parseApt(generalGotos(std::string("MULTAX/ON\n") + bad), "bad.apt");
    } catch (const InputError& e) {
      b = e.what();
    }
    // (the general spelling has one more character before the values: columns one further)
    // (a message without a column is the same either way)
    auto split = [](const std::string& m, int* column) {
      const size_t c1 = m.find(':', m.find(':') + 1), c2 = m.find(':', c1 + 1);
      const std::string field = m.substr(c1 + 1, c2 - c1 - 1);
      if (field.empty() || field.find_first_not_of("0123456789") != std::string::npos) return m;
      *column = std::stoi(field);
      return m.substr(0, c1) + m.substr(c2);
    };
    ASSERT_FALSE(a.empty()) << bad;
    ASSERT_FALSE(b.empty()) << bad;
    int ca = -1, cb = -1;
    EXPECT_EQ(split(a, &ca), split(b, &cb)) << bad;
    EXPECT_EQ(cb, ca < 0 ? -1 : ca + 1) << a << " / " << b;
  }
}

// Feed rates as CAM posts write them (the program's clock for measure's thermal drift): the unit
// before or after the value, per minute in the file's unit without one, inches per minute, per
// revolution through SPINDL's speed; inverse time and per revolution without a speed unknown.
TEST(AptReader, FeedRatesAreKeptInMillimetresPerMinute) {
  const ClProgram p = parseApt(
      "GOTO/0,0,0\n"
      "FEDRAT/MMPM,500\nGOTO/1,0,0\n"
      "FEDRAT/250,MMPM\nGOTO/2,0,0\n"
      "FEDRAT/10,IPM\nGOTO/3,0,0\n"
      "FEDRAT/0.1,MMPR\nGOTO/4,0,0\n"  // no speed yet: unknown
      "SPINDL/RPM,3000,CLW\nFEDRAT/0.1,MMPR\nGOTO/5,0,0\n"
      "FEDRAT/INVERS,2\nGOTO/6,0,0\n"
      "UNITS/INCHES\nFEDRAT/20\nGOTO/7,0,0\n",
      "feeds.cls");
  ASSERT_EQ(p.path.size(), 8u);
  EXPECT_TRUE(std::isnan(p.path[0].feed_mm_min));
  EXPECT_FLOAT_EQ(p.path[1].feed_mm_min, 500.0f);
  EXPECT_FLOAT_EQ(p.path[2].feed_mm_min, 250.0f);
  EXPECT_FLOAT_EQ(p.path[3].feed_mm_min, 254.0f);
  EXPECT_TRUE(std::isnan(p.path[4].feed_mm_min));
  EXPECT_FLOAT_EQ(p.path[5].feed_mm_min, 300.0f);
  EXPECT_TRUE(std::isnan(p.path[6].feed_mm_min));
  EXPECT_FLOAT_EQ(p.path[7].feed_mm_min, 508.0f);
  // The clock: 1 mm at 500, 250, 254 mm/min, then a move without a feed: no clock at all.
  EXPECT_TRUE(programTimes(p.path).empty());
  std::vector<ClPoint> head(p.path.begin(), p.path.begin() + 4);
  const std::vector<double> t = programTimes(head);
  ASSERT_EQ(t.size(), 4u);
  EXPECT_NEAR(t[3], 1.0 / 500 + 1.0 / 250 + 1.0 / 254, 1e-9);
  head[2].rapid = true;  // a rapid at the stated rate
  EXPECT_NEAR(programTimes(head, 1000.0)[3], 1.0 / 500 + 1.0 / 1000 + 1.0 / 254, 1e-9);
}

// The operations the CAM systems name: NX's TOOL PATH/name, Creo's FEATNO, CATIA's PPRINT and
// `$$` comments; "end of operation" lines name none.
TEST(AptReader, NamesTheProgramsOperations) {
  const ClProgram nx = readAptFile(test::sourcePath("tests/fixtures/cl/nx_TORETC_250_BOK.cls"));
  ASSERT_FALSE(nx.operations.empty());
  EXPECT_EQ(nx.operations[0].name, "2_TORETC_250_BOK");
  EXPECT_EQ(operationAt(nx.operations, nx.path.back().line), nx.operations.back().name);
  const ClProgram creo = readAptFile(test::sourcePath("tests/fixtures/cl/creo_schruppen_1.ncl"));
  ASSERT_EQ(creo.operations.size(), 1u);
  EXPECT_EQ(creo.operations[0].name, "feature 605");
  const ClProgram text = parseApt(
      "UNITS/MM\nGOTO/0,0,0\nPPRINT/OPERATION NAME : Sweeping.1\nGOTO/1,0,0\n"
      "$$ end of operation: Sweeping.1\n$$ Operation: Pocket 2\nGOTO/2,0,0\nFINI\n",
      "ops.apt");
  ASSERT_EQ(text.operations.size(), 2u);
  EXPECT_EQ(text.operations[0].name, "Sweeping.1");
  EXPECT_EQ(text.operations[1].name, "Pocket 2");
  EXPECT_EQ(operationAt(text.operations, 2), "");
  EXPECT_EQ(operationAt(text.operations, 4), "Sweeping.1");
  EXPECT_EQ(operationAt(text.operations, 7), "Pocket 2");
}

}  // namespace
}  // namespace tolver
