// Every command as a library function (pipeline/<command>.h), called without the binary: typed
// inputs in, a typed run with its Verdict out, files written as the run says, and an invalid
// input refused as a FieldError naming the input's field (never a command-line option).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "io/common/io_error.h"
#include "machine_errors.h"
#include "pipeline/allocate.h"
#include "pipeline/analyze.h"
#include "pipeline/ballbar.h"
#include "pipeline/calibrate.h"
#include "pipeline/compensate.h"
#include "pipeline/diagnose.h"
#include "pipeline/predict.h"
#include "pipeline/setup.h"
#include "pipeline/verify.h"
#include "test_support.h"

namespace tolver {
namespace {

namespace fs = std::filesystem;
using test::sourcePath;

const char* kNominal = "resources/machines/matsuura_mc760vx.xml";
const char* kMeasured = "samples/machines/matsuura_mc760vx_measured.xml";

class Commands : public test::TempDirTest {
 protected:
  static MachineOptions machine(const char* file, bool with_setup = true) {
    MachineOptions m;
    m.machine = sourcePath(file);
    if (with_setup) m.setup = sourcePath("samples/matsuura_setup.txt");
    return m;
  }
  static ProgramOptions cone() {
    ProgramOptions p;
    p.cl = sourcePath("samples/nas979_cone.apt");
    return p;
  }
};

// The field an input error names, and that it names no option.
template <typename F>
std::string refusedField(F&& f) {
  try {
    f();
  } catch (const FieldError& e) {
    EXPECT_EQ(std::string(e.what()).find(" --"), std::string::npos) << e.what();
    return e.field();
  }
  return "(not refused)";
}

// A machine without errors reaches every point of the program: deviation zero, both files written
// with one row per point.
TEST_F(Commands, PredictOnAPerfectMachineIsTheProgram) {
  PredictInputs in;
  in.machine = machine(kNominal);
  in.program = cone();
  in.output = path("p.apt");
  const PredictionRun run = predict(in);
  EXPECT_EQ(run.verdict, Verdict::Ok);
  EXPECT_LT(run.prediction.summary.max_deviation, 1e-9);
  EXPECT_EQ(run.nonzero_parameters, 0);
  EXPECT_EQ(run.point_table, path("p.csv"));
  ASSERT_TRUE(fs::exists(path("p.apt")));
  std::ifstream table(path("p.csv"));
  std::string line;
  size_t rows = 0;
  while (std::getline(table, line))
    if (!line.empty() && line[0] != '#') ++rows;
  EXPECT_EQ(rows, run.program.pointsRead() + 1);  // and the header
  EXPECT_EQ(run.program.pointsRead(), static_cast<size_t>(run.prediction.summary.points));

  in.machine = machine(kMeasured);
  const PredictionRun real = predict(in);
  EXPECT_GT(real.prediction.summary.max_deviation, 1e-3);  // the measured machine's errors show

  in.output = path("no/such/dir/p.apt");
  EXPECT_EQ(refusedField([&] { predict(in); }), "output");
  in.output = path("p.apt");
  in.machine.part_zero = {1, 2};
  EXPECT_EQ(refusedField([&] { predict(in); }), "part_zero");
}

// A program whose subs and loops run (LinuxCNC O-words: LinuxCNC's own flowsnake test) is
// predicted in blocks as whole: the written CL and table byte for byte, although its
// constructs' points come in runs longer than a block.
TEST_F(Commands, PredictInBlocksRunsOWordProgramsAsWhole) {
  PredictInputs in;
  in.machine.machine = sourcePath("resources/machines/linuxcnc_xyzac_trt.xml");
  in.program.nc = sourcePath("tests/fixtures/gcode/linuxcnc_flowsnake.ngc");
  std::string text[2], table[2];
  for (int blocks = 0; blocks < 2; ++blocks) {
    in.block_points = blocks ? 7 : 0;
    in.output = path("f" + std::to_string(blocks) + ".apt");
    const PredictionRun run = predict(in);
    EXPECT_EQ(run.verdict, Verdict::Ok);
    EXPECT_EQ(run.program.pointsRead(), 195u);
    text[blocks] = test::readText(in.output);
    table[blocks] = test::readText(path("f" + std::to_string(blocks) + ".csv"));
  }
  EXPECT_EQ(text[0], text[1]);
  EXPECT_EQ(table[0], table[1]);
  // compensate cannot rewrite it line by line: refused at the first call, nothing written.
  CompensateInputs c;
  c.machine = in.machine;
  c.program = in.program;
  c.output = path("c.ngc");
  try {
    compensateProgram(c);
    ADD_FAILURE() << "compensated";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "control flow");
    EXPECT_NE(std::string(e.what()).find("flowsnake.ngc:36"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(path("c.ngc")));
}

// The link model of the thesis's machine: the minimal-complete set has as many parameters as the
// rank of the sensitivity Jacobian (every dependent column removed, none more).
TEST_F(Commands, AnalyzeKeepsTheRankOfTheModel) {
  AnalyzeInputs in;
  in.machine = machine(kNominal, false);
  in.model = "link";
  const AnalysisRun run = analyze(in);
  EXPECT_EQ(run.verdict, Verdict::Ok);
  EXPECT_EQ(static_cast<int>(run.minimal.kept.size()), run.minimal.initial.rank);
  EXPECT_EQ(run.minimal.reduced.rank, static_cast<int>(run.minimal.kept.size()));
  in.model = "spline";
  EXPECT_EQ(refusedField([&] { analyze(in); }), "model");
}

// Plan, simulate on the true machine without noise, calibrate on the nominal one: the identified
// machine reproduces the readings (the written files read back), and a plan the readings then
// analyse is fully observable.
TEST_F(Commands, PlanSimulateCalibrateRoundTrip) {
  PlanBallbarInputs plan;
  plan.machine = machine(kNominal, false);
  plan.output = path("plan.csv");
  plan.heldout = 30;
  const PlanRun p = planBallbar(plan);
  EXPECT_EQ(p.verdict, Verdict::Ok);
  EXPECT_EQ(p.gcode, path("plan.nc"));
  EXPECT_EQ(p.heldout_output, path("plan_heldout.csv"));
  for (const std::string& f : {p.output, p.gcode, p.heldout_output, p.heldout_gcode})
    EXPECT_TRUE(fs::exists(f)) << f;
  EXPECT_EQ(p.plan.rank, p.plan.unknowns);
  EXPECT_GE(p.plan.test.readings.size(), 180u);  // the poses and the reference returns

  SimulateBallbarInputs sim;
  sim.machine = machine(kMeasured, false);
  sim.plan = p.output;
  sim.heldout_plan = p.heldout_output;
  sim.output = path("readings.csv");
  const SimulationRun s = simulateBallbar(sim);
  EXPECT_EQ(s.readings, p.plan.test.readings.size());
  EXPECT_EQ(s.heldout_readings, 30u);
  EXPECT_EQ(s.heldout_output, path("readings_heldout.csv"));

  CalibrateInputs cal;
  cal.machine = machine(kNominal, false);
  cal.readings = s.output;
  cal.heldout = s.heldout_output;
  cal.prior = "none";
  cal.output = path("identified.xml");
  const CalibrationRun c = calibrateMachine(cal);
  EXPECT_EQ(c.verdict, Verdict::Ok);
  EXPECT_LT(c.fit.rms_residual, 1e-6);
  EXPECT_LT(c.written.fit.rms, 1e-6);      // the written files, read back
  EXPECT_LT(c.written.heldout.rms, 1e-4);  // and poses they were not fitted to
  EXPECT_EQ(c.outputs.balls, path("identified_balls.csv"));
  EXPECT_TRUE(fs::exists(c.outputs.report));

  // With a set-up file (its 100 mm gauge length moves the tool frame the ball positions are in),
  // simulated and fitted alike: the written files, read back with the same set-up, reproduce the
  // fit (they reported 98.6 mm RMS, read back without it).
  sim.machine = machine(kMeasured, true);
  sim.output = path("readings_setup.csv");
  sim.heldout_output = path("readings_setup_heldout.csv");
  simulateBallbar(sim);
  cal.machine = machine(kNominal, true);
  cal.readings = sim.output;
  cal.heldout = sim.heldout_output;
  cal.output = path("identified_setup.xml");
  const CalibrationRun cs = calibrateMachine(cal);
  EXPECT_LT(cs.fit.rms_residual, 1e-6);
  EXPECT_LT(cs.written.fit.rms, 1e-6);
  EXPECT_LT(cs.written.heldout.rms, 1e-4);

  cal.spindle_tilt_urad = -1;
  EXPECT_EQ(refusedField([&] { calibrateMachine(cal); }), "spindle_tilt_urad");
  plan.program = cone();
  plan.volume = true;
  EXPECT_EQ(refusedField([&] { planBallbar(plan); }), "volume");
}

// Diagnose on readings of a machine with a reversal error adds the reversal; on clean readings,
// nothing. The augmented machine and the report directory are written as the run says.
TEST_F(Commands, DiagnoseAddsWhatIsMissingAndNothingElse) {
  DiagnoseInputs in;
  in.machine = machine(kNominal, false);
  in.readings = sourcePath("samples/ballbar/reversal.csv");
  in.output = path("augmented.xml");
  in.report_dir = path("out");
  const DiagnosisRun run = diagnoseMachine(in);
  EXPECT_EQ(run.verdict, Verdict::Ok);
  ASSERT_EQ(run.result.added.size(), 1u);
  EXPECT_NE(run.result.added[0].label.find("reversal"), std::string::npos)
      << run.result.added[0].label;
  EXPECT_TRUE(fs::exists(run.json));
  EXPECT_TRUE(fs::exists(path("augmented_balls.csv")));

  in.readings = sourcePath("samples/ballbar/clean.csv");
  in.report_dir = path("clean");
  const DiagnosisRun clean = diagnoseMachine(in);
  EXPECT_TRUE(clean.result.added.empty());
  EXPECT_EQ(clean.result.verdict, DiagnosisVerdict::NothingMissing);

  in.types = {"backlash-ish"};
  EXPECT_EQ(refusedField([&] { diagnoseMachine(in); }), "types");
}

// The set-up search on the cone: a set-up that keeps every point inside travel, with the margin
// the proposal states; the set-up file it writes, read back by predict, reaches every point.
TEST_F(Commands, SetupProposesAReachableSetUp) {
  SetupInputs in;
  in.machine = machine(kNominal, false);
  in.program = cone();
  in.output = path("setup.txt");
  const SetupRun run = proposeSetup(in);
  ASSERT_EQ(run.verdict, Verdict::Ok);
  EXPECT_EQ(run.mode, SetupMode::PartFrame);
  EXPECT_TRUE(run.search.found);
  EXPECT_GE(run.search.margin, 0.0);
  ASSERT_EQ(run.written.size(), 1u);
  PredictInputs p;
  p.machine = machine(kNominal, false);
  p.machine.setup = run.written[0].first;
  p.program = cone();
  p.output = path("p.apt");
  EXPECT_NO_THROW(predict(p));

  in.gauge_lengths = {-5};
  EXPECT_EQ(refusedField([&] { proposeSetup(in); }), "gauge_lengths");
}

// Compensation on the measured machine: the written program, read back and predicted, is closer
// to the nominal path than the original; no output and no tables is refused by field.
TEST_F(Commands, CompensateWritesACloserProgram) {
  CompensateInputs in;
  in.machine = machine(kMeasured);
  in.program = cone();
  in.output = path("c.apt");
  const CompensateRun run = compensateProgram(in);
  EXPECT_EQ(run.verdict, Verdict::Ok);
  ASSERT_TRUE(run.compensation);
  EXPECT_TRUE(run.worse_lines.empty());
  EXPECT_LT(run.compensation->report.after.tip_max_um,
            0.05 * run.compensation->report.before.tip_max_um);
  EXPECT_EQ(run.report, path("c.json"));
  EXPECT_TRUE(fs::exists(run.joints));
  // The machine's own errors are said: none named on the measured machine; on the nominal one,
  // that there is nothing to compensate and the program is written as it came.
  auto saysNoErrors = [](const CompensateRun& r) {
    for (const std::string& w : r.compensation->warnings)
      if (w.find("carries no errors") != std::string::npos &&
          w.find("written as it came") != std::string::npos)
        return true;
    return false;
  };
  EXPECT_FALSE(saysNoErrors(run));
  in.machine = machine(kNominal);
  in.output = path("n.apt");
  const CompensateRun nominal = compensateProgram(in);
  ASSERT_TRUE(nominal.compensation);
  EXPECT_TRUE(saysNoErrors(nominal));
  in.output.clear();
  EXPECT_EQ(refusedField([&] { compensateProgram(in); }), "output");
}

// Programs are compensated block by block (issue 36): the same files as the whole program at
// once, byte for byte (the program, the joints), the same report (the band within 1e-3), on real CL
// programs with arcs, drilling cycles, '$' continuations, a multi-axis program whose first GOTOs
// give no axis, CRLF line ends and a byte-order mark, and on G-code in TCP mode, in inches with
// arcs (the block before an arc kept), a swivelled plane; on a calibrated machine with the set-up
// fitted, absolute and probed. Blocks of 97 points (G-code: 3): most statements, arcs and cycles
// meet a block's end somewhere.
TEST_F(Commands, CompensateInBlocksWritesWhatTheWholeProgramWrites) {
  // The cone with its first three GOTOs without a tool axis, CRLF line ends and a BOM.
  std::string cone_text = test::readText(sourcePath("samples/nas979_cone.apt"));
  {
    std::string edited = "\xEF\xBB\xBF";
    size_t at = 0;
    int shortened = 0;
    while (at < cone_text.size()) {
      size_t eol = cone_text.find('\n', at);
      if (eol == std::string::npos) eol = cone_text.size();
      std::string line = cone_text.substr(at, eol - at);
      if (line.rfind("GOTO/", 0) == 0 && shortened < 3) {
        size_t comma = 0;
        for (int k = 0; k < 3; ++k) comma = line.find(',', comma + 1);
        line.resize(comma);
        ++shortened;
      }
      edited += line + "\r\n";
      at = eol + 1;
    }
    std::ofstream(path("cone_crlf.apt"), std::ios::binary) << edited;
  }
  struct Case {
    const char* name;
    std::string cl;
    MachineOptions machine;
    bool absolute = false;
    std::string probed;
    std::string nc;  // G-code instead of cl
  };
  MachineOptions creo = machine(kMeasured, false);
  creo.part_zero = {0, 0, 100};
  creo.gauge_length = 100;
  // G-code: LinuxCNC's boat in TCP mode (M428), a posted inch program in joint words with arcs
  // and machine moves, a Sinumerik swivelled plane (CYCLE800); on machines with random errors.
  auto withErrors = [&](const char* file, unsigned seed) {
    MachineOptions m;
    m.machine = path(fs::path(file).stem().string() + "_errors.xml");
    test::writeMachineWithErrors(sourcePath(file), seed, m.machine);
    return m;
  };
  MachineOptions boat = withErrors("resources/machines/linuxcnc_xyzac_trt.xml", 5);
  boat.setup = sourcePath("samples/gcode/linuxcnc_setup.txt");
  MachineOptions umc = withErrors("resources/machines/umc_bc_trunnion.xml", 7);
  umc.gauge_length = 76.2;
  // A calibrated machine (its file carries the calibration's covariance): the set-up fitted to
  // the program's poses in a first pass, the band over every point.
  MachineOptions calibrated = machine(kNominal);
  calibrated.machine = path("id.xml");
  for (const std::string& cmd :
       {"plan-ballbar --machine " + sourcePath(kNominal) + " --poses 120 --seed 5 -o " +
            path("plan.csv"),
        "simulate-ballbar --machine " + sourcePath(kMeasured) + " --plan " + path("plan.csv") +
            " --noise-um 0.5 --seed 5 -o " + path("r.csv"),
        "calibrate --machine " + sourcePath(kNominal) + " --readings " + path("r.csv") + " -o " +
            path("id.xml")}) {
    const auto r = test::runTolver(cmd);
    ASSERT_EQ(r.exit_code, 0) << cmd << "\n" << r.output;
  }
  MachineOptions swivel = withErrors("resources/machines/sinumerik_bc_table.xml", 11);
  swivel.setup = path("swivel_setup.txt");
  std::ofstream(swivel.setup)
      << "part_zero_mm = 0, 0, 0\ng54_mm = -310, 0, 200\ngauge_length_mm = 100\n";
  std::ofstream(path("swivel.mpf"))
      << "N10 G54 G0 X0 Y0 Z80 B0 C0 D1\n"
         "N20 CYCLE800(1,\"TC1\",0,57,10,0,0,0,30,0,5,0,-3,1,100,1)\n"
         "N50 G0 X5 Y-15 Z40\nN60 G1 Z2 F500\nN70 X25.000 Y10.000\nN72 X25.000 Y-10.000\n"
         "N74 X5.000 Y-10.000\nN80 G0 Z40\nN90 CYCLE800()\nN100 G0 X0 Y0 Z80\n"
         "N110 G1 X10 Y10 Z60 B10 C20\nN120 X12 Y8\nN130 G2 X14 Y10 I1 J1\nN140 G1 X16\nM30\n";
  const std::vector<Case> cases = {
      {"cone", sourcePath("samples/nas979_cone.apt"), machine(kMeasured)},
      {"cone absolute", sourcePath("samples/nas979_cone.apt"), machine(kMeasured), true},
      {"cone probed", sourcePath("samples/nas979_cone.apt"), machine(kMeasured), false,
       sourcePath("samples/matsuura_probed.csv")},
      {"cone, CRLF, BOM, first GOTOs 3-axis", path("cone_crlf.apt"), machine(kMeasured)},
      {"SolidWorks CAM, drilling cycles", sourcePath("tests/fixtures/cl/swcam_basemach.apt"),
       machine(kMeasured)},
      {"Creo, arcs", sourcePath("tests/fixtures/cl/creo_profile_milling.ncl"), creo},
      {"nominal machine", sourcePath("samples/nas979_cone.apt"), machine(kNominal)},
      {"calibrated", sourcePath("samples/nas979_cone.apt"), calibrated},
      {"calibrated, absolute", sourcePath("samples/nas979_cone.apt"), calibrated, true},
      {"calibrated, probed", sourcePath("samples/nas979_cone.apt"), calibrated, false,
       sourcePath("samples/matsuura_probed.csv")},
      {"G-code, LinuxCNC TCP", "", boat, false, "", sourcePath("samples/gcode/boat-xyzac.ngc")},
      {"G-code, inch, joint words", "", umc, false, "", sourcePath("samples/gcode/umc_bc_inch.nc")},
      {"G-code, Sinumerik CYCLE800", "", swivel, false, "", path("swivel.mpf")},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    CompensateInputs in;
    in.machine = c.machine;
    in.program.cl = c.cl;
    in.program.nc = c.nc;
    in.absolute = c.absolute;
    in.probed = c.probed;
    const std::string ext = c.nc.empty() ? ".apt" : fs::path(c.nc).extension().string();
    in.output = path("whole" + ext);
    in.block_points = 0;
    const CompensateRun whole = compensateProgram(in);
    ASSERT_TRUE(whole.compensation);
    EXPECT_FALSE(whole.compensation->line.empty());  // the whole program in memory
    in.output = path("blocks" + ext);
    in.block_points = c.nc.empty() ? 97 : 3;
    in.report_dir = path("blocks_report");
    const CompensateRun blocks = compensateProgram(in);
    ASSERT_TRUE(blocks.compensation);
    EXPECT_TRUE(blocks.compensation->line.empty());  // streamed: no per-point arrays
    EXPECT_TRUE(fs::exists(path("blocks_report/report.html")));
    EXPECT_EQ(blocks.verdict, whole.verdict);
    EXPECT_EQ(blocks.worse_lines, whole.worse_lines);
    EXPECT_FALSE(fs::exists(path("blocks" + ext + ".points.tmp-tolver")));
    // The program and the joints, byte for byte.
    EXPECT_EQ(test::readText(path("blocks" + ext)), test::readText(path("whole" + ext)));
    EXPECT_EQ(test::readText(path("blocks_joints.csv")), test::readText(path("whole_joints.csv")));
    nlohmann::json a = nlohmann::json::parse(test::readText(path("whole.json")));
    nlohmann::json b = nlohmann::json::parse(test::readText(path("blocks.json")));
    EXPECT_EQ(a.contains("after_uncertainty"), b.contains("after_uncertainty"));
    EXPECT_EQ(b.contains("after_uncertainty"), c.machine.machine == calibrated.machine);
    if (a.contains("after_uncertainty")) {
      for (const char* k : {"band95_max_um", "band95_median_um", "axis_band95_max_urad",
                            "axis_band95_median_urad"}) {
        const double x = a["after_uncertainty"][k].get<double>();
        const double y = b["after_uncertainty"][k].get<double>();
        // The band is taken modulo the set-up over the program's evenly spaced poses: in blocks
        // the poses before compensation (the first pass), whole those after it, micro-radians
        // apart: 1e-4 of the band (0.05 nm here).
        EXPECT_NEAR(x, y, 1e-3 * x) << k;
      }
      a.erase("after_uncertainty");
      b.erase("after_uncertainty");
    }
    for (const char* k : {"output", "joints_file"}) {
      a.erase(k);
      b.erase(k);
    }
    EXPECT_EQ(a, b) << a.dump(1) << "\n" << b.dump(1);
    EXPECT_GT(b["points"].get<int>(), 3 * in.block_points);
  }
}

// An error found after blocks were written (a malformed number, a point out of travel near the
// end) leaves nothing: no program, report, joints, temporary or spooled records.
TEST_F(Commands, CompensateInBlocksLeavesNothingWhenALaterBlockFails) {
  const std::string cone = test::readText(sourcePath("samples/nas979_cone.apt"));
  const std::string body = cone.substr(0, cone.rfind("FINI"));
  const std::pair<std::string, std::string> cases[] = {
      {"GOTO/1,2,abc,0,0,1\n", "expected a number"},
      {"GOTO/0,0,-900,0,0,1\n", "unreachable"},
  };
  for (const auto& [bad, says] : cases) {
    SCOPED_TRACE(says);
    std::ofstream(path("late.apt")) << body << body << bad << "FINI\n";
    CompensateInputs in;
    in.machine = machine(kMeasured);
    in.program.cl = path("late.apt");
    in.output = path("out/late_c.apt");
    in.block_points = 100;
    fs::create_directories(path("out"));
    try {
      compensateProgram(in);
      ADD_FAILURE() << "accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(says), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("late.apt:"), std::string::npos) << e.what();
    }
    EXPECT_TRUE(fs::is_empty(path("out")));
  }
}

// verifyPart's verdict is the report's, and report.json's exit code is the verdict's.
TEST_F(Commands, VerifyVerdictIsTheReportsAndItsExitCode) {
  VerifyInputs in;
  in.machine = machine(kMeasured);
  in.program.cl = sourcePath("samples/sculptured_finish.apt");
  in.part = sourcePath("samples/sculptured_part.obj");
  in.spacing_mm = 1.5;
  in.images = false;
  for (double t : {0.002, 0.5}) {
    in.tolerance_mm = t;
    in.report_dir = path("t" + std::to_string(static_cast<int>(t * 1000)));
    const VerifyRun run = verifyPart(in);
    std::ifstream f(fs::path(in.report_dir) / "report.json");
    const nlohmann::json j = nlohmann::json::parse(f);
    EXPECT_EQ(j["exit_code"], exitCode(run.verdict));
    EXPECT_EQ(run.verdict, t < 0.01 ? Verdict::NotMet : Verdict::Ok) << j["verdict"];
    EXPECT_EQ(j["verdict"], t < 0.01 ? "fail" : "pass");
  }
  in.tolerance_mm = NAN;
  EXPECT_EQ(refusedField([&] { verifyPart(in); }), "tolerance_mm");
}

// A batch's verdict is its worst job's; a job with bad input is reported, the others still run.
TEST_F(Commands, VerifyBatchTakesTheWorstJob) {
  VerifyInputs base;
  base.spacing_mm = 1.5;
  base.images = false;
  base.report_dir = path("batch");
  const BatchRun run = verifyBatch(base, sourcePath("samples/verify_jobs.csv"));
  ASSERT_FALSE(run.jobs.empty());
  Verdict worst = Verdict::Ok;
  for (const JobOutcome& j : run.jobs) worst = worse(worst, j.verdict);
  EXPECT_EQ(run.verdict, worst);
  EXPECT_TRUE(fs::exists(run.summary));

  std::ofstream(path("jobs.csv"))
      << "name,machine,cl,part,tolerance\nbad,nowhere.xml,nothing.apt,,0.05\n";
  const BatchRun bad = verifyBatch(base, path("jobs.csv"));
  ASSERT_EQ(bad.jobs.size(), 1u);
  EXPECT_EQ(bad.verdict, Verdict::BadInput);
  EXPECT_EQ(exitCode(bad.verdict), 2);
  EXPECT_FALSE(bad.jobs[0].error.empty());
}

// Allocation on the XKH800: the standard tolerances break the limits and no tightening is
// allowed, so nothing meets them (NotMet); allowing tighter tolerances finds one that does.
TEST_F(Commands, AllocateMeetsTheLimitsOrSaysItCannot) {
  AllocateInputs in;
  in.machine.machine = sourcePath("resources/machines/xkh800.xml");
  in.machine.gauge_length = 150;
  in.tolerances = sourcePath("resources/allocation/xkh800_standard.csv");
  in.opt.generations = 40;
  in.report_dir = path("a");
  const AllocationRun none = allocate(in);
  EXPECT_EQ(none.verdict, Verdict::NotMet);
  in.lower_factor = 0.25;
  in.report_dir = path("b");
  const AllocationRun run = allocate(in);
  ASSERT_EQ(run.verdict, Verdict::Ok);
  const AllocationSolution& c = run.result.front[run.result.chosen];
  for (int k = 0; k < 3; ++k) EXPECT_LE(c.worst_exact[k], in.limits_mm[k] * (1 + 1e-9));
  EXPECT_TRUE(fs::exists(path("b/report.json")));
  in.limits_mm = {0.01, 0.01};
  EXPECT_EQ(refusedField([&] { allocate(in); }), "limits_mm");
}

// The verdict's exit codes, and the worse of two.
TEST(Verdicts, ExitCodesAndOrder) {
  EXPECT_EQ(exitCode(Verdict::Ok), 0);
  EXPECT_EQ(exitCode(Verdict::NotMet), 1);
  EXPECT_EQ(exitCode(Verdict::BadInput), 2);
  EXPECT_EQ(exitCode(Verdict::Undecided), 4);
  EXPECT_EQ(worse(Verdict::Ok, Verdict::Undecided), Verdict::Undecided);
  EXPECT_EQ(worse(Verdict::NotMet, Verdict::Undecided), Verdict::NotMet);
  EXPECT_EQ(worse(Verdict::NotMet, Verdict::BadInput), Verdict::BadInput);
}

}  // namespace
}  // namespace tolver
