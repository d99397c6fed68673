#include "pipeline/predict.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <limits>

#include "core/numerics/statistics.h"
#include "core/numerics/units.h"
#include "io/common/io_error.h"
#include "io/program/apt_writer.h"
#include "io/program/point_table.h"
#include "pipeline/block_predictor.h"
#include "pipeline/parallel_prediction.h"

namespace tolver {

namespace {

// The band over the program's points, block by block.
class BandTally {
 public:
  explicit BandTally(size_t axes) { band_.beyond.assign(axes, 0.0); }
  void add(const ClProgram& block, const std::vector<PoseUncertainty>& unc) {
    for (size_t i = 0; i < unc.size(); ++i) {
      const PoseUncertainty& u = unc[i];
      tip_.add(u.tip);
      axis_.add(u.axis);
      cal_tip_.add(u.calibration_tip);
      cal_axis_.add(u.calibration_axis);
      band_.tip_max = std::max(band_.tip_max, u.tip);
      band_.axis_max = std::max(band_.axis_max, u.axis);
      if (!u.outside) continue;
      if (band_.outside++ == 0) band_.first_outside_line = block.path[i].line;
      for (size_t a = 0; a < band_.beyond.size() && a < static_cast<size_t>(u.beyond.size()); ++a)
        band_.beyond[a] = std::max(band_.beyond[a], u.beyond[a]);
    }
  }
  BandSummary finish() {
    const size_t mid = tip_.count() / 2;
    if (tip_.count() > 0) {
      band_.tip_median = tip_.ranked(mid);
      band_.axis_median = axis_.ranked(mid);
      band_.calibration_tip_median = cal_tip_.ranked(mid);
      band_.calibration_axis_median = cal_axis_.ranked(mid);
    }
    return band_;
  }

