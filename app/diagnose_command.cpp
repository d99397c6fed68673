// tolver diagnose: after a ball-bar calibration, find what the model failed to explain, trace it
// to an effect the model lacks, add it, and report the error before and after.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>

#include "app/commands.h"
#include "app/ballbar_support.h"
#include "app/common.h"
#include "core/diagnosis/diagnosis.h"
#include "core/model/effects.h"
#include "core/path/tool_path_prediction.h"
#include "io/program/apt_reader.h"
#include "io/machine/ballbar_file.h"
#include "io/report/diagnosis_report.h"
#include "io/common/io_error.h"
#include "io/machine/machine_file.h"
#include "io/program/setup_file.h"

namespace tolver::app {
namespace {

struct DiagnoseOptions {
  MachineOptions machine;
  std::string readings, output, report_dir, cl, cl_setup, heldout, balls;
  std::vector<std::string> types;
  double alpha = 1e-3;
  int max_effects = 4;
  int blocks_per_setup = 6;
  bool quiet = false, keep_outliers = false;
};

PredictionResult predictOrThrow(const Machine& m, const ClProgram& program, const std::string& file) {
  PredictionResult r = predictToolPath(m.model, m.params, program.path);
  if (!r.ok())
    throw InputError(file, r.failures.front().line, 0, "unreachable", r.failures.front().message);
  return r;
}

ProgramComparison compareProgram(const std::string& cl, const Machine& before, const Machine& after) {
  const ClProgram program = readAptFile(cl, AptReadOptions{});
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

void runDiagnose(const DiagnoseOptions& o, int* exit_code) {
  const auto t0 = std::chrono::steady_clock::now();
  const Machine machine = loadMachine(o.machine);
  if (!machine.model.effects.empty())
    throw InputError(o.machine.machine, 0, 0, "effect",
                     "the machine already has effects; diagnose starts from a base model "
                     "(link and motion errors only)");
  const BallbarFile f = readBallbarFile(o.readings, machine.model, true);
  const BallbarTest heldout = loadHeldout(o.heldout, machine.model, f.test, o.readings);
  const std::string balls_file = o.balls.empty() ? ballsPathFor(o.output) : o.balls;
  checkOutputDir(balls_file, "--balls");
  checkOutputDir(o.output, "-o");
  if (!o.cl.empty() && !std::filesystem::exists(o.cl))
    throw InputError(o.cl, 0, 0, "--cl", "no such file");
  for (const std::string& w : f.warnings)
    std::fprintf(stderr, "tolver: warning: %s: %s\n", o.readings.c_str(), w.c_str());

  DiagnosisOptions opt;
  opt.alpha = o.alpha;
  opt.max_effects = o.max_effects;
  opt.blocks_per_setup = o.blocks_per_setup;
  for (const std::string& t : o.types) {
    const EffectTraits* tr = findEffectType(t);
    if (!tr) throw InputError("--types", 0, 0, "type", "unknown effect type '" + t + "'");
    opt.types.push_back(tr->type);
  }
  // Gross readings first: the base fit without them is what the diagnosis starts from.
  const std::vector<int> base_unknowns = defaultCalibrationUnknowns(machine.model);
  opt.base_unknowns = base_unknowns;
  if (!heldout.readings.empty()) opt.heldout = &heldout;
  std::printf("tolver diagnose: %s from %zu readings in %zu set-ups\n", machine.model.name.c_str(),
              f.test.readings.size(), f.test.setups.size());
  RobustCalibration rc;
  if (!o.keep_outliers) {
    rc = calibrateWithoutGross(machine.model, machine.params, f.test, base_unknowns);
    printGross(o.readings, f.test, rc.removed, false, rc.with_all, rc.fit, rc.limit_reached);
  } else {
    rc.test = f.test;
    const CalibrationResult all = calibrate(machine.model, machine.params, f.test, base_unknowns);
    printGross(o.readings, f.test, grossReadings(machine.model, f.test, all), true, all, all, false);
  }
  const BallbarTest& used = rc.test;
  for (const std::string& w : testDesignWarnings(machine.model, used,
                                                 static_cast<int>(base_unknowns.size() +
                                                                  6 * used.setups.size())))
    std::fprintf(stderr, "tolver: warning: %s: %s\n", o.readings.c_str(), w.c_str());
  ProgressBar bar(!o.quiet);
  const DiagnosisResult r = diagnose(machine, used, opt, [&](int done, int total) {
    bar("scoring candidates", total > 0 ? static_cast<double>(done) / total : 1.0);
  });
  if (!r.ok) throw InputError(o.readings, 0, 0, "diagnose", r.message);
  if (r.base_fit.status != CalibrationStatus::Converged) {
    char msg[200];
    std::snprintf(msg, sizeof msg,
                  "the base calibration did not converge (residual RMS %.3g um): do the machine "
                  "file and its set-up match the test?",
                  r.base_fit.rms_residual * 1e3);
    throw InputError(o.readings, 0, 0, "calibrate", msg);
  }

  std::unique_ptr<ProgramComparison> program;
  if (!o.cl.empty()) {
    Machine before = machine, after = r.machine;
    before.params = r.base_fit.params;
    if (!o.cl_setup.empty()) {
      before.model.setup = readSetupFile(o.cl_setup);
      after.model.setup = before.model.setup;
    }
    program = std::make_unique<ProgramComparison>(compareProgram(o.cl, before, after));
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  DiagnosisReportInputs in{o.machine.machine, o.readings, o.output, program.get(), seconds};
  in.balls_file = balls_file;
  in.heldout_file = o.heldout;
  for (const GrossReading& g : rc.removed)
    in.removed.push_back({f.test.readings[g.index].line, g.residual, g.studentized});
  // The report directory is written as a whole (staged, swapped in at the end; a concurrent run on
  // it is refused), and taken before anything is written.
  ReportDirectory report_dir(o.report_dir);
  const std::string json_path = (std::filesystem::path(report_dir.staging()) / "report.json").string();
  const std::string html_path = (std::filesystem::path(report_dir.staging()) / "report.html").string();
  Machine augmented = r.machine;
  augmented.model.errors_source = "identified";
  augmented.identification = identificationUncertainty(
      r.final_fit, used, static_cast<int>(augmented.model.axes.size()));
  writeFileAtomically(o.output, formatMachineXml(augmented, "augmented by tolver diagnose from " +
                                                                o.readings + " (" + r.message +
                                                                "); ball positions in " + balls_file));
  writeFileAtomically(balls_file,
                      formatBallPositionsCsv(used, r.final_fit.ball_errors, &r.final_fit.ball_uncertainty,
                                             {"identified ball positions of " + o.readings +
                                              " by tolver diagnose (machine " + o.output + ")"}));
  // What the written files predict, read back as the next command will: the report states it.
  in.written = checkWrittenFiles(o.output, balls_file, used, heldout);
  const std::string html = writeDiagnosisHtml(report_dir.staging(), machine.model, used, r, in);
  writeFileAtomically(json_path, formatDiagnosisJson(machine.model, used, r, in));
  writeFileAtomically(html_path, html);
  report_dir.commit();

  const MachineModel& m = r.machine.model;
  std::printf("  base fit   residual RMS %.3f um, cross-validated RMS %.3f um (%d contiguous blocks)\n",
              r.rms_before * 1e3, r.cv_rms_before * 1e3, r.folds);
  std::printf("  residual   follows %s\n",
              r.analysis_before.follows.empty()
                  ? "nothing in particular"
                  : (r.analysis_before.follows + " (" +
                     std::to_string(static_cast<int>(r.analysis_before.follows_strength * 100 + 0.5)) +
                     " % of its variance)")
                        .c_str());
  std::printf("  candidates %zu scored in %d round(s)\n", r.candidates.size(),
              r.candidates.empty() ? 0 : r.candidates.back().round);
  for (const CandidateScore& c : r.candidates)
    if (c.verdict == CandidateVerdict::RefitFailed)
      std::printf("  rejected   %s: %s\n", c.label.c_str(), c.reason.c_str());
  if (!r.withdrawn.empty())
    std::printf("  verdict    nothing added: %s\n", r.withdrawn_reason.c_str());
  else if (r.added.empty())
    std::printf("  verdict    nothing missing: no effect added\n");
  for (const AddedEffect& a : r.added) {
    double k = 1;
    const char* unit = effectUnit(a.spec, &k);
    std::printf("  added      %s:", a.label.c_str());
    for (size_t j = 0; j < a.parameters.size(); ++j)
      std::printf(" %s %.3f +- %.3f", m.parameters[a.parameters[j]].iso_code.c_str(), a.values[j] * k,
                  a.uncertainty[j] * k);
    std::printf(" %s", unit);
    if (std::isfinite(a.hyperparameter))
      std::printf("; %s %.4g +- %.2g", traitsOf(a.spec.type).hyper.name, a.hyperparameter,
                  a.hyperparameter_uncertainty);
    std::printf("\n");
    if (!a.equivalent.empty()) {
      std::printf("             the readings cannot tell it from:");
      for (size_t k = 0; k < a.equivalent.size(); ++k)
        std::printf("%s %s", k ? "," : "", a.equivalent[k].c_str());
      std::printf(" (the same motion seen from the part)\n");
    }
    if (!a.confounded_with.empty()) {
      std::printf("             partly confounded (new information %.3f) with", a.new_information);
      for (size_t k = 0; k < a.confounded_with.size(); ++k) {
        const AddedEffect::Confounding& c = a.confounded_with[k];
        const double f = c.angular ? 1e6 : 1e3;
        std::printf("%s %s (|cos| %.2f: %.3f -> %.3f %s)", k ? "," : "", c.name.c_str(), c.cosine,
                    c.before * f, c.after * f, c.angular ? "urad" : "um");
      }
      std::printf("\n");
    }
  }
  if (r.unexplained) {
    const ResidualFinding& u = r.unexplained_finding;
    char what[96] = "";
    if (u.test == "periodogram")
      std::snprintf(what, sizeof what, u.period < 9 ? ", order %.0f" : ", period %.2f mm", u.period);
    std::printf("  unexplained the residual still follows %s (%s%s; %.0f %% of its variance, p %.1e): "
                "structure no effect of the library removes (plot in the report)\n",
                u.variable.c_str(), u.test.c_str(), what, u.strength * 100.0, u.p_value);
  }
  std::printf("  after      residual RMS %.3f um, cross-validated RMS %.3f um\n", r.rms_after * 1e3,
              r.cv_rms_after * 1e3);
  if (r.heldout_before.readings > 0) {
    std::printf("  held-out   %d readings (%s): RMS %.3f -> %.3f um, max %.3f -> %.3f um\n",
                r.heldout_before.readings, o.heldout.c_str(), r.heldout_before.rms * 1e3,
                r.heldout_after.rms * 1e3, r.heldout_before.max * 1e3, r.heldout_after.max * 1e3);
    heldoutWarning(o.heldout, r.heldout_after, r.final_fit.rms_residual);
  }
  std::printf("  written    %s + %s reproduce the fitted readings at RMS %.3f um", o.output.c_str(),
              balls_file.c_str(), in.written.fit.rms * 1e3);
  if (in.written.heldout.readings > 0)
    std::printf(", the held-out ones at %.3f um", in.written.heldout.rms * 1e3);
  std::printf("\n");
  if (program)
    std::printf("  program    %s: predicted error max %.3f -> %.3f um, RMS %.3f -> %.3f um "
                "(change up to %.3f um, line %d)\n",
                o.cl.c_str(), program->before.max_deviation * 1e3, program->after.max_deviation * 1e3,
                program->before.rms_deviation * 1e3, program->after.rms_deviation * 1e3,
                program->change_max * 1e3, program->change_max_line);
  std::printf("  wrote      %s (augmented machine), %s (ball positions), %s, %s\n", o.output.c_str(),
              balls_file.c_str(), json_path.c_str(), html_path.c_str());
  *exit_code = 0;
}

}  // namespace

void registerDiagnose(CLI::App& app, int* exit_code) {
  auto o = std::make_shared<DiagnoseOptions>();
  CLI::App* cmd = app.add_subcommand(
      "diagnose",
      "Find what a ball-bar calibration leaves unexplained, trace it to an effect the model "
      "lacks (backlash, cyclic error, rotary harmonics, thermal drift, bar length, a higher "
      "degree), add it and report the error before and after.");
  addMachineOptions(cmd, o->machine, "base machine file (XML): link and motion errors, no effects");
  cmd->add_option("--readings", o->readings, "ball-bar readings (CSV)")->required();
  cmd->add_option("-o,--output", o->output, "augmented machine file to write (XML)")->required();
  cmd->add_option("--report-dir", o->report_dir, "directory for report.json, report.html and plots")
      ->required();
  cmd->add_option("--cl", o->cl, "part program (APT): its predicted error before and after");
  cmd->add_option("--cl-setup", o->cl_setup,
                  "set-up file of the part program (part zero, gauge length; default: the "
                  "machine's set-up, as for the ball-bar test)");
  cmd->add_option("--types", o->types,
                  "effect types to try (default all): chebyshev, reversal, periodic, harmonics, "
                  "drift, warmup, bar_length")
      ->delimiter(',');
  cmd->add_option("--alpha", o->alpha, "family-wise significance level per round (default 0.001)")
      ->check(CLI::Range(1e-12, 0.5));
  cmd->add_option("--max-effects", o->max_effects, "most effects to add (default 4)")
      ->check(CLI::Range(0, 20));
  cmd->add_option("--blocks-per-setup", o->blocks_per_setup,
                  "cross-validation: contiguous blocks per set-up (default 6)")
      ->check(CLI::Range(2, 100));
  cmd->add_option("--heldout", o->heldout,
                  "held-out readings (CSV) of the same set-ups, never fitted: RMS before and "
                  "after, and the final check of the augmented model");
  cmd->add_option("--balls", o->balls,
                  "identified ball positions to write (CSV; default: the output path with "
                  "_balls.csv)");
  cmd->add_flag("--keep-outliers", o->keep_outliers,
                "fit every reading (gross readings are still named)");
  cmd->add_flag("--quiet", o->quiet, "no progress bar");
  cmd->callback([o, exit_code] { runDiagnose(*o, exit_code); });
}

}  // namespace tolver::app
