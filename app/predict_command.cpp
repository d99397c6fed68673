// tolver predict: CL_predicted of a part program on a machine with errors ([AM01] 5.5.1-5.5.3).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>

#include "app/commands.h"
#include "app/common.h"
#include "core/numerics/units.h"
#include "geometry/cutter.h"
#include "io/common/text_util.h"
#include "pipeline/predict.h"

namespace tolver::app {
namespace {

// Rounds away "-0.000" in printed figures.
double clean(double v) { return std::abs(v) < 5e-7 ? 0.0 : v; }

// The prediction's uncertainty on a calibrated machine: the set-up it is taken after, the 1-sigma
// band, and the points beyond the calibrated ranges.
void printUncertainty(const Machine& machine, const CalibratedPrediction& cal,
                      const BandSummary& band) {
  const Eigen::VectorXd& measured_setup = cal.measured_setup;
  if (cal.probed)
    std::printf(
        "  set-up     probed: the calibration cannot see the part's pose on the table; "
        "predicted with the set-up fitted to the probed points, uncertainty included\n");
  else if (measured_setup.size() == 9)
    std::printf(
        "  set-up     the calibration cannot see the part's pose on the table or the tool "
        "tip's offset from the spindle: predicted after the set-up a shop measures (part "
        "probed: %+.2f %+.2f %+.2f um, %+.1f %+.1f %+.1f urad; tool preset: %+.2f %+.2f "
        "%+.2f um taken up); --absolute for the raw prediction\n",
        mmToUm(measured_setup[0]), mmToUm(measured_setup[1]), mmToUm(measured_setup[2]),
        radToUrad(measured_setup[3]), radToUrad(measured_setup[4]), radToUrad(measured_setup[5]),
        mmToUm(measured_setup[6]), mmToUm(measured_setup[7]), mmToUm(measured_setup[8]));
  else
    std::printf(
        "  set-up     absolute prediction (--absolute): it includes what probing the part "
        "and presetting the tool would take up, which the calibration cannot see\n");
  std::printf(
      "  uncertainty (1 sigma) of the prediction (%zu identified values and what their "
      "covariance does not hold, below): tip median %.3f um, max %.3f um; tool axis median %.3f "
      "urad, "
      "max %.3f urad\n",
      machine.identification.parameters.size(), mmToUm(band.tip_median), mmToUm(band.tip_max),
      radToUrad(band.axis_median), radToUrad(band.axis_max));
  // Which parts of the band come from where.
  const IdentificationUncertainty& id = machine.identification;
  std::printf(
      "  band from  the covariance (tip median %.3f um, axis median %.3f urad); %s; %s\n",
      mmToUm(band.calibration_tip_median), radToUrad(band.calibration_axis_median),
      id.lack_of_fit_mm > 0
          ? ("the calibration's lack of fit, " + formatWith("%.3f um", mmToUm(id.lack_of_fit_mm)) +
             " per tip coordinate")
                .c_str()
          : "no lack of fit (the calibration's test passed, or it had no repeats)",
      id.spindle_tilt_rad > 0
          ? ("the spindle tilt's prior, " + formatWith("%.1f urad", id.spindle_tilt_rad * 1e6) +
             " on the axis")
                .c_str()
          : "the spindle's tilt, which a ball-bar cannot see, is not in the axis band (calibrate "
            "--spindle-tilt-urad states its prior; a tram measures it)");
  if (band.outside > 0) {
    std::string where;
    char buf[96];
    for (size_t a = 0; a < band.beyond.size(); ++a)
      if (band.beyond[a] > 0) {
        const bool rot = machine.model.axes[a].isRotary();
        std::snprintf(buf, sizeof buf, "%s%s by up to %.3f %s", where.empty() ? "" : ", ",
                      machine.model.axes[a].name.c_str(),
                      band.beyond[a] * (rot ? radToDeg(1.0) : 1.0), rot ? "deg" : "mm");
        where += buf;
      }
    std::printf(
        "  calibrated %d points lie outside the joint ranges the calibration readings "
        "covered (first at line %d; %s): there the errors are extrapolated\n",
        band.outside, band.first_outside_line, where.c_str());
  }
}

// Singular points and large rotary steps between cutting moves.
void printRisks(const PredictionRun& run, double max_rotary_step_deg) {
  const Machine& machine = run.machine;
  const PredictionSummary& s = run.prediction.summary;
  if (s.singular_points > 0)
    std::printf(
        "  note       %d points have the tool axis within %.4g deg of a rotary axis (first "
        "at line %d); that axis kept its previous angle\n",
        s.singular_points, radToDeg(machine.model.control.singular_band), s.first_singular_line);
  const auto& jumps = run.jumps;
  if (!jumps.empty()) {
    std::printf("  risk       %zu rotary steps above %.1f deg between cutting moves:", jumps.size(),
                max_rotary_step_deg);
    for (size_t k = 0; k < jumps.size() && k < 5; ++k)
      std::printf("%s line %d %s %+.1f deg", k ? "," : "", jumps[k].line,
                  machine.model.axes[jumps[k].axis].name.c_str(), radToDeg(jumps[k].step));
    std::printf("%s\n", jumps.size() > 5 ? ", ..." : "");
  }
}

void printPrediction(const PredictionRun& run, const PredictInputs& in) {
  const Machine& machine = run.machine;
  const ClProgram& program = run.program;
  const PartSetup& setup = machine.model.setup;
  const PredictionSummary& s = run.prediction.summary;
  const CalibratedPrediction& cal = run.calibration;
  std::printf("tolver predict\n");
  std::printf("  machine    %s (%s): %zu axes, %d error parameters, %d non-zero\n",
              machine.model.name.c_str(), in.machine.machine.c_str(), machine.model.axes.size(),
              machine.model.parameterCount(), run.nonzero_parameters);
  std::printf("             %s\n", run.errors_statement.c_str());
  std::printf("  program    %s (%s): %d tool positions (%d arcs expanded), units %s%s\n",
              program.file.c_str(), program.dialect.c_str(), s.points, program.arcs_expanded,
              program.units.c_str(), program.units_declared ? "" : " (assumed)");
  Cutter cutter;
  if (!program.cutters.empty() &&
      cutterFromApt(program.cutters.back().source, program.cutters.back().values, &cutter))
    std::printf("  tool       %s (line %d)\n", cutter.describe().c_str(),
                program.cutters.back().line);
  std::printf(
      "  set-up     part zero (%.4f, %.4f, %.4f) mm in the table frame, rotation %.4f deg, "
      "gauge length %.4f mm\n",
      setup.part_zero_table.x(), setup.part_zero_table.y(), setup.part_zero_table.z(),
      radToDeg(setup.part_rotation), setup.gauge_length);
  if (cal.probed) std::printf("  probed     %s\n", run.probe_line.c_str());
  const PredictedPoint& worst = run.worst;
  std::printf("  deviation  max %.3f um at point %d (line %d), RMS %.3f um%s\n",
              mmToUm(s.max_deviation), s.max_index, s.max_line, mmToUm(s.rms_deviation),
              s.rapid_points > 0 ? " (cutting moves)" : "");
  std::printf(
      "             at the max: (%.3f, %.3f, %.3f) um in the part frame, %.3f um along the "
      "tool axis, %.3f um across\n",
      clean(mmToUm(worst.deviation_w.x())), clean(mmToUm(worst.deviation_w.y())),
      clean(mmToUm(worst.deviation_w.z())), clean(mmToUm(worst.along_axis)),
      clean(mmToUm(worst.across_axis)));
  if (s.rapid_points > 0 && s.rapid_max_index >= 0)
    std::printf("  rapids     %d positioning and home moves, apart: max %.3f um at line %d\n",
                s.rapid_points, mmToUm(s.rapid_max_deviation), s.rapid_max_line);
  std::printf("  tool axis  max %.3f urad, RMS %.3f urad\n", radToUrad(s.max_axis_angle),
              radToUrad(s.rms_axis_angle));
  if (run.has_band) printUncertainty(machine, cal, run.band);
  printRisks(run, in.max_rotary_step_deg);
  printWarnings(run.warnings);
  printNotes(run.notes);
  if (run.point_table.empty())
    std::printf("  wrote      %s (predicted CL)\n", run.output.c_str());
  else
    std::printf("  wrote      %s (predicted CL), %s (per-point table)\n", run.output.c_str(),
                run.point_table.c_str());
}

}  // namespace

void registerPredict(CLI::App& app, Verdict* verdict) {
  auto o = std::make_shared<PredictInputs>();
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
  auto* errors =
      cmd->add_option("--errors", o->point_table,
                      "per-point table to write (CSV; default: the output path with .csv)");
  cmd->add_flag("--no-errors", o->no_point_table,
                "write the predicted CL alone, without the per-point table")
      ->excludes(errors);
  cmd->add_flag("--absolute", o->absolute,
                "a calibrated machine: predict without the set-up a shop measures (part probed, "
                "tool preset), i.e. with what the calibration cannot see left in");
  addProbedOption(cmd, o->probed);
  auto quiet = addQuietFlag(cmd);
  cmd->callback([o, verdict, quiet] {
    ProgressBar bar(!*quiet);
    const PredictionRun run = predict(*o, progressOf(bar));
    printPrediction(run, *o);
    *verdict = run.verdict;
  });
}

}  // namespace tolver::app
