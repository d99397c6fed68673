// tolver diagnose: after a ball-bar calibration, find what the model failed to explain, trace it
// to an effect the model lacks, add it, and report the error before and after.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>

#include "app/ballbar_support.h"
#include "app/commands.h"
#include "app/common.h"
#include "core/model/effects.h"
#include "core/numerics/units.h"
#include "io/common/text_util.h"
#include "pipeline/diagnose.h"

namespace tolver::app {
namespace {

struct DiagnoseOptions {
  DiagnoseInputs in;
  bool quiet = false;
};

void printAdded(const MachineModel& m, const AddedEffect& a) {
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
      const double f = c.angular ? radToUrad(1.0) : mmToUm(1.0);
      std::printf("%s %s (|cos| %.2f: %.3f -> %.3f %s)", k ? "," : "", c.name.c_str(), c.cosine,
                  c.before * f, c.after * f, c.angular ? "urad" : "um");
    }
    std::printf("\n");
  }
}

void printDiagnosis(const DiagnosisRun& run, const DiagnoseOptions& o) {
  const DiagnosisOutputs& out = run.outputs;
  const DiagnosisResult& r = run.result;
  const ProgramComparison* program = run.program.get();
  const MachineModel& m = r.machine.model;
  std::printf(
      "  base fit   residual RMS %.3f um, cross-validated RMS %.3f um (%d contiguous blocks)\n",
      mmToUm(r.rms_before), mmToUm(r.cv_rms_before), r.folds);
  std::printf(
      "  residual   follows %s\n",
      r.analysis_before.follows.empty()
          ? "nothing in particular"
          : (r.analysis_before.follows + " (" +
             std::to_string(static_cast<int>(r.analysis_before.follows_strength * 100 + 0.5)) +
             " % of its variance)")
                .c_str());
  std::printf("  lack of fit %s\n", describeLackOfFit(r.lack_of_fit_before, o.in.alpha).c_str());
  std::printf("  candidates %zu scored in %d round(s)\n", r.candidates.size(),
              r.candidates.empty() ? 0 : r.candidates.back().round);
  for (const CandidateScore& c : r.candidates)
    if (c.verdict == CandidateVerdict::RefitFailed || c.verdict == CandidateVerdict::Implausible)
      std::printf("  rejected   %s: %s\n", c.label.c_str(), c.reason.c_str());
  // One verdict; what follows supports it.
  std::printf("  verdict    %s\n", r.verdict_text.c_str());
  if (r.budget_spent)
    std::printf(
        "  budget     --max-seconds %g ran out after %d selection round%s: the effects above are "
        "those the rounds done found; a longer budget may add more\n",
        o.in.max_seconds, r.rounds_done, r.rounds_done == 1 ? "" : "s");
  for (const AddedEffect& a : r.added) printAdded(m, a);
  if (!r.where.empty()) std::printf("  where      %s\n", r.where.c_str());
  if (!r.suggestion.empty()) std::printf("  to separate it: %s\n", r.suggestion.c_str());
  const LackOfFit& lof = r.lack_of_fit_after;
  std::printf(
      "  after      residual RMS %.3f um, cross-validated RMS %.3f um; lack of fit %s\n",
      mmToUm(r.rms_after), mmToUm(r.cv_rms_after),
      lof.tested
          ? ("F " + formatWith("%.2f", lof.f) + ", p " + formatWith("%.2g", lof.p_value)).c_str()
          : "not tested");
  if (r.heldout_before.readings == 0 && (!r.added.empty() || !r.withdrawn.empty()) &&
      std::isfinite(r.cv_gain_se_mm2))
    std::printf("  cv gain    mean squared gain %.3g +- %.2g um^2 over the %d folds (%s)\n",
                r.cv_gain_mm2 * 1e6, r.cv_gain_se_mm2 * 1e6, r.folds,
                r.cv_gain_mm2 > 2.0 * r.cv_gain_se_mm2 ? "confirmed: above twice its uncertainty"
                                                       : "not confirmed");
  if (r.heldout_before.readings > 0) {
    std::printf(
        "  held-out   %d readings (%s): RMS %.3f -> %.3f um, max %.3f -> %.3f um; mean squared "
        "gain "
        "%.3g +- %.2g um^2\n",
        r.heldout_before.readings, o.in.heldout.c_str(), mmToUm(r.heldout_before.rms),
        mmToUm(r.heldout_after.rms), mmToUm(r.heldout_before.max), mmToUm(r.heldout_after.max),
        r.heldout_gain_mm2 * 1e6, r.heldout_gain_se_mm2 * 1e6);
  }
  std::printf("  written    %s + %s reproduce the fitted readings at RMS %.3f um",
              out.machine.c_str(), out.balls.c_str(), mmToUm(run.written.fit.rms));
  if (run.written.heldout.readings > 0)
    std::printf(", the held-out ones at %.3f um", mmToUm(run.written.heldout.rms));
  // The set-up is not in the machine file: the next command needs it again.
  if (!o.in.machine.setup.empty()) std::printf(" (with --setup %s)", o.in.machine.setup.c_str());
  std::printf("\n");
  if (program)
    std::printf(
        "  program    %s: predicted error max %.3f -> %.3f um, RMS %.3f -> %.3f um "
        "(change up to %.3f um, line %d)\n",
        o.in.cl.c_str(), mmToUm(program->before.max_deviation),
        mmToUm(program->after.max_deviation), mmToUm(program->before.rms_deviation),
        mmToUm(program->after.rms_deviation), mmToUm(program->change_max),
        program->change_max_line);
  std::printf("  wrote      %s (augmented machine), %s (ball positions), %s, %s\n",
              out.machine.c_str(), out.balls.c_str(), run.json.c_str(), run.html.c_str());
}

