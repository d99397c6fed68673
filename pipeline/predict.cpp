#include "pipeline/predict.h"

#include "core/numerics/units.h"
#include "io/common/io_error.h"
#include "io/program/apt_writer.h"
#include "io/program/point_table.h"

namespace tolver {

PredictionRun predict(const PredictInputs& in) {
  PredictionRun run;
  run.machine = loadMachine(in.machine);
  run.program = loadProgram(in.program, run.machine.model);
  run.output = in.output;
  run.point_table = in.point_table.empty() ? replaceExtension(in.output, ".csv") : in.point_table;
  checkOutputDir(run.output, "output");
  checkOutputDir(run.point_table, "point_table");
  const Machine& machine = run.machine;
  const ClProgram& program = run.program;

  run.prediction = predictProgram(machine, program);
  // A calibrated machine: after the set-up a shop measures (unless absolute), with each point's
  // uncertainty.
  const std::vector<ProbedPoint> probed = loadProbed(in.probed, machine.model);
  run.calibration = applyCalibration(run.machine, program, run.prediction, in.absolute, probed);
  if (run.calibration.probed)
    run.probe_line = describeProbedSetup(in.probed, run.calibration.probe, probed, &run.warnings);
  const std::vector<PoseUncertainty>& unc = run.calibration.uncertainty;

  std::vector<ClPoint> predicted(program.path.size());
  const PredictedPoints& pts = run.prediction.points;
  for (size_t i = 0; i < predicted.size(); ++i) {
    predicted[i] = program.path[i];
    predicted[i].p_w = pts[i].p_pred_w;
    predicted[i].u_w = pts[i].u_pred_w;
  }
  const std::vector<std::string> header = {
      "tolver predicted CL: " + program.file + " on " + machine.model.name + " (" +
          in.machine.machine + ")",
      "each GOTO is the tool position the machine will really reach, in the program's frame"};
  OutputSet outputs;  // both files, or neither
  // Written as they are made: a long program's outputs never sit whole in memory.
  outputs.addStreamed(run.output,
                      [&](TextOut& out) { writePredictedApt(out, program, predicted, header); });
  // The prediction's uncertainty, when the machine file carries its calibration's covariance.
  outputs.addStreamed(run.point_table, [&](TextOut& out) {
    writePointTable(out, machine.model, program.path, pts, unc.empty() ? nullptr : &unc);
  });
  outputs.commit();

  for (int i = 0; i < machine.params.size(); ++i)
    run.nonzero_parameters += machine.params[i] != 0.0;
  bool no_errors = false;
  run.errors_statement = machineErrorsStatement(machine, &no_errors);
  run.jumps = findRotaryJumps(machine.model, program.path, run.prediction,
                              degToRad(in.max_rotary_step_deg));
  for (const std::string& w : setupWarnings(machine.model)) run.warnings.push_back(w);
  for (const std::string& w : unitWarnings(program, machine.model, in.program.units))
    run.warnings.push_back(w);
  for (const std::string& w : programNotes(program)) run.notes.push_back(program.file + ": " + w);
  return run;
}

}  // namespace tolver
