// tolver compensate: a corrected program that the machine, errors included, runs onto the
// nominal path; the predicted error before and after (the after measured on the written file).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <set>

#include "app/commands.h"
#include "app/common.h"
#include "core/numerics/units.h"
#include "io/common/text_util.h"
#include "pipeline/compensate.h"

namespace tolver::app {
namespace {

void printTables(const TableRun& run, const CompensateInputs& o) {
  std::printf("tolver compensate --table\n");
  std::printf("  machine    %s (%s)\n", run.machine.model.name.c_str(), o.machine.machine.c_str());
  std::printf("  tables     %zu linear axes, step %.3f mm, zero at %s\n", run.tables.size(),
              o.table_step, run.reference.c_str());
  std::printf(
      "  effect     tool-tip error over the linear travel (relative to the reference pose, whose "
      "constant "
      "the work offset takes), rotary axes at the reference: RMS %.3f -> %.3f um\n",
      mmToUm(run.flat.before_rms), mmToUm(run.flat.after_rms));
  std::printf(
      "             over the whole travel, rotary axes moving: RMS %.3f -> %.3f um (what linear "
      "tables cannot "
      "carry: the rotary axes' errors and the angular errors seen through the other axes' "
      "offsets)\n",
      mmToUm(run.full.before_rms), mmToUm(run.full.after_rms));
  if (run.rotary_terms > 0)
    std::printf(
        "  not carried %d error terms of the rotary axes (%s%s): a five-axis volumetric "
        "compensation of the control is needed for them\n",
        run.rotary_terms, run.rotary_names.c_str(), run.rotary_terms > 8 ? ", ..." : "");
  for (const std::string& f : run.files) std::printf("  wrote      %s\n", f.c_str());
}

void printCompensation(const CompensationRun& run, const CompensateInputs& o,
                       const std::string& report) {
  const CompensationReport& rep = run.report;
  const int n = rep.points;
  std::printf("tolver compensate\n");
  std::printf("  machine    %s (%s)\n", run.machine.model.name.c_str(), o.machine.machine.c_str());
  std::printf(
      "  program    %s (%s): %d tool positions%s, %s\n", run.program.file.c_str(),
      run.program.dialect.c_str(), n,
      o.program.lines.empty()
          ? ""
          : (" of lines " + o.program.lines + " (the other lines written as they are)").c_str(),
      run.orientation ? "tool tip and tool axis compensated"
                      : "3-axis: the tool tip compensated by the linear axes");
  if (!run.setup_note.empty()) std::printf("  set-up     %s\n", run.setup_note.c_str());
  if (!rep.process.empty())
    std::printf(
        "  process    %s: also compensated, %s (before and after are measured against where "
        "these effects need the tool)\n",
        rep.process.c_str(), rep.process_applied.c_str());
  std::printf(
      "  before     tip max %.3f um (line %d), RMS %.3f um; tool axis max %.2f urad, RMS %.2f "
      "urad\n",
      rep.before.tip_max_um, rep.before.tip_max_line, rep.before.tip_rms_um,
      rep.before.axis_max_urad, rep.before.axis_rms_urad);
  // On a calibrated machine the after is the calibration's band (what the model cannot know);
  // the model's own residual, read back, is given apart.
  if (rep.after_band95_max_um >= 0) {
    std::printf(
        "  after      within the calibration's 95 %% radius: tip median %.3f um, max %.3f um; "
        "tool axis median %.2f urad, max %.2f urad\n",
        rep.after_band95_median_um, rep.after_band95_max_um, rep.after_axis_band95_median_urad,
        rep.after_axis_band95_max_urad);
    std::printf(
        "  band from  the covariance; %s; %s\n",
        rep.after_lack_of_fit_um > 0
            ? formatWith("the lack of fit, %.3f um per tip coordinate", rep.after_lack_of_fit_um)
                  .c_str()
            : "no lack of fit",
        rep.after_tilt_prior_urad > 0
            ? formatWith("the spindle tilt's prior, %.1f urad on the axis",
                         rep.after_tilt_prior_urad)
                  .c_str()
            : "the spindle's tilt, which a ball-bar cannot see, is not in the axis band "
              "(calibrate --spindle-tilt-urad states its prior)");
  }
  std::printf(
      "  %s tip max %.4f um (line %d), RMS %.4f um; tool axis max %.3f urad, RMS %.3f urad "
      "(the written program, read back and predicted on the model)\n",
      rep.after_band95_max_um >= 0 ? "model     " : "after     ", rep.after.tip_max_um,
      rep.after.tip_max_line, rep.after.tip_rms_um, rep.after.axis_max_urad,
      rep.after.axis_rms_urad);
  if (rep.compensated_points < n)
    std::printf(
        "             on the %d points the file compensates (the others are listed below): tip max "
        "%.4f um, RMS %.4f um; tool axis max %.3f urad\n",
        rep.compensated_points, rep.after_compensated.tip_max_um, rep.after_compensated.tip_rms_um,
        rep.after_compensated.axis_max_urad);
  std::string jc;
  char buf[96];
  for (size_t a = 0; a < rep.joint_correction_max.size(); ++a) {
    std::snprintf(buf, sizeof buf, "%s%s %.3f %s", a ? ", " : "",
                  rep.joint_correction_max[a].first.c_str(), rep.joint_correction_max[a].second,
                  rep.joint_rotary[a] ? "urad" : "um");
    jc += buf;
  }
  std::printf("  joints     largest corrections: %s\n", jc.c_str());
  if (rep.segments.size() > 1) {
    std::vector<const SegmentFigures*> worst;
    for (const SegmentFigures& s : rep.segments) worst.push_back(&s);
    std::sort(worst.begin(), worst.end(),
              [](auto* a, auto* b) { return a->before.tip_max_um > b->before.tip_max_um; });
    std::printf("  segments   %zu (cutting runs between rapids); the worst before:",
                rep.segments.size());
    for (size_t k = 0; k < worst.size() && k < 3; ++k)
      std::printf("%s lines %d-%d %.2f -> %.4f um", k ? "," : "", worst[k]->first_line,
                  worst[k]->last_line, worst[k]->before.tip_max_um, worst[k]->after.tip_max_um);
    std::printf("\n");
  }
  auto lines = [](const std::vector<int>& v) {
    std::string s;
    for (size_t k = 0; k < v.size() && k < 6; ++k) s += (k ? ", " : "") + std::to_string(v[k]);
    return s + (v.size() > 6 ? ", ..." : "");
  };
  if (rep.out_of_travel > 0)
    std::printf(
        "  travel     %d points would need joints beyond travel: left uncompensated (lines %s)\n",
        rep.out_of_travel, lines(rep.out_of_travel_lines).c_str());
  if (rep.not_converged > 0)
    std::printf("  warning    %d points did not converge: left uncompensated\n", rep.not_converged);
  if (rep.ill_conditioned > 0)
    std::printf(
        "  singular   %d points near a singular pose (condition above %.0e): the tool tip "
        "compensated, the tool axis left as programmed (correcting it would swing a rotary axis) "
        "(lines %s)\n",
        rep.ill_conditioned, o.max_condition, lines(rep.ill_conditioned_lines).c_str());
  for (const std::string& note : run.text.notes) std::printf("  note       %s\n", note.c_str());
  printWarnings(run.warnings);
  std::printf(
      "  wrote      %s (compensated program), %s (report), %s (the joints of every point)\n",
      o.output.c_str(), report.c_str(), compensatedJointsPath(report).c_str());
  if (!o.report_dir.empty())
    std::printf("  report     %s/report.html (and report.json, tip_deviation.png, tool_axis.png)\n",
                o.report_dir.c_str());
}

void printRun(const CompensateRun& run, const CompensateInputs& o) {
  if (run.tables) printTables(*run.tables, o);
  if (!run.compensation) return;
  printCompensation(*run.compensation, o, run.report);
  const std::vector<int>& worse = run.worse_lines;
  if (worse.empty()) return;
  std::string lines;
  for (size_t k = 0; k < worse.size() && k < 8; ++k)
    lines += (k ? ", " : "") + std::to_string(worse[k]);
  std::printf(
      "  FAILED     the written program, read back, is further off than the original at %zu "
      "lines (%s%s; up to %.3f um): it moves where the original did not; do not run it "
      "as written\n",
      worse.size(), lines.c_str(), worse.size() > 8 ? ", ..." : "", run.worse_max_um);
}

}  // namespace

void registerCompensate(CLI::App& app, Verdict* verdict) {
  auto o = std::make_shared<CompensateInputs>();
  CLI::App* cmd = app.add_subcommand(
      "compensate",
      "Write the program that the machine, errors included, runs onto the nominal path: joints by "
      "Newton on the full error model, written back in the program's own dialect, with the "
      "predicted error before and after.");
  addMachineOptions(cmd, o->machine, "machine file (XML) with the errors to compensate");
  addProgramOptions(cmd, o->program);
  cmd->add_option("-o,--output", o->output,
                  "compensated program to write (same dialect as the input)");
  cmd->add_option("--table", o->table,
                  "also (or only) write pitch and straightness tables for the linear axes: "
                  "<stem>_<axis>.csv per axis");
  cmd->add_option("--table-step", o->table_step, "grid step of the tables, mm (default 10)")
      ->check(CLI::Range(0.1, 1000.0));
  cmd->add_option("--report", o->report, "JSON report (default: the output path with .json)");
  cmd->add_option(
      "--report-dir", o->report_dir,
      "also write report.html with before/after charts (and report.json) in this directory");
  cmd->add_option(
         "--max-condition", o->max_condition,
         "condition number beyond which a point counts as near a singular pose (default 1e6)")
      ->check(CLI::Range(10.0, 1e15));
  cmd->add_flag(
      "--absolute", o->absolute,
      "a calibrated machine: compensate its raw prediction, with what probing and presetting "
      "would take up");
  addProbedOption(cmd, o->probed);
  cmd->add_option("--process", o->process,
                  "process corrections learned from a measured part (tolver measure's "
                  "process.txt): the part's set-up, the tools' lengths, the spindle's drift and "
                  "the tools' deflection compensated too (a radius error goes to the tool table)");
  auto quiet = addQuietFlag(cmd);
  cmd->callback([o, verdict, quiet] {
    ProgressBar bar(!*quiet);
    const CompensateRun run = compensateProgram(*o, progressOf(bar));
    printRun(run, *o);
    *verdict = run.verdict;
  });
}

}  // namespace tolver::app
