// The calibrate pipeline: see pipeline/calibrate.h.
#include "pipeline/calibrate.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <optional>

#include "core/kinematics/forward_kinematics.h"
#include "core/numerics/quantities.h"
#include "core/numerics/units.h"
#include "io/common/io_error.h"
#include "io/common/text_util.h"
#include "io/machine/machine_file.h"

namespace tolver {
namespace {

// --prior: "auto", "none" or "um,urad" (the standard deviation of a linear and an angular error
// coefficient on this machine's class). *um = 0 for auto and none.
void parsePrior(const std::string& prior, double* um, double* urad) {
  *um = *urad = 0;
  if (prior == "auto" || prior == "none") return;
  const auto cells = splitCsvLine(prior);
  const auto a = cells.size() == 2 ? parseNumber(cells[0]) : std::nullopt;
  const auto b = cells.size() == 2 ? parseNumber(cells[1]) : std::nullopt;
  if (!a || !b || !(*a > 0) || !(*b > 0) || *a > 1e4 || *b > 1e5)
    throw FieldError("prior",
                     "expected auto, none, or 'um,urad' (the standard deviation of a linear and "
                     "an angular error coefficient on this machine's class, e.g. 3,10)");
  *um = *a;
  *urad = *b;
}

// Regularised refit: the prior's scale from the readings' evidence (auto), or as given. Keeps
// the plain fit when the refit does not converge.
void refitWithPrior(const CalibrateInputs& in, const CalibrationOptions& opt, CalibrationRun& run) {
  double prior_um = 0, prior_urad = 0;
  parsePrior(in.prior, &prior_um, &prior_urad);
  const bool prior_auto = in.prior == "auto";
  const CalibrationResult& r = run.fit;
  if (!(prior_auto || prior_um > 0) ||
      !(r.status == CalibrationStatus::Converged || r.status == CalibrationStatus::NotConverged))
    return;
  CalibrationOptions ro = opt;
  PriorScaleEvidence evidence;
  if (prior_auto) {
    double k = 0;
    ro = evidencePrior(run.machine.model, run.used, r, opt, &k, &evidence);
    prior_um = k * mmToUm(kPriorUnitLinear);
    prior_urad = k * radToUrad(kPriorUnitAngular);
  } else {
    ro.prior_linear = umToMm(prior_um);
    ro.prior_angular = uradToRad(prior_urad);
    ro.prior_noise = std::max(r.residual_sigma, 1e-12);
  }
  CalibrationResult rr =
      calibrate(run.machine.model, run.machine.params, run.used, run.unknowns, ro);
  if (rr.status != CalibrationStatus::Converged) return;
  // The evidence's k is itself uncertain: the covariance over its posterior, not at its best.
  if (prior_auto) marginalisePriorScale(evidence, r.identified, &rr);
  run.fit = rr;
  char buf[160];
  std::snprintf(buf, sizeof buf, "%.3g um per linear, %.3g urad per angular coefficient%s",
                prior_um, prior_urad, prior_auto ? " (chosen by the readings' evidence)" : "");
  run.prior_text = buf;
}

}  // namespace

BallbarTest loadHeldout(const std::string& file, const MachineModel& model, const BallbarTest& fit,
                        const std::string& fit_file) {
  if (file.empty()) return {};
  BallbarFile h = readBallbarFile(file, model, true);
  alignHeldout(h.test, fit, file, fit_file);
  return h.test;
}

std::string ballsPathFor(const std::string& machine_output) {
  const std::filesystem::path p(machine_output);
  return (p.parent_path() / (p.stem().string() + "_balls.csv")).string();
}

CalibrationOutputs calibrationOutputs(const std::string& machine, const std::string& balls,
                                      const std::string& report) {
  CalibrationOutputs out;
  out.machine = machine;
  out.report = report.empty() ? replaceExtension(machine, ".json") : report;
  out.balls = balls.empty() ? ballsPathFor(machine) : balls;
  checkOutputDir(out.machine, "output");
  checkOutputDir(out.report, "report");
  checkOutputDir(out.balls, "balls");
  return out;
}

TestDesign testDesign(const MachineModel& model, const BallbarTest& test, int unknowns) {
  TestDesign d;
  const int m = static_cast<int>(test.readings.size());
  char buf[400];
  if (m < 3 * unknowns) {
    std::snprintf(buf, sizeof buf,
                  "%d readings for %d unknowns (fewer than 3 per unknown): the fit follows the "
                  "noise and predicts other poses worse than its residual says; plan at least %d "
                  "readings",
                  m, unknowns, 3 * unknowns);
    d.warnings.push_back(buf);
  }
  d.time = timeJointCorrelation(model, test);
  if (d.time.worst_axis >= 0 && d.time.worst > 0.5) {
    const char* axis = model.axes[d.time.worst_axis].name.c_str();
    std::snprintf(buf, sizeof buf,
                  "time and %s move together in these readings (|r| = %.2f): a thermal drift "
                  "and an error along %s cannot be told apart; order the poses at random "
                  "(plan-ballbar does)",
                  axis, d.time.worst, axis);
    d.warnings.push_back(buf);
  }
  return d;
}

std::string heldoutWarning(const std::string& file, const ResidualStats& after, double fit_rms) {
  if (!(after.readings > 0 && after.rms > 3.0 * fit_rms && after.rms > 1e-3)) return "";
  char buf[400];
  std::snprintf(
      buf, sizeof buf,
      "%s: the identified machine predicts the held-out readings at RMS %.3f um, %.0f times its "
      "fit (%.3f um): were they measured on the same set-ups (ball positions untouched), in the "
      "same machine state?",
      file.c_str(), mmToUm(after.rms), after.rms / fit_rms, mmToUm(fit_rms));
  return buf;
}

CalibrationRun calibrateMachine(const CalibrateInputs& in, const Progress& progress) {
  const CalibrationOutputs out = calibrationOutputs(in.output, in.balls, in.report);
  if (progress) progress("fitting", 0.0);
  CalibrationRun run = runCalibration(in);
  run.outputs = out;
  // The machine, its ball positions and the report as a set: all three or none.
  if (progress) progress("writing and checking the files", 0.0);
  run.written = writeCalibration(run, in, out);
  if (progress) progress("writing and checking the files", 1.0);
  run.verdict = run.fit.status == CalibrationStatus::Converged ? Verdict::Ok : Verdict::NotMet;
  return run;
}

CalibrationRun runCalibration(const CalibrateInputs& in) {
  if (const std::string problem = outOfRange(Quantity::SpindleTilt, in.spindle_tilt_urad);
      !problem.empty())
    throw FieldError("spindle_tilt_urad", problem);
  CalibrationRun run;
  run.machine = loadMachine(in.machine);
  const MachineModel& m = run.machine.model;
  run.file = readBallbarFile(in.readings, m, true);
  run.heldout = loadHeldout(in.heldout, m, run.file.test, in.readings);
  double um = 0, urad = 0;
  parsePrior(in.prior, &um, &urad);  // bad --prior before the work
  run.unknowns = defaultCalibrationUnknowns(m);
  CalibrationOptions opt;
  opt.strict = in.strict;
  if (in.keep_outliers) {
    run.fit = calibrate(m, run.machine.params, run.file.test, run.unknowns, opt);
    run.used = run.file.test;
  } else {
    run.robust = calibrateWithoutGross(m, run.machine.params, run.file.test, run.unknowns, opt);
    run.fit = run.robust.fit;
    run.used = run.robust.test;
    run.gross = run.robust.removed;
  }
  refitWithPrior(in, opt, run);
  if (in.keep_outliers) run.gross = grossReadings(m, run.file.test, run.fit);
  const CalibrationResult& r = run.fit;
  if (r.status == CalibrationStatus::Unobservable || r.status == CalibrationStatus::NoData) {
    std::string names;
    for (int p : r.held) names += " " + m.parameters[p].iso_code;
    throw InputError(in.readings, 0, 0, "calibrate",
                     r.message + (names.empty() ? "" : ":" + names));
  }
  run.absorbed = calibrationAbsorbed(m, run.unknowns);
  // Held-out readings: the prior machine with nominal balls, then the identified one.
  if (!run.heldout.readings.empty()) {
    const std::vector<BallErrors> nominal(run.file.test.setups.size());
    HeldoutFigures& ho = run.heldout_figures;
    ho.before = residualStats(
        ballbarResiduals(ForwardKinematics(m, run.machine.params), run.heldout, nominal));
    ho.after =
        residualStats(ballbarResiduals(ForwardKinematics(m, r.params), run.heldout, r.ball_errors));
    ho.file = in.heldout;
  }
  run.identified = run.machine;
  run.identified.params = r.params;
  run.identified.model.errors_source = "identified";
  run.identified.identification =
      identificationUncertainty(r, run.used, static_cast<int>(m.axes.size()));
  // What the covariance does not hold: the model's lack of fit when its test fails, the spindle
  // tilt's prior when the user states it.
  {
    const LackOfFit l = lackOfFit(run.used, r.residuals, r.unknowns);
    if (l.tested && l.p_value < 1e-3) run.identified.identification.lack_of_fit_mm = l.missing_rms;
    run.identified.identification.spindle_tilt_rad = in.spindle_tilt_urad * 1e-6;
  }
  run.lack_of_fit = lackOfFit(run.used, run.fit.residuals, run.fit.unknowns);
  for (const std::string& w : run.file.warnings) run.warnings.push_back(in.readings + ": " + w);
  run.design = testDesign(m, run.file.test, r.unknowns);
  for (const std::string& w : run.design.warnings) run.warnings.push_back(in.readings + ": " + w);
  if (!run.heldout.readings.empty()) {
    const std::string w = heldoutWarning(in.heldout, run.heldout_figures.after, r.rms_residual);
    if (!w.empty()) run.warnings.push_back(w);
  }
  return run;
}

WrittenCheck writeCalibration(const CalibrationRun& run, const CalibrateInputs& in,
                              const CalibrationOutputs& out) {
  const CalibrationResult& r = run.fit;
  OutputSet outputs;
  const std::string xml_tmp = outputs.add(
      out.machine,
      formatMachineXml(run.identified, "identified by tolver calibrate from " + in.readings + " (" +
                                           r.message + "); ball positions in " + out.balls));
  const std::string balls_tmp = outputs.add(
      out.balls, formatBallPositionsCsv(run.file.test, r.ball_errors, &r.ball_uncertainty,
                                        {"identified ball positions of " + in.readings +
                                         " by tolver calibrate (machine " + out.machine + ")"}));
  // What the written files predict, read back as the next command will.
  const WrittenCheck check =
      checkWrittenFiles(xml_tmp, balls_tmp, run.used, run.heldout, &run.machine.model.setup);
  CalibrationReportInputs rin;
  rin.machine_file = in.machine.machine;
  rin.readings_file = in.readings;
  rin.output_file = out.machine;
  rin.readings = static_cast<int>(run.file.test.readings.size());
  rin.balls_file = out.balls;
  rin.heldout = run.heldout_figures;
  rin.unknowns = run.unknowns;
  rin.absorbed = run.absorbed;
  rin.written = check;
  if (!in.keep_outliers)
    for (const GrossReading& g : run.robust.removed)
      rin.removed.push_back({run.file.test.readings[g.index].line, g.residual, g.studentized});
  outputs.add(out.report, formatCalibrationJson(run.machine.model, run.used, r, rin));
  outputs.commit();
  return check;
}

}  // namespace tolver
