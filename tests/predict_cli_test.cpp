// End-to-end tests of `tolver predict`: outputs, figures, exit codes and messages.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "io/program/apt_reader.h"
#include "test_support.h"

namespace tolver {
namespace {

namespace fs = std::filesystem;

class PredictCli : public test::TempDirTest {
 protected:
  static std::string src(const std::string& rel) { return test::sourcePath(rel); }
};

const char* kThreeAxisMachine = R"(<machine name="three axis" angle_unit="deg">
  <axis name="X" type="prismatic" branch="workpiece" direction="1 0 0" min="-200" max="200" nc_sign="-1"/>
  <axis name="Y" type="prismatic" branch="workpiece" order="-1" direction="0 1 0" min="-200" max="200" nc_sign="-1"/>
  <axis name="Z" type="prismatic" branch="tool" direction="0 0 1" min="-200" max="200"/>
  <axis name="A" type="rotary" branch="workpiece" direction="1 0 0" min="-90" max="90" nc_sign="-1"/>
  <axis name="C" type="rotary" branch="workpiece" direction="0 0 1" min="-180" max="180" nc_sign="-1"/>
  <errors length_unit="um" angle_unit="urad">%ERRORS%</errors></machine>)";

std::string machineWith(const std::string& errors) {
  std::string s = kThreeAxisMachine;
  s.replace(s.find("%ERRORS%"), 8, errors);
  return s;
}

TEST_F(PredictCli, SampleRunWritesBothOutputsAndASummary) {
  const auto r = test::runTolver(
      "predict --machine " + src("samples/machines/matsuura_mc760vx_measured.xml") + " --cl " +
      src("samples/nas979_cone.apt") + " --setup " + src("samples/matsuura_setup.txt") + " -o " +
      path("cone.apt") + " --errors " + path("cone.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("deviation  max"), std::string::npos);
  EXPECT_NE(r.output.find("gauge length 100.0000 mm"), std::string::npos);  // set-up printed
  const ClProgram back = readAptFile(path("cone.apt"));
  const ClProgram nominal = readAptFile(src("samples/nas979_cone.apt"));
  ASSERT_EQ(back.path.size(), nominal.path.size());
  // The per-point table agrees with the two CL files: dev = predicted - nominal.
  std::ifstream csv(path("cone.csv"));
  std::string header, row;
  std::getline(csv, header);
  EXPECT_EQ(header.rfind("index,line,rapid,nominal_x_mm", 0), 0u);
  EXPECT_NE(header.find("x_mm,y_mm,z_mm,a_deg,c_deg"), std::string::npos);
  size_t rows = 0;
  double max_dev = 0;
  while (std::getline(csv, row)) {
    std::vector<double> v;
    std::stringstream ss(row);
    std::string cell;
    while (std::getline(ss, cell, ',')) v.push_back(std::stod(cell));
    ASSERT_EQ(v.size(), 3 + 6 + 5 + 6 + 7 + 1u);
    const size_t i = static_cast<size_t>(v[0]);
    const Eigen::Vector3d dev = back.path[i].p_w - nominal.path[i].p_w;
    EXPECT_NEAR(v[20], dev.x() * 1e3, 2e-3);
    EXPECT_NEAR(v[21], dev.y() * 1e3, 2e-3);
    EXPECT_NEAR(v[22], dev.z() * 1e3, 2e-3);
    max_dev = std::max(max_dev, v[23]);
    ++rows;
  }
  EXPECT_EQ(rows, nominal.path.size());
  EXPECT_GT(max_dev, 1.0);  // the sample machine has errors of several micrometres
  EXPECT_LT(max_dev, 100.0);
}

TEST_F(PredictCli, ZeroErrorMachineReproducesTheProgram) {
  const auto r =
      test::runTolver("predict --machine " + src("resources/machines/trunnion_ac_trt.xml") +
                      " --cl " + src("samples/nas979_cone.apt") + " -o " + path("p.apt"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const ClProgram back = readAptFile(path("p.apt"));
  const ClProgram nominal = readAptFile(src("samples/nas979_cone.apt"));
  for (size_t i = 0; i < back.path.size(); ++i) {
    EXPECT_LT((back.path[i].p_w - nominal.path[i].p_w).norm(), 2e-6);
    EXPECT_LT((back.path[i].u_w - nominal.path[i].u_w).norm(), 2e-9);
  }
  EXPECT_TRUE(fs::exists(path("p.csv")));  // default table path
}

// Through the whole chain, signs included: a squareness gamma_z,X = 100 urad and the tool at
// y = 100 mm in the part give the tool tip dx = +y sin(gamma) = +10 um (see the FK test).
TEST_F(PredictCli, SquarenessShiftsThePredictedPointAnalytically) {
  const std::string m = write("m.xml", machineWith("<link axis='X' component='gz' value='100'/>"));
  const std::string cl = write("p.apt", "GOTO/0,100,0,0,0,1\nGOTO/50,100,0\nGOTO/0,-50,0\n");
  const auto r = test::runTolver("predict --machine " + m + " --cl " + cl + " -o " + path("o.apt"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const ClProgram back = readAptFile(path("o.apt"));
  const double g = 100e-6;
  EXPECT_NEAR(back.path[0].p_w.x(), 100 * std::sin(g), 2e-6);
  EXPECT_NEAR(back.path[0].p_w.y(), 100 * std::cos(g), 2e-6);
  EXPECT_NEAR(back.path[1].p_w.x(), 50 + 100 * std::sin(g), 2e-6);
  EXPECT_NEAR(back.path[2].p_w.x(), -50 * std::sin(g), 2e-6);
}

TEST_F(PredictCli, UnreachablePointNamesTheLineAndWritesNothing) {
  const std::string m = write("m.xml", machineWith(""));
  const std::string cl = write("p.apt", "GOTO/0,0,0,0,0,1\n$$ far away\nGOTO/500,0,0\n");
  const auto r = test::runTolver("predict --machine " + m + " --cl " + cl + " -o " + path("o.apt"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("p.apt:3: unreachable: axis X would need -500.0000 mm"),
            std::string::npos)
      << r.output;
  EXPECT_FALSE(fs::exists(path("o.apt")));
  EXPECT_FALSE(fs::exists(path("o.csv")));
}

TEST_F(PredictCli, BadInputsExitWithCode2AndOneLine) {
  const std::string m = write("m.xml", machineWith(""));
  struct Case {
    std::string args;
    std::string needle;
  };
  const std::vector<Case> cases = {
      {"--cl " + write("a.apt", "GOTO/1,2,3\nGOTO/1,2.x,3\n"), "a.apt:2:8: GOTO: malformed number"},
      {"--cl " + write("b.apt", "GOTO/1,2,\n"), "b.apt:1:10: GOTO: missing value"},
      {"--cl " + write("c.apt", ""), "c.apt: empty file"},
      {"--cl " + write("d.apt", "UNITS/CUBITS\nGOTO/1,2,3\n"), "d.apt:1:7: UNITS: unknown unit"},
      {"--cl " + write("e.apt", "PARTNO/NOTHING\n"), "no tool positions"},
      {"--cl " + path("missing.apt"), "missing.apt: cannot open"},
      {"--cl " + src("tests/fixtures/cl/nx_nurbs.clsf"), "nx_nurbs.clsf:13: NURBS"},
      {"--cl " + write("f.apt", "GOTO/1,2,3\n") + " --setup " + write("s.txt", "gauge = 3\n"),
       "s.txt:1: gauge: unknown key"},
      // The library names the input's field (gauge_length, point_table); the CLI, the option.
      {"--cl " + path("f.apt") + " --gauge-length -3",
       "error: --gauge-length: expected a gauge or tool length from 0"},
      {"--cl " + path("f.apt") + " --errors " + path("nodir/t.csv"),
       "error: --errors: " + path("nodir/t.csv")},
      // One number rule: what the files refuse, the command line refuses (nan, inf, hex).
      {"--cl " + path("f.apt") + " --gauge-length nan", "error: --gauge-length: expected a number"},
      {"--cl " + path("f.apt") + " --part-zero 0x10,0,0", "error: --part-zero: expected a number"},
      {"--cl " + path("f.apt") + " --part-rotation-deg inf",
       "error: --part-rotation-deg: expected a number"},
      // One range per quantity: a position the set-up file refuses, the option refuses.
      {"--cl " + path("f.apt") + " --part-zero 0,2e5,0",
       "error: --part-zero: expected a position from -100000 to 100000 mm, found 200000"},
  };
  for (const Case& c : cases) {
    const auto r =
        test::runTolver("predict --machine " + m + " " + c.args + " -o " + path("o.apt"));
    EXPECT_EQ(r.exit_code, 2) << c.args << "\n" << r.output;
    EXPECT_NE(r.output.find(c.needle), std::string::npos) << r.output;
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
    EXPECT_FALSE(fs::exists(path("o.apt")));
  }
  const std::string bad_machine = write("bad.xml", "<machine name='x'><axis name='X'/></machine>");
  const auto r = test::runTolver("predict --machine " + bad_machine + " --cl " +
                                 write("g.apt", "GOTO/1,2,3\n") + " -o " + path("o.apt"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("bad.xml:1: axis.type: missing attribute"), std::string::npos)
      << r.output;
  const auto no_dir = test::runTolver("predict --machine " + m + " --cl " + path("g.apt") + " -o " +
                                      path("nodir/o.apt"));
  EXPECT_EQ(no_dir.exit_code, 2);
  EXPECT_NE(no_dir.output.find("error: -o: "), std::string::npos) << no_dir.output;
  EXPECT_EQ(test::runTolver("predict --machine " + m).exit_code, 2);  // missing options
  EXPECT_EQ(test::runTolver("frobnicate").exit_code, 2);
}

TEST_F(PredictCli, UnknownStatementsWarnOnceAndSucceed) {
  const std::string m = write("m.xml", machineWith(""));
  const std::string cl = write("p.apt", "WIBBLE/3\nGOTO/1,2,3\nWOBBLE\nWIBBLE/4\n");
  const auto r = test::runTolver("predict --machine " + m + " --cl " + cl + " -o " + path("o.apt"));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("skipped 3 unknown statements (WIBBLE, WOBBLE)"), std::string::npos)
      << r.output;
}

TEST_F(PredictCli, HelpExitsZero) {
  const auto r = test::runTolver("predict --help");
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_NE(r.output.find("--machine"), std::string::npos);
}

}  // namespace
}  // namespace tolver

namespace tolver {
namespace {

class PredictOutputs : public test::TempDirTest {};

// The second output cannot be written: neither is left, exit 2; the same
// for calibrate's machine file when its report cannot be written.
TEST_F(PredictOutputs, ASecondOutputThatFailsLeavesNoFirst) {
  auto r = test::runTolver("predict --machine " +
                           test::sourcePath("resources/machines/matsuura_mc760vx.xml") +
                           " --setup " + test::sourcePath("samples/matsuura_setup.txt") + " --cl " +
                           test::sourcePath("samples/nas979_cone.apt") + " -o " + path("ok.apt") +
                           " --errors /proc/tolver_cannot_write.csv");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_FALSE(std::filesystem::exists(path("ok.apt")));
  EXPECT_FALSE(std::filesystem::exists(path("ok.apt.tmp-tolver")));
  r = test::runTolver("calibrate --machine " +
                      test::sourcePath("resources/machines/matsuura_mc760vx.xml") + " --readings " +
                      test::sourcePath("samples/ballbar/clean.csv") + " -o " + path("ok.xml") +
                      " --report /proc/tolver_cannot_write.json");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_FALSE(std::filesystem::exists(path("ok.xml")));
  EXPECT_FALSE(std::filesystem::exists(path("ok_balls.csv")));
}

}  // namespace
}  // namespace tolver

namespace tolver {
namespace {

// Every command that can run long says where it is: in a log, one line per phase when it ends
// (TOLVER_PROGRESS_SECONDS=0: every phase), none with --quiet, never a terminal's bar.
class ProgressCli : public test::TempDirTest {};

TEST_F(ProgressCli, PredictCompensatePlanAndCalibrateSayTheirPhasesInALog) {
  const std::string m = test::sourcePath("samples/machines/matsuura_mc760vx_measured.xml");
  const std::string nominal = test::sourcePath("resources/machines/matsuura_mc760vx.xml");
  const std::string prog = " --cl " + test::sourcePath("samples/nas979_cone.apt") + " --setup " +
                           test::sourcePath("samples/matsuura_setup.txt");
  const std::vector<std::pair<std::string, std::vector<std::string>>> runs = {
      {"predict --machine " + m + prog + " -o " + path("p.apt"), {"predicting"}},
      {"compensate --machine " + m + prog + " -o " + path("c.apt"),
       {"reading", "compensating", "reading back"}},  // CL data: in blocks, three passes
      {"plan-ballbar --machine " + nominal + " --poses 60 -o " + path("plan.csv"),
       {"choosing poses"}},
      {"calibrate --machine " + nominal + " --readings " +
           test::sourcePath("samples/ballbar/clean.csv") + " -o " + path("id.xml"),
       {"fitting", "writing and checking the files"}},
  };
  setenv("TOLVER_PROGRESS_SECONDS", "0", 1);
  for (const auto& [cmd, phases] : runs) {
    const auto r = test::runTolver(cmd);
    const auto q = test::runTolver(cmd + " --quiet");
    ASSERT_EQ(r.exit_code, 0) << cmd << "\n" << r.output;
    ASSERT_EQ(q.exit_code, 0) << cmd << "\n" << q.output;
    for (const std::string& p : phases) {
      const std::string line = "tolver: " + p + ": ";
      const size_t at = r.output.find(line);
      EXPECT_NE(at, std::string::npos) << cmd << "\n" << r.output;
      EXPECT_EQ(r.output.find(line, at + 1), std::string::npos) << cmd << "\n" << r.output;
      EXPECT_EQ(q.output.find(line), std::string::npos) << cmd << "\n" << q.output;
    }
    EXPECT_EQ(r.output.find('\r'), std::string::npos) << cmd;
  }
  unsetenv("TOLVER_PROGRESS_SECONDS");
}

}  // namespace
}  // namespace tolver
