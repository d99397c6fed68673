// tolver predict: CL_predicted of a part program on a machine with errors ([AM01] 5.5.1-5.5.3).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>

#include "app/commands.h"
#include "app/common.h"
#include "io/common/text_util.h"
#include "core/path/prediction_uncertainty.h"
#include "core/path/tool_path_prediction.h"
#include "geometry/cutter.h"
#include "io/program/apt_reader.h"
#include "io/program/apt_writer.h"
#include "io/common/io_error.h"
#include "io/program/point_table.h"
#include "core/numerics/units.h"

namespace tolver::app {
namespace {

struct PredictOptions {
  MachineOptions machine;
  ProgramOptions program;
  std::string output, table;
  double max_rotary_step_deg = 10.0;
  bool absolute = false;
  std::string probed;
};

// Rounds away "-0.000" in printed figures.
double clean(double v) { return std::abs(v) < 5e-7 ? 0.0 : v; }

// The prediction's uncertainty on a calibrated machine: the set-up it is taken after, the 1-sigma
// band, and the points beyond the calibrated ranges.
void printUncertainty(const Machine& machine, const ClProgram& program, const CalibratedPrediction& cal) {
  const std::vector<PoseUncertainty>& unc = cal.uncertainty;
  const Eigen::VectorXd& measured_setup = cal.measured_setup;
  std::vector<double> tip(unc.size()), axis(unc.size());
  int outside = 0, first_outside = -1;
  std::vector<double> beyond(machine.model.axes.size(), 0.0);
  for (size_t i = 0; i < unc.size(); ++i) {
    tip[i] = unc[i].tip;
    axis[i] = unc[i].axis;
    if (unc[i].outside) {
      if (outside++ == 0) first_outside = static_cast<int>(i);
      for (size_t a = 0; a < beyond.size() && a < static_cast<size_t>(unc[i].beyond.size()); ++a)
        beyond[a] = std::max(beyond[a], unc[i].beyond[a]);
    }
  }
  auto median = [](std::vector<double> v) {
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    return v[v.size() / 2];
  };
  if (cal.probed)
    std::printf("  set-up     probed: the calibration cannot see the part's pose on the table; "
                "predicted with the set-up fitted to the probed points, uncertainty included\n");
  else if (measured_setup.size() == 9)
    std::printf("  set-up     the calibration cannot see the part's pose on the table or the tool "
                "tip's offset from the spindle: predicted after the set-up a shop measures (part "
                "probed: %+.2f %+.2f %+.2f um, %+.1f %+.1f %+.1f urad; tool preset: %+.2f %+.2f "
                "%+.2f um taken up); --absolute for the raw prediction\n",
                mmToUm(measured_setup[0]), mmToUm(measured_setup[1]), mmToUm(measured_setup[2]),
                radToUrad(measured_setup[3]), radToUrad(measured_setup[4]), radToUrad(measured_setup[5]),
                mmToUm(measured_setup[6]), mmToUm(measured_setup[7]), mmToUm(measured_setup[8]));
  else
    std::printf("  set-up     absolute prediction (--absolute): it includes what probing the part "
                "and presetting the tool would take up, which the calibration cannot see\n");
  std::printf("  uncertainty (1 sigma) of the prediction (%zu identified values and what their "
              "covariance does not hold, below): tip median %.3f um, max %.3f um; tool axis median %.3f urad, "
              "max %.3f urad\n",
              machine.identification.parameters.size(), mmToUm(median(tip)),
              mmToUm(*std::max_element(tip.begin(), tip.end())), radToUrad(median(axis)),
              radToUrad(*std::max_element(axis.begin(), axis.end())));
  // Which parts of the band come from where.
  const IdentificationUncertainty& id = machine.identification;
  std::vector<double> cal_tip(unc.size()), cal_axis(unc.size());
  for (size_t i = 0; i < unc.size(); ++i) {
    cal_tip[i] = unc[i].calibration_tip;
    cal_axis[i] = unc[i].calibration_axis;
  }
  std::printf("  band from  the covariance (tip median %.3f um, axis median %.3f urad); %s; %s\n",
              mmToUm(median(cal_tip)), radToUrad(median(cal_axis)),
              id.lack_of_fit_mm > 0 ? ("the calibration's lack of fit, " + formatWith("%.3f um", mmToUm(id.lack_of_fit_mm)) +
                                       " per tip coordinate").c_str()
                                    : "no lack of fit (the calibration's test passed, or it had no repeats)",
              id.spindle_tilt_rad > 0
                  ? ("the spindle tilt's prior, " + formatWith("%.1f urad", id.spindle_tilt_rad * 1e6) + " on the axis").c_str()
                  : "the spindle's tilt, which a ball-bar cannot see, is not in the axis band (calibrate "
                    "--spindle-tilt-urad states its prior; a tram measures it)");
  if (outside > 0) {
    std::string where;
    char buf[96];
    for (size_t a = 0; a < beyond.size(); ++a)
      if (beyond[a] > 0) {
        const bool rot = machine.model.axes[a].isRotary();
        std::snprintf(buf, sizeof buf, "%s%s by up to %.3f %s", where.empty() ? "" : ", ",
                      machine.model.axes[a].name.c_str(), beyond[a] * (rot ? radToDeg(1.0) : 1.0),
                      rot ? "deg" : "mm");
        where += buf;
      }
    std::printf("  calibrated %d points lie outside the joint ranges the calibration readings "
                "covered (first at line %d; %s): there the errors are extrapolated\n",
                outside, program.path[first_outside].line, where.c_str());
  }
}

// Singular points and large rotary steps between cutting moves.
void printRisks(const Machine& machine, const ClProgram& program, const PredictionResult& r,
                double max_rotary_step_deg) {
  const PredictionSummary& s = r.summary;
  if (s.singular_points > 0)
    std::printf("  note       %d points have the tool axis within %.4g deg of a rotary axis (first "
                "at line %d); that axis kept its previous angle\n",
                s.singular_points, radToDeg(machine.model.control.singular_band),
                s.first_singular_line);
  const auto jumps = findRotaryJumps(machine.model, program.path, r,
                                     degToRad(max_rotary_step_deg));
  if (!jumps.empty()) {
    std::printf("  risk       %zu rotary steps above %.1f deg between cutting moves:", jumps.size(),
                max_rotary_step_deg);
    for (size_t k = 0; k < jumps.size() && k < 5; ++k)
      std::printf("%s line %d %s %+.1f deg", k ? "," : "", jumps[k].line,
                  machine.model.axes[jumps[k].axis].name.c_str(), radToDeg(jumps[k].step));
    std::printf("%s\n", jumps.size() > 5 ? ", ..." : "");
  }
}

void printWarnings(const Machine& machine, const ClProgram& program, const std::vector<std::string>& probe_warnings,
                   const std::string& units_option) {
  for (const std::string& w : probe_warnings) std::fprintf(stderr, "tolver: warning: %s\n", w.c_str());
  for (const std::string& w : setupWarnings(machine.model))
    std::fprintf(stderr, "tolver: warning: %s\n", w.c_str());
  for (const std::string& w : unitWarnings(program, machine.model, units_option))
    std::fprintf(stderr, "tolver: warning: %s\n", w.c_str());
  for (const std::string& w : programNotes(program))
    std::fprintf(stderr, "tolver: note: %s: %s\n", program.file.c_str(), w.c_str());
}

void runPredict(const PredictOptions& o, int* exit_code) {
  Machine machine = loadMachine(o.machine);
  const PartSetup& setup = machine.model.setup;
  const ClProgram program = loadProgram(o.program, machine.model);
  const std::string table = o.table.empty() ? replaceExtension(o.output, ".csv") : o.table;
  checkOutputDir(o.output, "-o");
  checkOutputDir(table, "--errors");

  PredictionResult r = predictProgram(machine, program);
  // A calibrated machine: after the set-up a shop measures (unless --absolute), with each
  // point's uncertainty.
  const std::vector<ProbedPoint> probed = loadProbed(o.probed, machine.model);
  const CalibratedPrediction cal = applyCalibration(machine, program, r, o.absolute, probed);
  std::vector<std::string> probe_warnings;
  const std::string probe_line =
      cal.probed ? describeProbedSetup(o.probed, cal.probe, probed, &probe_warnings) : "";
  const std::vector<PoseUncertainty>& unc = cal.uncertainty;

  std::vector<ClPoint> predicted(program.path.size());
  const PredictedPoints& pts = r.points;
  for (size_t i = 0; i < predicted.size(); ++i) {
    predicted[i] = program.path[i];
    predicted[i].p_w = pts[i].p_pred_w;
    predicted[i].u_w = pts[i].u_pred_w;
  }
  const std::vector<std::string> header = {
      "tolver predicted CL: " + program.file + " on " + machine.model.name + " (" +
          o.machine.machine + ")",
      "each GOTO is the tool position the machine will really reach, in the program's frame"};
  OutputSet outputs;  // both files, or neither
  // Written as they are made: a long program's outputs never sit whole in memory.
  outputs.addStreamed(o.output, [&](TextOut& out) { writePredictedApt(out, program, predicted, header); });
  // The prediction's uncertainty, when the machine file carries its calibration's covariance.
  outputs.addStreamed(table, [&](TextOut& out) {
    writePointTable(out, machine.model, program.path, pts, unc.empty() ? nullptr : &unc);
  });
  outputs.commit();

  // Summary.
  const PredictionSummary& s = r.summary;
  int nonzero = 0;
  for (int i = 0; i < machine.params.size(); ++i) nonzero += machine.params[i] != 0.0;
  std::printf("tolver predict\n");
  std::printf("  machine    %s (%s): %zu axes, %d error parameters, %d non-zero\n",
              machine.model.name.c_str(), o.machine.machine.c_str(), machine.model.axes.size(),
              machine.model.parameterCount(), nonzero);
  bool no_errors = false;
  const std::string errors = machineErrorsStatement(machine, &no_errors);
  std::printf("             %s\n", errors.c_str());
  std::printf("  program    %s (%s): %d tool positions (%d arcs expanded), units %s%s\n",
              program.file.c_str(), program.dialect.c_str(), s.points, program.arcs_expanded,
              program.units.c_str(), program.units_declared ? "" : " (assumed)");
  Cutter cutter;
  if (!program.cutters.empty() &&
      cutterFromApt(program.cutters.back().source, program.cutters.back().values, &cutter))
    std::printf("  tool       %s (line %d)\n", cutter.describe().c_str(),
                program.cutters.back().line);
  std::printf("  set-up     part zero (%.4f, %.4f, %.4f) mm in the table frame, rotation %.4f deg, "
              "gauge length %.4f mm\n",
              setup.part_zero_table.x(), setup.part_zero_table.y(), setup.part_zero_table.z(),
              radToDeg(setup.part_rotation), setup.gauge_length);
  if (cal.probed) std::printf("  probed     %s\n", probe_line.c_str());
  const PredictedPoint& worst = pts[s.max_index];
  std::printf("  deviation  max %.3f um at point %d (line %d), RMS %.3f um%s\n",
              mmToUm(s.max_deviation), s.max_index, program.path[s.max_index].line,
              mmToUm(s.rms_deviation), s.rapid_points > 0 ? " (cutting moves)" : "");
  std::printf("             at the max: (%.3f, %.3f, %.3f) um in the part frame, %.3f um along the "
              "tool axis, %.3f um across\n",
              clean(mmToUm(worst.deviation_w.x())), clean(mmToUm(worst.deviation_w.y())),
              clean(mmToUm(worst.deviation_w.z())), clean(mmToUm(worst.along_axis)),
              clean(mmToUm(worst.across_axis)));
  if (s.rapid_points > 0 && s.rapid_max_index >= 0)
    std::printf("  rapids     %d positioning and home moves, apart: max %.3f um at line %d\n",
                s.rapid_points, mmToUm(s.rapid_max_deviation),
                program.path[s.rapid_max_index].line);
  std::printf("  tool axis  max %.3f urad, RMS %.3f urad\n", radToUrad(s.max_axis_angle),
              radToUrad(s.rms_axis_angle));
  if (!unc.empty()) printUncertainty(machine, program, cal);
  printRisks(machine, program, r, o.max_rotary_step_deg);
  printWarnings(machine, program, probe_warnings, o.program.units);
  std::printf("  wrote      %s (predicted CL), %s (per-point table)\n", o.output.c_str(),
              table.c_str());
  *exit_code = 0;
}

}  // namespace

void registerPredict(CLI::App& app, int* exit_code) {
  auto o = std::make_shared<PredictOptions>();
  CLI::App* cmd = app.add_subcommand(
      "predict",
      "Predict the real tool path of a CL program on a machine with errors: inverse kinematics "
      "on the nominal machine, forward kinematics with the errors (CL_predicted).");
  addMachineOptions(cmd, o->machine, "machine file (XML)");
  addProgramOptions(cmd, o->program);
  cmd->add_option("-o,--output", o->output, "predicted CL file to write (APT)")->required();
  cmd->add_option("--max-rotary-step-deg", o->max_rotary_step_deg,
                  "report rotary steps above this between cutting moves, deg (default 10)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--errors", o->table,
                  "per-point table to write (CSV; default: the output path with .csv)");
  cmd->add_flag("--absolute", o->absolute,
                "a calibrated machine: predict without the set-up a shop measures (part probed, "
                "tool preset), i.e. with what the calibration cannot see left in");
  addProbedOption(cmd, o->probed);
  cmd->callback([o, exit_code] { runPredict(*o, exit_code); });
}

}  // namespace tolver::app
