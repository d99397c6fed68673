// tolver predict reads, predicts and writes a program block by block (its memory independent of
// the program's length). Its files are those the whole program makes, byte for byte: read at once
// (loadProgram), predicted at once, written by the whole-program writers, on real CL and G-code
// programs from several CAM systems and machines with errors, for blocks of any size (one
// statement, fewer points than BlockPrediction::kExactEvery, more), with --lines, and on a
// calibrated machine (two passes: the measured set-up first, then each point's band).
#include <gtest/gtest.h>

#include <random>

#include "io/common/io_error.h"
#include "io/machine/machine_file.h"
#include "io/program/apt_writer.h"
#include "io/program/point_table.h"
#include "pipeline/ballbar.h"
#include "pipeline/calibrate.h"
#include "pipeline/predict.h"
#include "test_support.h"

namespace tolver {
namespace {

using test::sourcePath;

class PredictStream : public test::TempDirTest {
 protected:
  // The machine file with random errors of a real machine's size, written beside the outputs.
  std::string withErrors(const std::string& file, unsigned seed) {
    Machine m = readMachineFile(sourcePath(file));
    std::mt19937 rng(seed);
    std::normal_distribution<double> n(0.0, 1.0);
    for (int i = 0; i < m.model.parameterCount(); ++i)
      m.params[i] = n(rng) * (m.model.parameters[i].angular ? 20e-6 : 0.005);
    const std::string out = path("machine_" + std::to_string(seed) + ".xml");
    writeFileAtomically(out, formatMachineXml(m, "random errors for a test"));
    return out;
  }

  // What the whole program makes: read at once, predicted at once, the whole-program writers.
  std::pair<std::string, std::string> whole(const PredictInputs& in) {
    Machine machine = loadMachine(in.machine);
    const ClProgram program = loadProgram(in.program, machine.model);
    PredictionResult r = predictProgram(machine, program);
    const CalibratedPrediction cal = applyCalibration(machine, program, r, in.absolute);
    std::vector<ClPoint> predicted(program.path.size());
    for (size_t i = 0; i < predicted.size(); ++i) {
      predicted[i] = program.path[i];
      predicted[i].p_w = r.points[i].p_pred_w;
      predicted[i].u_w = r.points[i].u_pred_w;
    }
    const std::vector<std::string> header = {
        "tolver predicted CL: " + program.file + " on " + machine.model.name + " (" +
            in.machine.machine + ")",
        "each GOTO is the tool position the machine will really reach, in the program's frame"};
    return {formatPredictedApt(program, predicted, header),
            formatPointTable(machine.model, program.path, r.points,
                             cal.uncertainty.empty() ? nullptr : &cal.uncertainty)};
  }