 private:
  BandSummary band_;
  StreamQuantiles tip_, axis_, cal_tip_, cal_axis_;
};

}  // namespace

PredictionRun predict(const PredictInputs& in, const Progress& progress) {
  PredictionRun run;
  run.machine = loadMachine(in.machine);
  run.output = in.output;
  if (!in.no_point_table)
    run.point_table = in.point_table.empty() ? replaceExtension(in.output, ".csv") : in.point_table;
  checkOutputDir(run.output, "output");
  if (!run.point_table.empty()) checkOutputDir(run.point_table, "point_table");
  Machine& machine = run.machine;
  const MachineModel& model = machine.model;
  ProgramBlocks blocks;
  blocks.points = std::max<size_t>(1, in.block_points);
  auto told = [&](const char* phase) {
    return [&progress, phase](double f) {
      if (progress) progress(phase, f);
    };
  };
  auto unreachable = [&](const ClProgram& program, const PredictionResult& r) {
    if (!r.ok())
      throw InputError(program.file, r.failures.front().line, 0, "unreachable",
                       describeUnreachable(model, r));
  };

  // A calibrated machine: after the set-up a shop measures (unless absolute), with each point's
  // uncertainty; the set-up is fitted to the program's evenly spaced poses, read in a first pass.
  const std::vector<ProbedPoint> probed = loadProbed(in.probed, model);
  std::unique_ptr<PredictionUncertainty> pu;
  if (!probed.empty()) {
    run.calibration.probed = true;
    run.calibration.probe = fitProbedSetup(machine, probed);
    if (!machine.identification.empty()) {
      pu = std::make_unique<PredictionUncertainty>(machine);
      pu->setupModuloProbed(probed);
    }
  } else if (!machine.identification.empty()) {
    EvenPoses even;
    if (!in.absolute) {
      run.passes = 2;
      BlockPredictor first(machine);
      PredictedPoints pts;
      const ClProgram program =
          streamProgram(in.program, model,
                        ProgramBlocks{blocks.points,
                                      [&](ClProgram& block, bool last) {
                                        first.predict(block, last, pts);
                                        for (size_t i = 0; i < pts.size(); ++i) {
                                          const size_t at = block.first_point + i;
                                          if (even.wants(at))
                                            even.add(at, pts[i].q, pts[i].deviation_w);
                                        }
                                      }},
                        told("fitting the measured set-up"));
      unreachable(program, first.result());
      run.calibration.measured_setup =
          applyMeasuredSetup(machine, even.q, even.deviation_w, even.q.size());
    }
    pu = std::make_unique<PredictionUncertainty>(machine);
    if (!in.absolute) pu->setupModulo(even.q);
  }
  if (run.calibration.probed)
    run.probe_line = describeProbedSetup(in.probed, run.calibration.probe, probed, &run.warnings);

  std::unique_ptr<tbb::enumerable_thread_specific<PredictionUncertainty>> per_thread;
  if (pu)
    per_thread = std::make_unique<tbb::enumerable_thread_specific<PredictionUncertainty>>(*pu);
  OutputSet outputs;  // both files, or neither
  TextOut& cl_out = outputs.open(run.output);
  TextOut* table_out = run.point_table.empty() ? nullptr : &outputs.open(run.point_table);
  BlockPredictor predictor(machine);
  PredictedPoints pts;
  std::vector<ClPoint> predicted;
  std::vector<PoseUncertainty> unc;
  BandTally band(model.axes.size());
  RotaryJumpFinder jumps(model, degToRad(in.max_rotary_step_deg));
  ProgramNotes notes;
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d hi = -lo;
  bool started = false;
  blocks.sink = [&](ClProgram& block, bool last) {
    if (!started) {
      writePredictedAptStart(
          cl_out, block,
          {"tolver predicted CL: " + block.file + " on " + model.name + " (" + in.machine.machine +
               ")",
           "each GOTO is the tool position the machine will really reach, in the program's "
           "frame"});
      if (table_out) writePointTableHeader(*table_out, model, pu != nullptr);
      started = true;
    }
    predictor.predict(block, last, pts);
    const size_t n = block.path.size();
    predicted.resize(n);
    for (size_t i = 0; i < n; ++i) {
      predicted[i] = block.path[i];
      predicted[i].p_w = Eigen::Vector3d(pts.field(PredictedPoints::kTipX)[i],
                                         pts.field(PredictedPoints::kTipY)[i],
                                         pts.field(PredictedPoints::kTipZ)[i]);
      predicted[i].u_w = Eigen::Vector3d(pts.field(PredictedPoints::kAxisX)[i],
                                         pts.field(PredictedPoints::kAxisY)[i],
                                         pts.field(PredictedPoints::kAxisZ)[i]);
      lo = lo.cwiseMin(block.path[i].p_w);
      hi = hi.cwiseMax(block.path[i].p_w);
    }
    writePredictedAptStatements(cl_out, block, predicted);
    if (pu) {
      // Each point's band on the cores (a copy of the uncertainty's work matrix per thread; the
      // points are independent, the result the same on any number of threads).
      unc.resize(n);
      tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 256),
                        [&](const tbb::blocked_range<size_t>& r) {
                          const PredictionUncertainty& u = per_thread->local();
                          JointVector q(pts.axes());
                          for (size_t i = r.begin(); i < r.end(); ++i) {
                            for (int a = 0; a < pts.axes(); ++a) q[a] = pts.q(a)[i];
                            unc[i] = u.at(q);
                          }
                        });
      band.add(block, unc);
    }
    if (table_out)
      writePointTableRows(*table_out, model, block.path, pts, pu ? &unc : nullptr,
                          block.first_point);
    jumps.add(block.path, pts, block.first_point);
    notes.add(block);
    if (last) writePredictedAptEnd(cl_out, block);
  };
  run.program = streamProgram(in.program, model, blocks, told("predicting"));
  run.prediction = predictor.takeResult();
  unreachable(run.program, run.prediction);
  outputs.commit();

  run.worst = predictor.worst();
  if (pu) {
    run.band = band.finish();
    run.has_band = true;
  }
  for (int i = 0; i < machine.params.size(); ++i)
    run.nonzero_parameters += machine.params[i] != 0.0;
  bool no_errors = false;
  run.errors_statement = machineErrorsStatement(machine, &no_errors);
  run.jumps = std::move(jumps.jumps);
  for (const std::string& w : setupWarnings(model)) run.warnings.push_back(w);
  if (run.program.pointsRead() > 0)
    for (const std::string& w : unitWarnings(run.program, model, in.program.units, lo, hi))
      run.warnings.push_back(w);
  for (const std::string& w : notes.notes(run.program))
    run.notes.push_back(run.program.file + ": " + w);
  return run;
}

}  // namespace tolver
