// tolver measure against an independent machining simulation: the sculptured sample's ball-end
// finish cut by a brute-force simulator (its own reading of the CL file, its own placements and
// its own envelope: the material left along each measured point's normal is where that line
// first enters a ball, over every placement; no code of tolver's sweep), on a perfect machine
// with one process effect, measured with 0.5 um probe noise. tolver measure must name the effect
// (or nothing when there is none) and bring the held-out residual to the probe's noise.
#include "pipeline/measure.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "independent_machining.h"
#include "io/common/io_error.h"
#include "io/machine/machine_file.h"
#include "io/mesh/mesh_file.h"
#include "io/program/measured_points.h"
#include "io/program/process_file.h"
#include "pipeline/compensate.h"
#include "test_support.h"

namespace tolver {
namespace {

namespace fs = std::filesystem;
using namespace indep_cut;

// Ten seeds per case, as the issue asks: the right answer in at least 9 of 10, the held-out
// residual after within 1.5 x the probe's noise.
constexpr int kSeeds = 10;
constexpr double kNoise = 0.5e-3;

void print(const char* what, const MeasureRun& r) {
  const PartTrace& t = r.report.trace;
  std::printf("[ measure ] %-12s %s; held-out RMS %.2f -> %.2f um (%d used)\n", what,
              t.verdict_text.c_str(), 1e3 * t.heldout_rms_before, 1e3 * t.heldout_rms_after,
              r.report.used);
}

class MeasureTest : public test::TempDirTest {
 protected:
  MeasureInputs inputs(const std::string& points) {
    MeasureInputs in;
    in.verify.machine.machine = test::sourcePath(machine_);
    if (!setup_.empty()) in.verify.machine.setup = test::sourcePath(setup_);
    in.verify.program.cl = program_;
    in.verify.part = test::sourcePath("samples/sculptured_part.obj");
    in.verify.tolerance_mm = 0.03;
    in.points = points;
    return in;
  }
  static const TriangleMesh& mesh() {
    static const TriangleMesh m =
        readPartMesh(test::sourcePath("samples/sculptured_part.obj")).mesh;
    return m;
  }
  std::string program_;
  // The machine tolver predicts with (the simulator's part does not depend on it).
  std::string machine_ = "resources/machines/matsuura_mc760vx.xml",
              setup_ = "samples/matsuura_setup.txt";
  static const std::vector<Cl>& cl() {
    static const std::vector<Cl> c = readGotos(test::sourcePath("samples/sculptured_finish.apt"));
    return c;
  }
  void SetUp() override {
    TempDirTest::SetUp();
    program_ = write("sculptured_3axis.apt", threeAxisProgram(cl(), 5.0));
  }
  // machine_ as a calibration that missed its X, Y and Z scales: their linear terms identified
  // loose (200 um SD), written beside the test.
  std::string looseScales() {
    Machine m = readMachineFile(test::sourcePath(machine_));
    std::vector<int> ids;
    for (const char* code : {"EXX.c1", "EYY.c1", "EZZ.c1"}) {
      const int k = m.model.findParameter(code);
      EXPECT_GE(k, 0) << code;
      if (k >= 0) ids.push_back(k);
    }
    m.identification.parameters = ids;
    const Eigen::Index n = static_cast<Eigen::Index>(ids.size());
    m.identification.covariance = Eigen::MatrixXd::Identity(n, n) * 0.2 * 0.2;
    m.identification.readings = 600;
    return write("calibrated.xml", formatMachineXml(m, "loose linear terms"));
  }
  // Ten seeds of the X scale off by k (the simulator's own k x), measured with --absolute on
  // `machine`: {named as the machine with |EXX.c1| within 3 SD (+2 um) of 60 um, at the noise}.
  std::pair<int, int> scaleCampaign(const std::string& machine, double k, unsigned first_seed,
                                    const char* what) {
    Effect e;
    e.machine_error = [k](const Eigen::Vector3d& p) { return Eigen::Vector3d(k * p.x(), 0, 0); };
    int named = 0, at_noise = 0;
    for (unsigned seed = first_seed; seed < first_seed + kSeeds; ++seed) {
      const Simulator sim(upright(cl(), 5.0), 5.0, e);
      MeasureInputs in = inputs(write("machine" + std::to_string(seed) + ".csv",
                                      measuredCsv(mesh(), sim, 600, seed, kNoise)));
      in.verify.machine.machine = machine;
      in.verify.absolute = true;  // the simulator's part was not probed on the machine
      const MeasureRun r = measurePart(in);
      print(what, r);
      const PartTrace& t = r.report.trace;
      if (!t.added.empty() && t.groups[0].name == "machine") {
        const TraceGroup& g = t.groups[0];
        std::printf(
            "[ measure ]   EXX.c1 %.2f +- %.2f um, EYY.c1 %.2f +- %.2f, EZZ.c1 %.2f +- %.2f\n",
            1e3 * g.values[0], 1e3 * g.sd[0], 1e3 * g.values[1], 1e3 * g.sd[1], 1e3 * g.values[2],
            1e3 * g.sd[2]);
        named += std::abs(std::abs(g.values[0]) - 0.060) < 3 * g.sd[0] + 2e-3;
      }
      at_noise += t.heldout_rms_after < 1.5 * kNoise;
    }
    return {named, at_noise};
  }
  MeasureRun run(const Effect& e, unsigned seed, const std::string& name) {
    const Simulator sim(upright(cl(), 5.0), 5.0, e);
    const std::string file = write(name + ".csv", measuredCsv(mesh(), sim, 600, seed, 0.5e-3));
    return measurePart(inputs(file));
  }
};

TEST_F(MeasureTest, ACleanPartAddsNothing) {
  int nothing = 0, at_noise = 0;
  for (unsigned seed = 1; seed <= kSeeds; ++seed) {
    const MeasureRun r = run(Effect{}, seed, "clean" + std::to_string(seed));
    print("clean", r);
    EXPECT_GT(r.report.used, 400);
    nothing += r.report.trace.added.empty();
    at_noise += r.report.trace.heldout_rms_after < 1.5 * kNoise;
  }
  EXPECT_GE(nothing, 9);
  EXPECT_GE(at_noise, 9);
}

TEST_F(MeasureTest, ACutterRadiusErrorIsNamedWithItsValue) {
  Effect e;
  e.radius_error_mm = 0.015;
  int named = 0, at_noise = 0;
  for (unsigned seed = 101; seed < 101 + kSeeds; ++seed) {
    const MeasureRun r = run(e, seed, "radius" + std::to_string(seed));
    print("radius +15 um", r);
    const PartTrace& t = r.report.trace;
    // The value within three of its standard deviations (on this gentle part 15 um of radius
    // moves the surface by 0.3 um RMS: the value is known to about 1-2 um).
    const bool ok = !t.added.empty() && t.groups[0].name == "cutter radius" &&
                    std::abs(t.groups[0].values[0] - 0.015) < 3 * t.groups[0].sd[0];
    if (!t.added.empty())
      std::printf("[ measure ]   radius %.2f +- %.2f um\n", 1e3 * t.groups[0].values[0],
                  1e3 * t.groups[0].sd[0]);
    named += ok;
    at_noise += t.heldout_rms_after < 1.5 * kNoise && t.heldout_rms_after < t.heldout_rms_before;
  }
  EXPECT_GE(named, 9);
  EXPECT_GE(at_noise, 9);
}

// A tool 12 um longer than preset: on this gentle part (normals within 35 deg of the axis) it
// reads almost as a uniform stock; tolver names the length, or names the two as confounded.
TEST_F(MeasureTest, AToolLengthErrorIsNamedOrConfounded) {
  Effect e;
  e.length_error_mm = 0.012;
  int named = 0, at_noise = 0;
  for (unsigned seed = 201; seed < 201 + kSeeds; ++seed) {
    const MeasureRun r = run(e, seed, "length" + std::to_string(seed));
    print("length +12 um", r);
    const PartTrace& t = r.report.trace;
    bool ok = false;
    if (!t.added.empty()) {
      const TraceGroup& g = t.groups[0];
      ok = (g.name == "tool length" && std::abs(g.values[0] - 0.012) < 0.002) ||
           std::find(g.confounded.begin(), g.confounded.end(), "tool length") != g.confounded.end();
    }
    named += ok;
    at_noise += t.heldout_rms_after < 1.5 * kNoise;
  }
  EXPECT_GE(named, 9);
  EXPECT_GE(at_noise, 9);
}

TEST_F(MeasureTest, APartSetUpErrorIsNamed) {
  Effect e;
  e.part_error.translation() = Eigen::Vector3d(0.010, -0.004, -0.006);
  e.part_error.linear() = Eigen::AngleAxisd(60e-6, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  int named = 0, at_noise = 0;
  for (unsigned seed = 301; seed < 301 + kSeeds; ++seed) {
    const MeasureRun r = run(e, seed, "setup" + std::to_string(seed));
    print("set-up", r);
    const PartTrace& t = r.report.trace;
    named += !t.added.empty() && t.groups[0].name == "set-up";
    at_noise += t.heldout_rms_after < 1.5 * kNoise;
  }
  EXPECT_GE(named, 9);
  EXPECT_GE(at_noise, 9);
}

// The spindle growing 60 um/h from the program's start: over the finish's 5 min (its FEDRAT,
// 2 m/min) the tip moves 5 um along the axis, growing with the program's clock. tolver reads the
// clock from the program's feed rates and names the drift with its rate (not a tool length).
TEST_F(MeasureTest, AThermalDriftIsNamedWithItsRate) {
  Effect e;
  e.drift_mm_per_h = 0.060;
  int named = 0, at_noise = 0;
  for (unsigned seed = 601; seed < 601 + kSeeds; ++seed) {
    const MeasureRun r = run(e, seed, "drift" + std::to_string(seed));
    print("drift 60um/h", r);
    const PartTrace& t = r.report.trace;
    bool ok = false;
    if (!t.added.empty()) {
      const TraceGroup& g = t.groups[0];
      std::printf("[ measure ]   %s %.2f +- %.2f\n", g.name.c_str(), 1e3 * g.values[0],
                  1e3 * g.sd[0]);
      ok = g.name == "thermal drift" && std::abs(g.values[0] - 0.060) < 3 * g.sd[0] + 1e-3;
    }
    named += ok;
    at_noise += t.heldout_rms_after < 1.5 * kNoise;
  }
  EXPECT_GE(named, 9);
  EXPECT_GE(at_noise, 9);
}

// The cutter pushed 8 um sideways of its feed (a climb cut's deflection): the raster's passes
// run both ways, so the part shows it with opposite signs on neighbouring passes.
TEST_F(MeasureTest, ASidewaysDeflectionIsNamed) {
  Effect e;
  e.deflection_across_mm = 0.008;
  int named = 0, at_noise = 0;
  for (unsigned seed = 701; seed < 701 + kSeeds; ++seed) {
    const MeasureRun r = run(e, seed, "deflection" + std::to_string(seed));
    print("deflect 8 um", r);
    const PartTrace& t = r.report.trace;
    bool ok = false;
    if (!t.added.empty()) {
      const TraceGroup& g = t.groups[0];
      std::printf("[ measure ]   %s %.2f +- %.2f, %.2f +- %.2f um\n", g.name.c_str(),
                  1e3 * g.values[0], 1e3 * g.sd[0], 1e3 * g.values[g.values.size() - 1],
                  1e3 * g.sd[g.sd.size() - 1]);
      ok = g.name == "tool deflection" && std::abs(g.values[1] - 0.008) < 3 * g.sd[1] + 0.5e-3 &&
           std::abs(g.values[0]) < 3 * g.sd[0] + 0.5e-3;
    }
    named += ok;
    at_noise += t.heldout_rms_after < 1.5 * kNoise;
  }
  EXPECT_GE(named, 9);
  EXPECT_GE(at_noise, 9);
}

// An implausible value is not added: the same drift, judged against a physical range of
// 10 um/h, is reported as implausible and the trace goes on without it.
TEST_F(MeasureTest, AnImplausibleValueIsNotAdded) {
  Effect e;
  e.drift_mm_per_h = 0.060;
  const Simulator sim(upright(cl(), 5.0), 5.0, e);
  const std::string file = write("drift.csv", measuredCsv(mesh(), sim, 600, 651, kNoise));
  MeasureInputs in = inputs(file);
  const MeasureRun plausible = measurePart(in);
  ASSERT_FALSE(plausible.report.trace.added.empty());
  EXPECT_EQ(plausible.report.trace.groups[0].name, "thermal drift");
  // The same points judged against a tighter range.
  in.plausible.drift_mm_per_h = 0.010;
  const MeasureRun tight = measurePart(in);
  bool reported = false;
  for (const TraceGroup& g : tight.report.trace.groups) {
    EXPECT_FALSE(g.added && g.name == "thermal drift");
    if (g.name == "thermal drift") reported = g.reason.find("implausible") != std::string::npos;
  }
  EXPECT_TRUE(reported);
}

// A machine error the calibration missed: the X axis's scale off by 60 um over its 760 mm travel
// (the simulator moves the tool by k x along x, its own formula), on a machine file whose
// calibration left the axes' linear positioning terms loose (200 um SD). The part refines the
// machine: the machine group named with EXX.c1's value, machine.xml written, and the next
// measure with it adds nothing and starts where this one ended. --absolute: the simulated part
// was not probed on the machine (without it the prediction, and the machine rows, are taken
// modulo the set-up a shop measures; the loop for that case below).
TEST_F(MeasureTest, AMachineErrorTheCalibrationMissedRefinesTheMachine) {
  const std::string machine = looseScales();
  const double k = 0.060 / 380.0;
  const auto [named, at_noise] = scaleCampaign(machine, k, 801, "machine EXX");
  EXPECT_GE(named, 9);
  EXPECT_GE(at_noise, 9);
  Effect e;
  e.machine_error = [k](const Eigen::Vector3d& p) { return Eigen::Vector3d(k * p.x(), 0, 0); };
  // The loop: machine.xml written, read back, nothing left to add.
  const Simulator sim(upright(cl(), 5.0), 5.0, e);
  MeasureInputs in = inputs(write("loop.csv", measuredCsv(mesh(), sim, 600, 899, kNoise)));
  in.verify.machine.machine = machine;
  in.verify.absolute = true;
  in.report_dir = path("first");
  in.images = false;
  const MeasureRun first = measurePart(in);
  ASSERT_EQ(first.report.machine_written, "machine.xml") << first.report.trace.verdict_text;
  in.verify.machine.machine = path("first") + "/machine.xml";
  in.report_dir = path("second");
  const MeasureRun second = measurePart(in);
  print("refined", second);
  EXPECT_TRUE(second.report.trace.added.empty()) << second.report.trace.verdict_text;
  EXPECT_NEAR(second.report.trace.heldout_rms_before, first.report.trace.heldout_rms_after, 0.1e-3);
  // Modulo the measured set-up (no --absolute): the refined machine predicts what its rows fit.
  in.verify.absolute = false;
  in.verify.machine.machine = machine;
  in.report_dir = path("first_modulo");
  const MeasureRun first_modulo = measurePart(in);
  ASSERT_EQ(first_modulo.report.machine_written, "machine.xml")
      << first_modulo.report.trace.verdict_text;
  in.verify.machine.machine = path("first_modulo") + "/machine.xml";
  in.report_dir = path("second_modulo");
  const MeasureRun second_modulo = measurePart(in);
  print("modulo", second_modulo);
  EXPECT_TRUE(second_modulo.report.trace.added.empty()) << second_modulo.report.trace.verdict_text;
  EXPECT_NEAR(second_modulo.report.trace.heldout_rms_before,
              first_modulo.report.trace.heldout_rms_after, 0.1e-3);
}

// Other machines: the same simulated parts predicted through other kinematic chains (tool-side
// XYZ with an AC trunnion; a Sinumerik BC table; the XKH800, X on the table and A on the head).
// The process effects' sensitivities do not go through the machine, the prediction and its
// sweep do: on each, a clean part adds nothing, a set-up error and a spindle growth are named,
// 10 seeds each; on the trunnion a machine error the calibration missed is named as the machine.

class OtherMachineTest : public MeasureTest {
 protected:
  void campaign(const char* machine, const char* setup) {
    machine_ = machine;
    setup_ = setup;
    Effect setup_error;
    setup_error.part_error.translation() = Eigen::Vector3d(0.010, -0.004, -0.006);
    Effect drift;
    drift.drift_mm_per_h = 0.060;
    int nothing = 0, setup_named = 0, drift_named = 0, at_noise = 0;
    for (unsigned seed = 1001; seed < 1001 + kSeeds; ++seed) {
      const MeasureRun clean = run(Effect{}, seed, "clean" + std::to_string(seed));
      print("clean", clean);
      nothing += clean.report.trace.added.empty();
      const MeasureRun s = run(setup_error, seed + 100, "setup" + std::to_string(seed));
      print("set-up", s);
      setup_named += !s.report.trace.added.empty() && s.report.trace.groups[0].name == "set-up";
      const MeasureRun d = run(drift, seed + 200, "drift" + std::to_string(seed));
      print("drift", d);
      const PartTrace& dt = d.report.trace;
      drift_named += !dt.added.empty() && dt.groups[0].name == "thermal drift" &&
                     std::abs(dt.groups[0].values[0] - 0.060) < 3 * dt.groups[0].sd[0] + 1e-3;
      at_noise += clean.report.trace.heldout_rms_after < 1.5 * kNoise &&
                  s.report.trace.heldout_rms_after < 1.5 * kNoise &&
                  dt.heldout_rms_after < 1.5 * kNoise;
    }
    std::printf(
        "[ measure ] %s: clean nothing added %d/10, set-up named %d/10, drift named "
        "%d/10, all three at the noise %d/10\n",
        machine, nothing, setup_named, drift_named, at_noise);
    EXPECT_GE(nothing, 9);
    EXPECT_GE(setup_named, 9);
    EXPECT_GE(drift_named, 9);
    EXPECT_GE(at_noise, 9);
  }
};

TEST_F(OtherMachineTest, TrunnionAc) {
  campaign("resources/machines/trunnion_ac_trt.xml", "samples/trunnion_setup.txt");
}
TEST_F(OtherMachineTest, SinumerikBcTable) {
  campaign("resources/machines/sinumerik_bc_table.xml", "");
}
TEST_F(OtherMachineTest, Xkh800) {
  campaign("resources/machines/xkh800.xml", "samples/xkh800_setup.txt");
}

// A machine error the calibration missed, on the trunnion (X on the tool side, the part on an
// AC table; its X travel centred on the part's origin): the X scale 60 um over the travel.
TEST_F(OtherMachineTest, TrunnionMachineErrorTheCalibrationMissed) {
  machine_ = "resources/machines/trunnion_ac_trt.xml";
  setup_ = "samples/trunnion_setup.txt";
  const auto [named, at_noise] = scaleCampaign(looseScales(), 0.060 / 400.0, 1401, "trunnion EXX");
  EXPECT_GE(named, 9);
  EXPECT_GE(at_noise, 9);
}

// The command as a user runs it: the console's figures are report.json's, the residual RMS is
// residuals.csv's, process.txt holds the set-up found; a bad points file is refused with its
// line and field, and writes nothing.
TEST_F(MeasureTest, TheCommandWritesWhatItSaysAndRefusesBadPoints) {
  Effect e;
  e.part_error.translation() = Eigen::Vector3d(0.010, -0.004, -0.006);
  const Simulator sim(upright(cl(), 5.0), 5.0, e);
  const std::string points = write("cmm.csv", measuredCsv(mesh(), sim, 400, 77, kNoise));
  const std::string base =
      "measure --machine " + test::sourcePath("resources/machines/matsuura_mc760vx.xml") +
      " --setup " + test::sourcePath("samples/matsuura_setup.txt") + " --cl " + program_ +
      " --part " + test::sourcePath("samples/sculptured_part.obj") + " --tolerance 0.03";
  const test::RunResult r =
      test::runTolver(base + " --points " + points + " --report-dir " + path("out"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::printf("%s", r.output.c_str());
  EXPECT_NE(r.output.find("tolver measure: effects added: set-up"), std::string::npos) << r.output;
  std::ifstream jf(path("out") + "/report.json");
  const nlohmann::json j = nlohmann::json::parse(jf);
  EXPECT_EQ(j["points"]["used"].get<int>(), 400);
  EXPECT_EQ(j["trace"]["verdict"], "effects added");
  // The largest residual's place names the CAM operation that cut it (NX's TOOL PATH/name).
  EXPECT_EQ(j["largest_residual_after"]["operation"], "FINISH_3AXIS");
  EXPECT_NE(r.output.find(", operation FINISH_3AXIS"), std::string::npos) << r.output;
  char after[80];
  std::snprintf(after, sizeof after, "held-out RMS %.2f um",
                j["trace"]["after_um"]["heldout_rms"].get<double>());
  EXPECT_NE(r.output.find(after), std::string::npos) << r.output;
  // residuals.csv: the residual RMS of the used rows is the JSON's.
  std::ifstream cf(path("out") + "/residuals.csv");
  std::string line;
  std::getline(cf, line);
  double s2 = 0;
  int used = 0;
  while (std::getline(cf, line)) {
    std::vector<std::string> c;
    std::stringstream ss(line);
    for (std::string cell; std::getline(ss, cell, ',');) c.push_back(cell);
    ASSERT_EQ(c.size(), 23u) << line;
    if (c[20] != "used") continue;
    EXPECT_EQ(c[22], "FINISH_3AXIS") << line;
    const double res = std::stod(c[14]), meas = std::stod(c[10]), pred = std::stod(c[11]);
    EXPECT_NEAR(res, meas - pred, 2e-4) << line;
    s2 += res * res;
    ++used;
  }
  EXPECT_EQ(used, 400);
  EXPECT_NEAR(std::sqrt(s2 / used), j["deviation_um"]["residual_rms"].get<double>(), 1e-3);
  std::ifstream pf(path("out") + "/process.txt");
  const std::string process((std::istreambuf_iterator<char>(pf)), {});
  EXPECT_NE(process.find("set-up_x_mm "), std::string::npos) << process;
  // report.html: self-contained, the verdict, the effect added with its values as the console
  // prints them, the largest residual's operation, the images embedded.
  std::ifstream hf(path("out") + "/report.html");
  const std::string html((std::istreambuf_iterator<char>(hf)), {});
  EXPECT_NE(html.find(j["trace"]["verdict_text"].get<std::string>()), std::string::npos);
  EXPECT_NE(html.find("<tr class=\"added\"><td>set-up</td>"), std::string::npos);
  EXPECT_NE(html.find("operation FINISH_3AXIS"), std::string::npos);
  size_t embedded = 0;
  for (size_t at = html.find("data:image/png;base64,"); at != std::string::npos;
       at = html.find("data:image/png;base64,", at + 1))
    ++embedded;
  EXPECT_EQ(embedded, 4u);
  EXPECT_NE(r.output.find("report.html"), std::string::npos);
  // The residual's maps and histograms, before and after, listed in report.json and written.
  const std::vector<std::string> images = j["images"].get<std::vector<std::string>>();
  EXPECT_EQ(images.size(), 4u);
  for (const std::string name : {"map_residual.png", "map_residual_after.png",
                                 "histogram_residual.png", "histogram_residual_after.png"}) {
    EXPECT_NE(std::find(images.begin(), images.end(), name), images.end()) << name;
    EXPECT_GT(fs::file_size(path("out") + "/" + name), 10000u) << name;
    EXPECT_NE(r.output.find(name), std::string::npos) << name;
  }

  // Bad input: a word where a number goes; points nowhere near the part.
  const std::string bad = write("bad.csv", "x_mm,y_mm,z_mm\n1,2,3\n4,five,6\n");
  const test::RunResult b =
      test::runTolver(base + " --points " + bad + " --report-dir " + path("bad_out"));
  EXPECT_EQ(b.exit_code, 2) << b.output;
  EXPECT_NE(b.output.find("bad.csv:3"), std::string::npos) << b.output;
  EXPECT_NE(b.output.find("y_mm"), std::string::npos) << b.output;
  EXPECT_FALSE(fs::exists(path("bad_out")));
  const std::string far = write("far.csv", "x_mm,y_mm,z_mm\n1000,2000,3000\n");
  const test::RunResult f =
      test::runTolver(base + " --points " + far + " --report-dir " + path("far_out"));
  EXPECT_EQ(f.exit_code, 2) << f.output;
  EXPECT_NE(f.output.find("none of the 1 points"), std::string::npos) << f.output;
  EXPECT_FALSE(fs::exists(path("far_out")));
}

// The loop closed: the corrections measure writes, read back by measure (and verify) with
// --process, predict the same part to the probe's noise with nothing left to add; the second
// run's "before" is the first run's "after" on the same held-out points.
TEST_F(MeasureTest, TheProcessFileCarriesWhatWasLearnedIntoTheNextPrediction) {
  Effect e;
  e.radius_error_mm = 0.015;
  e.length_error_mm = 0.008;
  e.part_error.translation() = Eigen::Vector3d(0.006, 0.0, 0.0);
  const Simulator sim(upright(cl(), 5.0), 5.0, e);
  const std::string points = write("cmm.csv", measuredCsv(mesh(), sim, 600, 401, kNoise));
  MeasureInputs in = inputs(points);
  in.report_dir = path("first");
  const MeasureRun first = measurePart(in);
  print("first", first);
  ASSERT_FALSE(first.report.trace.added.empty());
  in.verify.process = path("first") + "/process.txt";
  in.report_dir = path("second");
  const MeasureRun second = measurePart(in);
  print("second", second);
  const PartTrace& t = second.report.trace;
  EXPECT_TRUE(t.added.empty()) << t.verdict_text;
  EXPECT_LT(t.heldout_rms_before, 1.5 * kNoise);
  EXPECT_NEAR(t.heldout_rms_before, first.report.trace.heldout_rms_after, 0.1e-3);
  // The second process file carries the first's corrections.
  std::ifstream a(path("first") + "/process.txt"), b(path("second") + "/process.txt");
  const std::string pa((std::istreambuf_iterator<char>(a)), {}),
      pb((std::istreambuf_iterator<char>(b)), {});
  for (const std::string key : {"tool_length_dL_mm", "set-up_x_mm"})
    if (pa.find(key) != std::string::npos) {
      EXPECT_NE(pb.find(key), std::string::npos) << pb;
    }
}

// The drift and the sideways deflection a part showed carry into the next prediction too:
// verify moves each predicted placement by the rate times the program's clock along the axis and
// by the deflection along a x f; the second measure finds nothing left.
TEST_F(MeasureTest, TheProcessFileCarriesDriftAndDeflection) {
  Effect e;
  e.drift_mm_per_h = 0.040;
  e.deflection_across_mm = 0.010;
  const Simulator sim(upright(cl(), 5.0), 5.0, e);
  const std::string points = write("cmm.csv", measuredCsv(mesh(), sim, 600, 451, kNoise));
  MeasureInputs in = inputs(points);
  in.report_dir = path("first");
  const MeasureRun first = measurePart(in);
  print("first", first);
  ASSERT_GE(first.report.trace.added.size(), 2u);
  std::ifstream a(path("first") + "/process.txt");
  const std::string pa((std::istreambuf_iterator<char>(a)), {});
  EXPECT_NE(pa.find("thermal_drift_spindle_growth_mm/h "), std::string::npos) << pa;
  EXPECT_NE(pa.find("tool_deflection_across_the_feed_mm "), std::string::npos) << pa;
  const ProcessCorrections pc = readProcessFile(path("first") + "/process.txt");
  EXPECT_NEAR(pc.drift_mm_per_h, 0.040, 0.003);
  ASSERT_EQ(pc.across_feed_mm.count(0), 1u);
  EXPECT_NEAR(pc.across_feed_mm.at(0), 0.010, 0.0015);
  in.verify.process = path("first") + "/process.txt";
  in.report_dir = path("second");
  const MeasureRun second = measurePart(in);
  print("second", second);
  EXPECT_TRUE(second.report.trace.added.empty()) << second.report.trace.verdict_text;
  EXPECT_LT(second.report.trace.heldout_rms_before, 1.5 * kNoise);
}

// The loop closed through compensate: the process file a measured part gave compensates the
// program (compensate --process), and the independent simulator cuts the compensated program
// with the same process effects: the part comes out where a clean process puts it, and measure
// on it (with the compensated program and the process file) finds nothing left.
TEST_F(MeasureTest, CompensatingForTheProcessMakesTheNextPartRight) {
  Effect e;
  e.part_error.translation() = Eigen::Vector3d(0.008, -0.005, 0.004);
  e.drift_mm_per_h = 0.040;
  e.deflection_across_mm = 0.006;
  const std::vector<Cl> nominal = upright(cl(), 5.0);
  const Simulator first_sim(nominal, 5.0, e);
  MeasureInputs in = inputs(write("cmm.csv", measuredCsv(mesh(), first_sim, 600, 501, kNoise)));
  in.report_dir = path("first");
  const MeasureRun first = measurePart(in);
  print("first", first);
  ASSERT_GE(first.report.trace.added.size(), 2u) << first.report.trace.verdict_text;
  CompensateInputs c;
  c.machine = in.verify.machine;
  c.program.cl = program_;
  c.process = path("first") + "/process.txt";
  c.output = path("compensated.apt");
  const CompensateRun comp = compensateProgram(c);
  EXPECT_EQ(comp.verdict, Verdict::Ok);
  ASSERT_TRUE(comp.compensation.has_value());
  const CompensationReport& rep = comp.compensation->report;
  EXPECT_NE(rep.process_applied.find("set-up"), std::string::npos) << rep.process_applied;
  std::printf("[ measure ] compensate --process: %s; before %.2f um RMS, after %.4f um\n",
              rep.process_applied.c_str(), rep.before.tip_rms_um, rep.after.tip_rms_um);
  EXPECT_GT(rep.before.tip_rms_um, 5.0);
  EXPECT_LT(rep.after.tip_rms_um, 0.01);
  {
    std::ifstream jf(path("compensated.json"));
    const nlohmann::json j = nlohmann::json::parse(jf);
    EXPECT_EQ(j["process"]["file"], c.process);
  }
  // The next part, cut by the independent simulator from the compensated program's own text.
  const std::vector<Cl> corrected = readGotos(c.output);
  ASSERT_EQ(corrected.size(), nominal.size());
  const Simulator second_sim(corrected, 5.0, e), clean_sim(nominal, 5.0, Effect{});
  auto offsets = [&](const Simulator& sim) {  // the surface along the same 300 normals
    std::vector<double> out;
    std::stringstream ss(measuredCsv(mesh(), sim, 300, 502, 0.0));
    std::string line;
    while (std::getline(ss, line)) {
      if (line.empty() || line[0] == '#' || line[0] == 'x') continue;
      double v[6];
      std::stringstream ls(line);
      std::string cell;
      for (int k = 0; k < 6 && std::getline(ls, cell, ','); ++k) v[k] = std::stod(cell);
      out.push_back(Eigen::Vector3d(v[0], v[1], v[2]).dot(Eigen::Vector3d(v[3], v[4], v[5])));
    }
    return out;
  };
  const std::vector<double> clean = offsets(clean_sim), before = offsets(first_sim),
                            after = offsets(second_sim);
  ASSERT_EQ(clean.size(), 300u);
  ASSERT_EQ(before.size(), clean.size());
  ASSERT_EQ(after.size(), clean.size());
  double s_before = 0, s_after = 0;
  for (size_t i = 0; i < clean.size(); ++i) {
    s_before += std::pow(before[i] - clean[i], 2);
    s_after += std::pow(after[i] - clean[i], 2);
  }
  const double rms_before = std::sqrt(s_before / clean.size()),
               rms_after = std::sqrt(s_after / clean.size());
  std::printf(
      "[ measure ] the part against a clean process's: %.2f um RMS uncompensated, %.2f um "
      "compensated\n",
      1e3 * rms_before, 1e3 * rms_after);
  EXPECT_GT(rms_before, 0.003);
  EXPECT_LT(rms_after, 0.1 * rms_before);
  EXPECT_LT(rms_after, kNoise);
  // measure on the compensated part, with the compensated program and the process file: the
  // prediction holds (nothing to add, held-out at the probe's noise).
  MeasureInputs again =
      inputs(write("cmm2.csv", measuredCsv(mesh(), second_sim, 600, 503, kNoise)));
  again.verify.program.cl = c.output;
  again.verify.process = c.process;
  const MeasureRun second = measurePart(again);
  print("second", second);
  EXPECT_TRUE(second.report.trace.added.empty()) << second.report.trace.verdict_text;
  EXPECT_LT(second.report.trace.heldout_rms_before, 1.5 * kNoise);
}

// Places measured twice give the repeatability: a clean part's residual is it (the test passes,
// nothing added); a 2 um waviness along x that no candidate holds fails it, and the verdict is
// "unexplained" with what the model misses, never "nothing added".
TEST_F(MeasureTest, RepeatedPlacesTestTheModelsAdequacy) {
  const auto trace = [&](const Effect& e, unsigned seed, const std::string& name) {
    const Simulator sim(upright(cl(), 5.0), 5.0, e);
    const std::string file = write(name, measuredCsv(mesh(), sim, 600, seed, kNoise, 2));
    return measurePart(inputs(file)).report.trace;
  };
  const PartTrace clean = trace(Effect{}, 501, "clean.csv");
  std::printf("[ measure ] clean, twice   %s\n", clean.verdict_text.c_str());
  EXPECT_TRUE(clean.lack_of_fit.tested);
  EXPECT_GE(clean.lack_of_fit.places,
            150);  // 300 places; pairs split by the held-out points do not count
  EXPECT_EQ(clean.verdict, "nothing added");
  EXPECT_NEAR(clean.lack_of_fit.s_pure, kNoise, 0.1e-3);
  Effect wave;
  wave.wave_mm = 0.002;
  const PartTrace waved = trace(wave, 502, "wave.csv");
  std::printf("[ measure ] wave, twice    %s\n", waved.verdict_text.c_str());
  EXPECT_EQ(waved.verdict, "unexplained");
  EXPECT_GT(waved.lack_of_fit.missing_rms, 0.8e-3);
  // Once per place: adequacy cannot be tested, and the verdict says so.
  const Simulator sim(upright(cl(), 5.0), 5.0, Effect{});
  const PartTrace once =
      measurePart(inputs(write("once.csv", measuredCsv(mesh(), sim, 300, 503, kNoise))))
          .report.trace;
  EXPECT_FALSE(once.lack_of_fit.tested);
  EXPECT_NE(once.verdict_text.find("adequacy not tested"), std::string::npos);
}

// The two readers' refusals name the line and the field; what they accept they read exactly.
TEST(MeasureFiles, PointsAndProcessCorrectionsAreReadOrRefusedByLine) {
  const auto refused = [](const std::function<void()>& f, const std::string& where) {
    try {
      f();
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(where), std::string::npos) << e.what();
      return true;
    }
    return false;
  };
  const ProcessCorrections c = parseProcessFile(
      "# c\nset-up_x_mm 0.002\nset-up_about_z_rad 1e-5\ncutter_radius_T2_dR_mm -0.003\n"
      "tool_length_dL_mm 0.01  # +- 1e-5\nstock_offset_mm 0.001\nmachine_EXX.c1 1e-4\n",
      "p.txt");
  EXPECT_DOUBLE_EQ(c.part_error.translation().x(), 0.002);
  EXPECT_NEAR(c.part_error.linear()(1, 0), 1e-5, 1e-12);
  EXPECT_DOUBLE_EQ(c.radius_mm.at(1), -0.003);
  EXPECT_DOUBLE_EQ(c.length_mm.at(0), 0.01);
  EXPECT_EQ(c.not_applied.size(), 2u);
  EXPECT_TRUE(refused([] { parseProcessFile("\nbogus_key 1\n", "p.txt"); }, "p.txt:2"));
  EXPECT_TRUE(refused([] { parseProcessFile("tool_length_dL_mm 5\n", "p.txt"); }, "beyond 1 mm"));
  EXPECT_TRUE(refused([] { parseProcessFile("cutter_radius_T99999999999_dR_mm 0.001\n", "p.txt"); },
                      "unknown key"));
  EXPECT_TRUE(refused([] { parseProcessFile("set-up_x_mm abc\n", "p.txt"); }, "not a number"));
  const std::vector<MeasuredPoint> asc = parseMeasuredPoints("1 2 3\n4;5;6\n", "c.asc");
  ASSERT_EQ(asc.size(), 2u);
  EXPECT_EQ(asc[1].p, Eigen::Vector3d(4, 5, 6));
  const std::vector<MeasuredPoint> csv =
      parseMeasuredPoints("X,Y,Z,nx,ny,nz,Deviation\n1,2,3,0,0,2,0.004\n", "c.csv");
  ASSERT_EQ(csv.size(), 1u);
  EXPECT_EQ(csv[0].n, Eigen::Vector3d(0, 0, 1));
  EXPECT_TRUE(csv[0].has_deviation);
  const std::vector<MeasuredPoint> table = parseMeasuredPoints(
      "nominal_x_mm,nominal_y_mm,nominal_z_mm,nx,ny,nz,deviation_mm\n1,2,3,0,0,1,0.004\n", "t.csv");
  ASSERT_EQ(table.size(), 1u);
  EXPECT_NEAR(table[0].p.z(), 3.004, 1e-12);
  EXPECT_TRUE(refused(
      [] { parseMeasuredPoints("nominal_x_mm,nominal_y_mm,nominal_z_mm\n1,2,3\n", "t.csv"); },
      "t.csv:2"));
  EXPECT_TRUE(
      refused([] { parseMeasuredPoints("x_mm,y_mm,z_mm,nx\n1,2,3,1\n", "c.csv"); }, "c.csv:2"));
  EXPECT_TRUE(refused([] { parseMeasuredPoints("1 2 3\n1 2\n", "c.asc"); }, "c.asc:2"));
  // Empty, comments only, a header alone: no points is an error, not an empty trace.
  const std::string dir = std::filesystem::temp_directory_path().string();
  for (const std::string text : {"", "# nothing\n", "x_mm,y_mm,z_mm\n"}) {
    const std::string f = dir + "/tolver_empty_points_" + std::to_string(::getpid()) + ".csv";
    std::ofstream(f) << text;
    EXPECT_TRUE(refused([&] { readMeasuredPoints(f); }, f + ": "))
        << text;  // "empty file" or "no measured points"
    std::filesystem::remove(f);
  }
  EXPECT_TRUE(refused([] { parseProcessFile("set-up_x_mm\n", "p.txt"); }, "key value"));
  EXPECT_TRUE(refused([] { parseMeasuredPoints("x_mm,y_mm\n1,2\n", "c.csv"); }, "z_mm"));
  EXPECT_TRUE(refused([] { parseMeasuredPoints("1 2 3 0 0 0\n", "c.asc"); }, "normal is zero"));
}

// PLY point clouds as CloudCompare and scanners write them: ascii and binary of both byte orders
// read the same points (and normals) as the CSV; short or malformed files are refused by field.
TEST(MeasureFiles, PlyPointCloudsReadAsTheCsvDoes) {
  const std::vector<Eigen::Vector3d> p = {{1.5, -2.25, 3.125}, {-10, 20.5, 0.001}, {7, 8, 9}};
  const std::vector<Eigen::Vector3d> n = {{0, 0, 1}, {0, 0.6, 0.8}, {1, 0, 0}};
  std::string ascii =
      "ply\nformat ascii 1.0\ncomment CloudCompare\nelement vertex 3\nproperty double x\n"
      "property double y\nproperty double z\nproperty float nx\nproperty float ny\n"
      "property float nz\nproperty uchar red\nelement face 0\n"
      "property list uchar int vertex_indices\nend_header\n";
  for (size_t i = 0; i < p.size(); ++i) {
    char l[200];
    std::snprintf(l, sizeof l, "%.17g %.17g %.17g %g %g %g 255\n", p[i].x(), p[i].y(), p[i].z(),
                  n[i].x(), n[i].y(), n[i].z());
    ascii += l;
  }
  const auto binary = [&](bool big) {
    std::string b = std::string("ply\nformat ") +
                    (big ? "binary_big_endian" : "binary_little_endian") +
                    " 1.0\nelement vertex 3\nproperty float64 x\nproperty float64 y\n"
                    "property float64 z\nproperty short flag\nproperty float nx\n"
                    "property float ny\nproperty float nz\nend_header\n";
    auto put = [&](const void* v, size_t size) {
      std::string bytes(static_cast<const char*>(v), size);
      if (big) std::reverse(bytes.begin(), bytes.end());  // the test machine is little-endian
      b += bytes;
    };
    for (size_t i = 0; i < p.size(); ++i) {
      for (int c = 0; c < 3; ++c) put(&p[i][c], 8);
      const int16_t flag = -3;
      put(&flag, 2);
      for (int c = 0; c < 3; ++c) {
        const float f = static_cast<float>(n[i][c]);
        put(&f, 4);
      }
    }
    return b;
  };
  for (const std::string& text : {ascii, binary(false), binary(true)}) {
    const std::vector<MeasuredPoint> m = parseMeasuredPoints(text, "cloud.ply");
    ASSERT_EQ(m.size(), 3u);
    for (size_t i = 0; i < p.size(); ++i) {
      EXPECT_EQ(m[i].p, p[i]);
      EXPECT_NEAR((m[i].n - n[i]).norm(), 0.0, 1e-6);
    }
  }
  const auto refusal = [](const std::string& text) {
    try {
      parseMeasuredPoints(text, "bad.ply");
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  std::string cut = binary(false);
  cut.resize(cut.size() - 5);
  EXPECT_NE(refusal(cut).find("shorter than its 3 vertices"), std::string::npos) << refusal(cut);
  EXPECT_NE(refusal("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float "
                    "y\nend_header\n1 2\n")
                .find("no property z"),
            std::string::npos);
  EXPECT_NE(refusal("ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float "
                    "y\nproperty float z\nend_header\n1 2 3\n4 five 6\n")
                .find("bad.ply:9"),
            std::string::npos);
  EXPECT_NE(refusal("ply\nformat ascii 1.0\nelement vertex 99999999999\nproperty float x\n"
                    "property float y\nproperty float z\nend_header\n1 2 3\n")
                .find("shorter"),
            std::string::npos);
  EXPECT_NE(refusal("ply\nformat binary 1.0\nend_header\n").find("format"), std::string::npos);
  EXPECT_NE(
      refusal("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n").find("end_header"),
      std::string::npos);
}

}  // namespace
}  // namespace tolver