  // predict() in blocks of each size writes the whole program's files.
  void expectBlocksMakeTheWhole(PredictInputs in, const std::vector<size_t>& sizes,
                                const std::string& what) {
    const auto [cl, table] = whole(in);
    ASSERT_GT(cl.size(), 100u) << what;
    for (size_t size : sizes) {
      in.block_points = size;
      in.output = path("p.apt");
      const PredictionRun run = predict(in);
      const std::string where = what + ", blocks of " + std::to_string(size);
      EXPECT_TRUE(readFile(path("p.apt")) == cl) << where;
      EXPECT_TRUE(readFile(path("p.csv")) == table) << where;
      EXPECT_EQ(run.program.pointsRead(), static_cast<size_t>(run.prediction.summary.points))
          << where;
      // The worst point printed is the summary's.
      EXPECT_GT(run.prediction.summary.max_line, 0) << where;
      EXPECT_DOUBLE_EQ(run.worst.deviation_w.norm(), run.prediction.summary.max_deviation) << where;
    }
  }
};

TEST_F(PredictStream, BlocksOfAnySizeWriteTheWholeProgramsFiles) {
  const size_t e = BlockPrediction::kExactEvery;
  const std::string matsuura = withErrors("resources/machines/matsuura_mc760vx.xml", 1);
  struct Case {
    std::string machine, program, setup;
    bool gcode;
    double gauge;
  };
  const std::vector<Case> cases = {
      {matsuura, "samples/sculptured_finish.apt", "samples/matsuura_setup.txt", false, NAN},
      {matsuura, "tests/fixtures/cl/creo_drilling.ncl", "samples/matsuura_setup.txt", false, NAN},
      {matsuura, "tests/fixtures/cl/nx_cutcom.clsf", "samples/matsuura_setup.txt", false, NAN},
      {matsuura, "tests/fixtures/cl/swcam_Interface-glue.apt", "samples/matsuura_setup.txt", false,
       NAN},
      {withErrors("resources/machines/umc_bc_trunnion.xml", 2), "samples/gcode/umc_bc_inch.nc", "",
       true, 76.2},
      {withErrors("resources/machines/linuxcnc_xyzac_trt.xml", 3), "samples/gcode/boat-xyzac.ngc",
       "samples/gcode/linuxcnc_setup.txt", true, NAN},
      {withErrors("resources/machines/sinumerik_bc_table.xml", 4),
       "tests/fixtures/gcode/nx_sin840d_Keychain.mpf", "", true, NAN},
  };
  for (const Case& c : cases) {
    PredictInputs in;
    in.machine.machine = c.machine;
    if (!c.setup.empty()) in.machine.setup = sourcePath(c.setup);
    in.machine.gauge_length = c.gauge;
    (c.gcode ? in.program.nc : in.program.cl) = sourcePath(c.program);
    // (blocks of one statement on the short programs: each re-predicts the tail before it)
    std::vector<size_t> sizes = {size_t{1} << 30, 3 * e + 5, e, 1000};
    if (c.gcode) sizes.push_back(1);
    expectBlocksMakeTheWhole(in, sizes, c.program);
  }
  // --lines: the range kept block by block.
  PredictInputs in;
  in.machine.machine = matsuura;
  in.machine.setup = sourcePath("samples/matsuura_setup.txt");
  in.program.cl = sourcePath("samples/sculptured_finish.apt");
  in.program.lines = "2000-7500";
  expectBlocksMakeTheWhole(in, {size_t{1} << 30, 1000}, "sculptured_finish.apt, --lines");
  // Without the table: the predicted CL alone, the same bytes.
  in.program.lines.clear();
  in.no_point_table = true;
  in.block_points = 1000;
  in.output = path("alone.apt");
  const PredictionRun run = predict(in);
  EXPECT_TRUE(run.point_table.empty());
  EXPECT_FALSE(std::filesystem::exists(path("alone.csv")));
  EXPECT_TRUE(readFile(path("alone.apt")) == whole(in).first);
}

// A program the machine cannot reach in a later block: nothing written, the first failing line
// named with the whole program's count.
TEST_F(PredictStream, AFailureInALaterBlockWritesNothing) {
  std::string text = "UNITS/MM\nMULTAX/ON\n";
  for (int i = 0; i < 5000; ++i)
    text += "GOTO/" + std::to_string(-20.0 + 0.008 * i) + ",0,0,0,0,1\n";
  text += "GOTO/5000,0,0,0,0,1\nGOTO/0,0,0,0,0,1\nFINI\n";
  PredictInputs in;
  in.machine.machine = sourcePath("resources/machines/matsuura_mc760vx.xml");
  in.machine.setup = sourcePath("samples/matsuura_setup.txt");
  in.program.cl = write("far.apt", text);
  in.output = path("far_pred.apt");
  in.block_points = 1000;
  try {
    predict(in);
    ADD_FAILURE() << "not refused";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("far.apt:5003"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("beyond its travel"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(std::filesystem::exists(path("far_pred.apt")));
  EXPECT_FALSE(std::filesystem::exists(path("far_pred.csv")));
  for (const auto& f : std::filesystem::directory_iterator(dir_))
    EXPECT_EQ(f.path().string().find("tmp-tolver"), std::string::npos) << f.path();
}

// A calibrated machine: the measured set-up fitted in a first pass over the program's evenly
// spaced poses, then each point's band, the same as the whole program's (applyCalibration).
TEST_F(PredictStream, ACalibratedMachineInBlocksIsTheWholeProgramsPrediction) {
  PlanBallbarInputs plan;
  plan.machine.machine = sourcePath("resources/machines/matsuura_mc760vx.xml");
  plan.plan.poses = 360;
  plan.plan.seed = 5;
  plan.output = path("plan.csv");
  planBallbar(plan);
  SimulateBallbarInputs sim;
  sim.machine.machine = sourcePath("samples/machines/matsuura_mc760vx_measured.xml");
  sim.plan = path("plan.csv");
  sim.noise_um = 0.5;
  sim.output = path("r.csv");
  simulateBallbar(sim);
  CalibrateInputs cal;
  cal.machine.machine = plan.machine.machine;
  cal.readings = path("r.csv");
  cal.output = path("id.xml");
  calibrateMachine(cal);

  PredictInputs in;
  in.machine.machine = path("id.xml");
  in.machine.setup = sourcePath("samples/matsuura_setup.txt");
  in.program.cl = sourcePath("samples/sculptured_finish.apt");
  expectBlocksMakeTheWhole(in, {size_t{1} << 30, 1000}, "calibrated");
  in.block_points = 1000;
  in.output = path("q.apt");
  const PredictionRun run = predict(in);
  EXPECT_EQ(run.passes, 2);
  ASSERT_TRUE(run.has_band);
  EXPECT_EQ(run.calibration.measured_setup.size(), 9);
  EXPECT_GT(run.band.tip_median, 0.0);
  EXPECT_LE(run.band.tip_median, run.band.tip_max);
  in.absolute = true;
  expectBlocksMakeTheWhole(in, {1000}, "calibrated, absolute");
}

}  // namespace
}  // namespace tolver