void printGrossAgain(const DiagnosisRun& run) {
  const BallbarTest& test = run.file.test;
  if (run.restored.empty() && run.gross_t_after.empty()) return;
  std::string lines;
  char buf[120];
  for (size_t k = 0; k < run.gross.size() && k < run.gross_t_after.size(); ++k) {
    bool back = false;
    for (const GrossReading& x : run.restored) back = back || x.index == run.gross[k].index;
    std::snprintf(buf, sizeof buf, "%sline %d t %.1f -> %.1f%s", k ? ", " : "",
                  test.readings[run.gross[k].index].line, run.gross[k].studentized,
                  run.gross_t_after[k], back ? " restored" : "");
    lines += buf;
  }
  std::printf(
      "  gross again against the final model: %s%s\n", lines.c_str(),
      run.restored.empty() ? "" : " (the diagnosis was run again with the restored readings)");
}

void printRun(const DiagnosisRun& run, const DiagnoseOptions& o) {
  const MachineModel& base = run.machine.model;
  const BallbarTest& test = run.file.test;
  printWarnings(run.warnings);
  std::printf("tolver diagnose: %s from %zu readings in %zu set-ups\n", base.name.c_str(),
              test.readings.size(), test.setups.size());
  printGross(o.in.readings, test, run.gross, o.in.keep_outliers, run.robust.with_all,
             run.robust.fit, run.robust.limit_reached);
  printTimeLine(base, run.design);
  printGrossAgain(run);
  printDiagnosis(run, o);
}

}  // namespace

void registerDiagnose(CLI::App& app, Verdict* verdict) {
  auto o = std::make_shared<DiagnoseOptions>();
  CLI::App* cmd = app.add_subcommand(
      "diagnose",
      "Find what a ball-bar calibration leaves unexplained, trace it to an effect the model "
      "lacks (backlash, cyclic error, rotary harmonics, thermal drift, bar length, a higher "
      "degree), add it and report the error before and after.");
  addMachineOptions(cmd, o->in.machine,
                    "base machine file (XML): link and motion errors, no effects");
  cmd->add_option("--readings", o->in.readings, "ball-bar readings (CSV)")->required();
  cmd->add_option("-o,--output", o->in.output, "augmented machine file to write (XML)")->required();
  cmd->add_option("--report-dir", o->in.report_dir,
                  "directory for report.json, report.html and plots")
      ->required();
  cmd->add_option("--cl", o->in.cl, "part program (APT): its predicted error before and after");
  cmd->add_option("--cl-setup", o->in.cl_setup,
                  "set-up file of the part program (part zero, gauge length; default: the "
                  "machine's set-up, as for the ball-bar test)");
  cmd->add_option("--types", o->in.types,
                  "effect types to try (default all): chebyshev, reversal, periodic, harmonics, "
                  "drift, warmup, bar_length")
      ->delimiter(',');
  cmd->add_option("--alpha", o->in.alpha,
                  "family-wise significance level per round (default 0.001)")
      ->check(CLI::Range(1e-12, 0.5));
  cmd->add_option("--max-seconds", o->in.max_seconds,
                  "time budget, s (default 0: none); when it runs out no further selection round "
                  "starts, said so")
      ->check(CLI::Range(0.0, 1e6));
  cmd->add_option("--max-effects", o->in.max_effects, "most effects to add (default 4)")
      ->check(CLI::Range(0, 20));
  cmd->add_option("--blocks-per-setup", o->in.blocks_per_setup,
                  "cross-validation: contiguous blocks per set-up (default 6)")
      ->check(CLI::Range(2, 100));
  cmd->add_option("--heldout", o->in.heldout,
                  "held-out readings (CSV) of the same set-ups, never fitted: RMS before and "
                  "after, and the final check of the augmented model");
  cmd->add_option("--balls", o->in.balls,
                  "identified ball positions to write (CSV; default: the output path with "
                  "_balls.csv)");
  cmd->add_option(
         "--spindle-tilt-urad", o->in.spindle_tilt_urad,
         "prior of the spindle's tilt against the machine's axes (urad, 1 sigma), which a "
         "ball-bar cannot see (e.g. the tram tolerance over 2): added to every prediction's "
         "tool-axis band")
      ->check(CLI::Range(0.0, 1e5));
  cmd->add_flag("--keep-outliers", o->in.keep_outliers,
                "fit every reading (gross readings are still named)");
  cmd->add_flag("--quiet", o->quiet, "no progress bar");
  cmd->callback([o, verdict] {
    ProgressBar bar(!o->quiet);
    const DiagnosisRun run = diagnoseMachine(o->in, progressOf(bar));
    printRun(run, *o);
    *verdict = run.verdict;
  });
}

}  // namespace tolver::app
