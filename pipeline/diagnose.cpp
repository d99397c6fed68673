// The diagnose pipeline: see pipeline/diagnose.h.
#include "pipeline/diagnose.h"

#include <cmath>
#include <cstdio>
#include <filesystem>

#include "core/model/effects.h"
#include "core/numerics/quantities.h"
#include "core/numerics/statistics.h"
#include "core/numerics/units.h"
#include "core/path/tool_path_prediction.h"
#include "io/common/io_error.h"
#include "io/machine/machine_file.h"
#include "io/program/setup_file.h"
#include "pipeline/calibrate.h"
#include "pipeline/parallel_prediction.h"

namespace tolver {
namespace {

PredictionResult predictOrThrow(const Machine& m, const ClProgram& program,
                                const std::string& file) {
  PredictionResult r = predictToolPathParallel(m.model, m.params, program.path);
  if (!r.ok())
    throw InputError(file, r.failures.front().line, 0, "unreachable", r.failures.front().message);
  return r;
}

// The part program's predicted error on the base machine and on the augmented one.
ProgramComparison compareProgram(const std::string& cl, const Machine& before,
                                 const Machine& after) {
  // As predict reads it: CL data or G-code (by extension and content), a language tolver does
  // not read refused by name.
  ProgramOptions o;
  o.cl = cl;
  const ClProgram program = loadProgram(o, before.model);
  if (program.path.empty()) throw InputError(cl, 0, 0, "GOTO", "the program has no tool positions");
  const PredictionResult a = predictOrThrow(before, program, cl);
  const PredictionResult b = predictOrThrow(after, program, cl);
  ProgramComparison c;
  c.cl_file = cl;
  c.before = a.summary;
  c.after = b.summary;
  double sum2 = 0;
  for (size_t i = 0; i < program.path.size(); ++i) {
    const double d = (b.points[i].p_pred_w - a.points[i].p_pred_w).norm();
    sum2 += d * d;
    if (d > c.change_max) {
      c.change_max = d;
      c.change_max_line = program.path[i].line;
    }
  }
  c.change_rms = std::sqrt(sum2 / program.path.size());
  return c;
}

DiagnosisOptions diagnosisOptions(const DiagnoseInputs& in) {
  DiagnosisOptions opt;
  opt.alpha = in.alpha;
  opt.max_effects = in.max_effects;
  opt.max_seconds = in.max_seconds;
  opt.blocks_per_setup = in.blocks_per_setup;
  for (const std::string& t : in.types) {
    const EffectTraits* tr = findEffectType(t);
    if (!tr) throw FieldError("types", "unknown effect type '" + t + "'");
    opt.types.push_back(tr->type);
  }
  return opt;
}

// Readings removed as gross by the base model, tested again against the final one (its
// effects included: a warm-up's first readings, a reversal's): those it explains, by the same
// criterion (Bonferroni over the test's readings, alpha 0.01), are restored and the diagnosis
// runs again with them.
void restoreExplainedGross(DiagnosisRun& run, const DiagnosisOptions& opt,
                           const std::function<void(int, int)>& progress) {
  if (run.robust.removed.empty()) return;
  const DiagnosisResult& r = run.result;
  const BallbarTest& all = run.file.test;
  BallbarTest removed;
  removed.setups = all.setups;
  for (const GrossReading& g : run.robust.removed)
    removed.readings.push_back(all.readings[g.index]);
  const ForwardKinematics fk(r.machine.model, r.machine.params);
  const Eigen::VectorXd res = ballbarResiduals(fk, removed, r.final_fit.ball_errors);
  const double s = r.final_fit.residual_sigma, m = static_cast<double>(all.readings.size());
  std::vector<GrossReading> still;
  for (size_t k = 0; k < run.robust.removed.size(); ++k) {
    const double t = s > 0 ? res[static_cast<Eigen::Index>(k)] / s : INFINITY;
    run.gross_t_after.push_back(t);
    const GrossReading g{run.robust.removed[k].index, res[static_cast<Eigen::Index>(k)], t};
    (2.0 * normalSurvival(std::abs(t)) * m >= 0.01 ? run.restored : still).push_back(g);
  }
  if (run.restored.empty()) return;
  std::vector<char> out(all.readings.size(), 0);
  for (const GrossReading& g : still) out[g.index] = 1;
  BallbarTest used;
  used.setups = all.setups;
  for (size_t i = 0; i < all.readings.size(); ++i)
    if (!out[i]) used.readings.push_back(all.readings[i]);
  run.robust.test = used;
  run.robust.removed = still;
  run.result = diagnose(run.machine, run.robust.test, opt, progress);
}

}  // namespace

DiagnosisOutputs diagnosisOutputs(const std::string& machine, const std::string& balls,
                                  const std::string& report_dir) {
  DiagnosisOutputs out{machine, balls.empty() ? ballsPathFor(machine) : balls, report_dir};
  checkOutputDir(out.balls, "balls");
  checkOutputDir(out.machine, "output");
  return out;
}

DiagnosisRun runDiagnosis(const DiagnoseInputs& in, const std::function<void(int, int)>& progress) {
  if (const std::string problem = outOfRange(Quantity::SpindleTilt, in.spindle_tilt_urad);
      !problem.empty())
    throw FieldError("spindle_tilt_urad", problem);
  DiagnosisRun run;
  run.started = std::chrono::steady_clock::now();
  run.machine = loadMachine(in.machine);
  const MachineModel& model = run.machine.model;
  if (!model.effects.empty())
    throw InputError(in.machine.machine, 0, 0, "effect",
                     "the machine already has effects; diagnose starts from a base model "
                     "(link and motion errors only)");
  run.file = readBallbarFile(in.readings, model, true);
  run.heldout = loadHeldout(in.heldout, model, run.file.test, in.readings);
  if (!in.cl.empty() && !std::filesystem::exists(in.cl))
    throw InputError(in.cl, 0, 0, "program", "no such file");
  DiagnosisOptions opt = diagnosisOptions(in);
  // Gross readings first: the base fit without them is what the diagnosis starts from.
  opt.base_unknowns = defaultCalibrationUnknowns(model);
  if (!run.heldout.readings.empty()) opt.heldout = &run.heldout;
  if (!in.keep_outliers) {
    run.robust = calibrateWithoutGross(model, run.machine.params, run.file.test, opt.base_unknowns);
    run.gross = run.robust.removed;
  } else {
    run.robust.test = run.file.test;
    run.robust.with_all = calibrate(model, run.machine.params, run.file.test, opt.base_unknowns);
    run.robust.fit = run.robust.with_all;
    run.gross = grossReadings(model, run.file.test, run.robust.with_all);
  }
  run.result = diagnose(run.machine, run.used(), opt, progress);
  if (!in.keep_outliers && run.result.ok) restoreExplainedGross(run, opt, progress);
  const DiagnosisResult& r = run.result;
  if (!r.ok) throw InputError(in.readings, 0, 0, "diagnose", r.message);
  if (r.base_fit.status != CalibrationStatus::Converged) {
    char msg[200];
    std::snprintf(msg, sizeof msg,
                  "the base calibration did not converge (residual RMS %.3g um): do the machine "
                  "file and its set-up match the test?",
                  mmToUm(r.base_fit.rms_residual));
    throw InputError(in.readings, 0, 0, "calibrate", msg);
  }
  if (!in.cl.empty()) {
    Machine before = run.machine, after = r.machine;
    before.params = r.base_fit.params;
    if (!in.cl_setup.empty()) {
      before.model.setup = readSetupFile(in.cl_setup);
      after.model.setup = before.model.setup;
    }
    run.program = std::make_unique<ProgramComparison>(compareProgram(in.cl, before, after));
  }
  for (const std::string& w : run.file.warnings) run.warnings.push_back(in.readings + ": " + w);
  const BallbarTest& used = run.used();
  run.design =
      testDesign(model, used, static_cast<int>(opt.base_unknowns.size() + 6 * used.setups.size()));
  for (const std::string& w : run.design.warnings) run.warnings.push_back(in.readings + ": " + w);
  if (r.heldout_before.readings > 0) {
    const std::string w = heldoutWarning(in.heldout, r.heldout_after, r.final_fit.rms_residual);
    if (!w.empty()) run.warnings.push_back(w);
  }
  return run;
}

DiagnosisRun diagnoseMachine(const DiagnoseInputs& in, const Progress& progress) {
  const DiagnosisOutputs out = diagnosisOutputs(in.output, in.balls, in.report_dir);
  DiagnosisRun run = runDiagnosis(in, [&](int done, int total) {
    if (progress)
      progress("scoring candidates", total > 0 ? static_cast<double>(done) / total : 1.0);
  });
  run.outputs = out;
  const DiagnosisWritten w = writeDiagnosis(run, in, out);
  run.written = w.check;
  run.json = w.json;
  run.html = w.html;
  return run;
}

DiagnosisWritten writeDiagnosis(const DiagnosisRun& run, const DiagnoseInputs& in,
                                const DiagnosisOutputs& out) {
  const DiagnosisResult& r = run.result;
  const BallbarTest& used = run.used();
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - run.started).count();
  DiagnosisReportInputs rin;
  rin.machine_file = in.machine.machine;
  rin.readings_file = in.readings;
  rin.output_file = out.machine;
  rin.program = run.program.get();
  rin.seconds = seconds;
  rin.balls_file = out.balls;
  rin.heldout_file = in.heldout;
  // Removed by the base model: still removed, or restored, with t against the final model.
  for (size_t k = 0; k < run.gross.size() && !in.keep_outliers; ++k) {
    const GrossReading& g = run.gross[k];
    RemovedReading e{run.file.test.readings[g.index].line, g.residual, g.studentized};
    if (k < run.gross_t_after.size()) e.studentized_after = run.gross_t_after[k];
    for (const GrossReading& x : run.restored) e.restored = e.restored || x.index == g.index;
    rin.removed.push_back(e);
  }
  // The report directory is staged and swapped in at the end (a concurrent run on it is refused),
  // taken before anything is written; the machine and ball files are renamed in after it.
  ReportDirectory report_dir(out.report_dir);
  const std::filesystem::path staging(report_dir.staging());
  Machine augmented = r.machine;
  augmented.model.errors_source = "identified";
  augmented.identification =
      identificationUncertainty(r.final_fit, used, static_cast<int>(augmented.model.axes.size()));
  if (r.lack_of_fit_after.tested && r.lack_of_fit_after.p_value < in.alpha)
    augmented.identification.lack_of_fit_mm = r.lack_of_fit_after.missing_rms;
  augmented.identification.spindle_tilt_rad = in.spindle_tilt_urad * 1e-6;
  OutputSet files;
  const std::string xml_tmp =
      files.add(out.machine, formatMachineXml(augmented, "augmented by tolver diagnose from " +
                                                             in.readings + " (" + r.message +
                                                             "); ball positions in " + out.balls));
  const std::string balls_tmp =
      files.add(out.balls,
                formatBallPositionsCsv(used, r.final_fit.ball_errors, &r.final_fit.ball_uncertainty,
                                       {"identified ball positions of " + in.readings +
                                        " by tolver diagnose (machine " + out.machine + ")"}));
  // What the written files predict, read back as the next command will: the report states it.
  rin.written = checkWrittenFiles(xml_tmp, balls_tmp, used, run.heldout, &run.machine.model.setup);
  const std::string html =
      writeDiagnosisHtml(report_dir.staging(), run.machine.model, used, r, rin);
  writeFileAtomically((staging / "report.json").string(),
                      formatDiagnosisJson(run.machine.model, used, r, rin));
  writeFileAtomically((staging / "report.html").string(), html);
  report_dir.commit();
  files.commit();
  DiagnosisWritten w;
  w.check = rin.written;
  w.json = (std::filesystem::path(report_dir.final()) / "report.json").string();
  w.html = (std::filesystem::path(report_dir.final()) / "report.html").string();
  return w;
}

}  // namespace tolver
