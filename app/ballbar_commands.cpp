// tolver plan-ballbar, simulate-ballbar, calibrate: a telescoping ball-bar calibration of a
// five-axis machine ([AM01] chapters 3 and 4).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <random>

#include "app/ballbar_support.h"
#include "app/commands.h"
#include "app/common.h"
#include "core/numerics/units.h"
#include "pipeline/ballbar.h"
#include "pipeline/calibrate.h"

namespace tolver::app {
namespace {

void printPlan(const PlanBallbarInputs& o, const PlanRun& run) {
  const Machine& machine = run.machine;
  const BallbarPlan& plan = run.plan;
  std::printf("tolver plan-ballbar: %s\n", machine.model.name.c_str());
  std::printf("  bar %s, %zu set-ups, %zu poses (%d sampled, %d outside travel)\n",
              run.lengths_text.c_str(), plan.test.setups.size(), plan.test.readings.size(),
              plan.sampled, plan.rejected);
  for (const BallbarSetup& s : plan.test.setups)
    std::printf(
        "  set-up %d: table ball (%.3f, %.3f, %.3f) mm in w, tool ball (%.3f, %.3f, %.3f) mm in "
        "t\n",
        s.id, s.table_ball_w.x(), s.table_ball_w.y(), s.table_ball_w.z(), s.tool_ball_t.x(),
        s.tool_ball_t.y(), s.tool_ball_t.z());
  std::printf(
      "  identification Jacobian: %d unknowns (%zu machine + 6 per set-up), rank %d, condition "
      "%.3g\n",
      plan.unknowns, run.unknowns.size(), plan.rank, plan.condition);
  if (plan.rank < plan.unknowns)
    std::printf("  warning: %d unknowns are not observable with this plan\n",
                plan.unknowns - plan.rank);
  if (plan.time_correlation_axis >= 0)
    std::printf(
        "  order      largest correlation of the measurement order with a joint within a "
        "set-up: |r| = %.2f (%s)%s\n",
        plan.time_correlation, machine.model.axes[plan.time_correlation_axis].name.c_str(),
        plan.time_correlation < o.plan.max_time_correlation
            ? ": a drift in time cannot pass for an error along an axis"
            : ": above 0.3, no better order was found");
  if (o.plan.reference_every > 0)
    std::printf("  drift      each set-up's first pose measured again after every %d poses\n",
                o.plan.reference_every);
  if (run.too_few_readings)
    std::fprintf(
        stderr,
        "tolver: warning: %zu readings for %d unknowns (fewer than 3 per unknown): the fit "
        "will follow the noise; ask for at least --poses %d\n",
        plan.test.readings.size(), plan.unknowns, 3 * plan.unknowns);
}

// What the plan would give at the target, before anyone measures; and what the default plan
// would give there.
void printExpected(const PlanBallbarInputs& o, const PlanRun& run) {
  std::printf(
      "  for        %s: poses chosen by the tool tip's prediction variance at %zu of its "
      "%s, after the set-up a shop measures (I-optimal)\n",
      run.target_text.c_str(), run.targets, o.volume ? "poses" : "points");
  std::printf(
      "  expected   tip uncertainty %s (1 sigma, %.2f um readings, after the measured "
      "set-up, at %zu poses): median %.3f um, max %.3f um; the D-optimal plan of the same "
      "size: median %.3f um, max %.3f um\n",
      o.volume ? "over the whole travel" : "where the program cuts", o.noise_um,
      run.target_q.size(), run.expected.median_um, run.expected.max_um,
      run.expected_default.median_um, run.expected_default.max_um);
  // What the targeted plan buys, and when it buys little: the expected figures are those of a
  // model that fits (a real machine's realised uncertainty varies more from machine to machine
  // than a gain of a few per cent).
  if (run.gain >= 0.1)
    std::printf(
        "  buys       an expected %.0f %% lower median tip uncertainty at the target than the "
        "default plan\n",
        100.0 * run.gain);
  else
    std::printf(
        "  buys       little: the expected median tip uncertainty at the target is %.0f %% %s than "
        "the "
        "default plan's, less than the spread between machines; the default plan (without --for or "
        "--volume) is as good here\n",
        100.0 * std::abs(run.gain), run.gain >= 0 ? "lower" : "higher");
}

void printPlanRun(const PlanBallbarInputs& o, const PlanRun& run) {
  printPlan(o, run);
  if (!run.target_q.empty()) printExpected(o, run);
  std::printf("  wrote      %s (plan), %s (NC program)\n", run.output.c_str(), run.gcode.c_str());
  if (!run.heldout_output.empty())
    std::printf(
        "  wrote      %s, %s (%zu held-out poses: measure them after the plan, give them "
        "to calibrate --heldout)\n",
        run.heldout_output.c_str(), run.heldout_gcode.c_str(), run.held.test.readings.size());
}

void printSimulation(const SimulateBallbarInputs& o, const SimulationRun& run) {
  std::printf("tolver simulate-ballbar: %zu readings from %s (%s)\n", run.readings,
              run.machine.model.name.c_str(), o.machine.machine.c_str());
  std::printf("  noise %.3f um (1 sigma), ball position errors %.3f um (1 sigma), seed %u\n",
              o.noise_um, o.ball_error_um, o.seed);
  std::printf("  wrote      %s\n", run.output.c_str());
  if (!run.heldout_output.empty())
    std::printf("  wrote      %s (%zu held-out readings: the same set-ups, measured after)\n",
                run.heldout_output.c_str(), run.heldout_readings);
}

// The largest identified errors, by significance, with what each stands for (the minimal-
// complete set folds the parameters it leaves out into the ones it keeps).
void printLargestErrors(const CalibrationRun& run) {
  const MachineModel& m = run.machine.model;
  const CalibrationResult& r = run.fit;
  std::vector<size_t> order(r.identified.size());
  for (size_t k = 0; k < order.size(); ++k) order[k] = k;
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) {
    return std::abs(r.params[r.identified[a]]) / r.uncertainty[a] >
           std::abs(r.params[r.identified[b]]) / r.uncertainty[b];
  });
  auto termsOf = [&](int p) -> const std::vector<AbsorbedTerm>* {
    const auto it = std::find(run.unknowns.begin(), run.unknowns.end(), p);
    return it == run.unknowns.end() ? nullptr : &run.absorbed[it - run.unknowns.begin()];
  };
  std::printf("  largest identified errors (value +- standard uncertainty):\n");
  for (size_t k = 0; k < std::min<size_t>(10, order.size()); ++k) {
    const int p = r.identified[order[k]];
    const double s = m.parameters[p].angular ? radToUrad(1.0) : mmToUm(1.0);
    std::printf("    %-10s %-18s %10.3f +- %.3f %s\n", m.parameters[p].iso_code.c_str(),
                m.parameters[p].thesis_name.c_str(), r.params[p] * s, r.uncertainty[order[k]] * s,
                m.parameters[p].angular ? "urad" : "um");
    const std::vector<AbsorbedTerm>* t = termsOf(p);
    if (t && !t->empty())
      std::printf("               stands for %s\n", standsFor(m, p, *t).c_str());
  }
}

void printCalibration(const CalibrationRun& run, const CalibrateInputs& in) {
  const MachineModel& m = run.machine.model;
  const CalibrationResult& r = run.fit;
  const BallbarTest& test = run.file.test;
  std::printf("tolver calibrate: %s from %zu readings in %zu set-ups\n", m.name.c_str(),
              test.readings.size(), test.setups.size());
  std::printf("  unknowns   %d (%zu machine parameters + 6 ball positions per set-up)\n",
              r.unknowns, r.identified.size());
  printTimeLine(m, run.design);
  std::printf("  solution   %s after %d iterations; rank %d, condition %.3g (column-scaled)\n",
              r.message.c_str(), r.iterations, r.rank, r.condition);
  if (run.prior_text == "none")
    std::printf(
        "  prior      none: the plain least-squares fit (beyond the calibrated ranges its "
        "polynomials extrapolate freely)\n");
  else
    std::printf(
        "  prior      %s: values the readings pin down weakly are drawn towards zero, so "
        "that predictions beyond the calibrated ranges are not worse than a perfect "
        "machine's\n",
        run.prior_text.c_str());
  printGross(in.readings, test, run.gross, in.keep_outliers, run.robust.with_all, r,
             run.robust.limit_reached);
  std::printf("  residual   RMS %.3f um, max %.3f um, sigma %.3f um (the %zu readings fitted)\n",
              mmToUm(r.rms_residual), mmToUm(r.max_residual), mmToUm(r.residual_sigma),
              run.used.readings.size());
  std::printf("  lack of fit %s\n", describeLackOfFit(run.lack_of_fit, 1e-3).c_str());
  if (run.lack_of_fit.tested && run.lack_of_fit.p_value < 1e-3)
    std::printf(
        "             the model lacks something the readings repeat: tolver diagnose looks for "
        "what\n");
  if (!r.held.empty()) {
    std::string names;
    for (int p : r.held) names += " " + m.parameters[p].iso_code;
    std::fprintf(
        stderr,
        "tolver: warning: the readings cannot see %zu parameters, held at their prior values "
        "(predictions that depend on them are unverified):%s\n",
        r.held.size(), names.c_str());
  }
  std::printf(
      "  unseen     a ball-bar cannot see where the part sits on the table (its position and "
      "its three rotations), where the tool tip is relative to the spindle, or the spindle's "
      "tilt against the machine's axes (the ball positions absorb all of them): predict, verify "
      "and compensate apply the set-up a shop measures (give its probed points with --probed, "
      "and a tram row for the spindle's tilt, which sets the tool axis; without them, the "
      "set-up that best fits the program), the tool preset\n");
  printLargestErrors(run);
  const HeldoutFigures& ho = run.heldout_figures;
  if (!run.heldout.readings.empty()) {
    std::printf(
        "  held-out   %d readings (%s): RMS %.3f -> %.3f um, max %.3f -> %.3f um "
        "(the prior machine with nominal balls -> the identified one)\n",
        ho.before.readings, in.heldout.c_str(), mmToUm(ho.before.rms), mmToUm(ho.after.rms),
        mmToUm(ho.before.max), mmToUm(ho.after.max));
  }
}

void printCalibrationRun(const CalibrationRun& run, const CalibrateInputs& in) {
  printWarnings(run.warnings);
  printCalibration(run, in);
  const CalibrationOutputs& out = run.outputs;
  std::printf("  written    %s + %s reproduce the fitted readings at RMS %.3f um",
              out.machine.c_str(), out.balls.c_str(), mmToUm(run.written.fit.rms));
  if (run.written.heldout.readings > 0)
    std::printf(", the held-out ones at %.3f um", mmToUm(run.written.heldout.rms));
  // The set-up is not in the machine file: the next command needs it again.
  if (!in.machine.setup.empty()) std::printf(" (with --setup %s)", in.machine.setup.c_str());
  std::printf("\n");
  std::printf("  wrote      %s (identified machine), %s (ball positions), %s (report)\n",
              out.machine.c_str(), out.balls.c_str(), out.report.c_str());
}

}  // namespace

// Long by design: the options of plan-ballbar, simulate-ballbar and calibrate, one per line.
void registerBallbar(CLI::App& app, Verdict* verdict) {
  {
    auto o = std::make_shared<PlanBallbarInputs>();
    CLI::App* cmd = app.add_subcommand(
        "plan-ballbar",
        "Plan a three-set-up ball-bar test: poses inside travel at the bar length, chosen for "
        "identifiability; writes the plan (CSV) and an NC program.");
    addMachineOptions(cmd, o->machine, "machine file (XML)");
    cmd->add_option("--length", o->lengths_mm,
                    "bar length, mm (default 150); a list (100,150,300) gives each set-up its "
                    "own, in turn")
        ->delimiter(',')
        ->check(CLI::PositiveNumber);
    cmd->add_option("--setups", o->plan.setups, "number of set-ups (default 3)")
        ->check(CLI::Range(1, 12));
    cmd->add_option("--poses", o->plan.poses, "poses in all (default 180)")
        ->check(CLI::Range(1, 100000));
    cmd->add_option("--seed", o->plan.seed, "random seed (default 1)");
    cmd->add_option("--reference-every", o->plan.reference_every,
                    "measure the set-up's first pose again after every N poses, a drift check "
                    "(default 8; 0: never)")
        ->check(CLI::Range(0, 100000));
    cmd->add_option("--for", o->program.cl,
                    "plan where this program cuts (CL or G-code; its set-up from --setup): poses "
                    "chosen by the tool tip's prediction variance at its points, and the expected "
                    "prediction uncertainty there");
    cmd->add_flag("--volume", o->volume,
                  "plan for predictions over the whole travel: poses chosen by the tool tip's "
                  "prediction variance at poses drawn over it, and the expected uncertainty there");
    cmd->add_option("--noise-um", o->noise_um,
                    "reading noise for the expected uncertainty, um (default 0.5)")
        ->check(CLI::PositiveNumber);
    cmd->add_option("--heldout", o->heldout,
                    "also plan N held-out poses of the same set-ups (written to <plan>_heldout.csv "
                    "and .nc), for calibrate/diagnose --heldout")
        ->check(CLI::Range(0, 100000));
    cmd->add_option("-o,--output", o->output, "plan to write (CSV)")->required();
    cmd->add_option("--gcode", o->gcode, "NC program to write (default: the plan path with .nc)");
    auto quiet = addQuietFlag(cmd);
    cmd->callback([o, verdict, quiet] {
      useOptionNames({{"cl", "--for"}, {"lengths_mm", "--length"}});
      ProgressBar bar(!*quiet);
      const PlanRun run = planBallbar(*o, progressOf(bar));
      printPlanRun(*o, run);
      *verdict = run.verdict;
    });
  }
  {
    auto o = std::make_shared<SimulateBallbarInputs>();
    CLI::App* cmd = app.add_subcommand(
        "simulate-ballbar",
        "The readings a machine with the given (true) errors would give for a plan.");
    addMachineOptions(cmd, o->machine, "the true machine (XML)");
    cmd->add_option("--plan", o->plan, "plan (CSV) from plan-ballbar")->required();
    cmd->add_option("--noise-um", o->noise_um, "reading noise, um (1 sigma; default 0)")
        ->check(CLI::NonNegativeNumber);
    cmd->add_option("--ball-error-um", o->ball_error_um,
                    "random ball position errors per set-up, um (1 sigma; default 0)")
        ->check(CLI::NonNegativeNumber);
    cmd->add_option("--balls", o->balls,
                    "ball positions per set-up (CSV, as calibrate writes them) instead of the "
                    "plan's nominal ones");
    cmd->add_option("--heldout-plan", o->heldout_plan,
                    "held-out poses (plan-ballbar --heldout): simulated on the same set-ups "
                    "(same ball errors), after the plan");
    cmd->add_option("--heldout-output", o->heldout_output,
                    "held-out readings to write (default: the output path with _heldout.csv)");
    cmd->add_option("--seconds-per-reading", o->seconds_per_reading,
                    "time_s step when the plan has none (default 20)");
    cmd->add_option("--seed", o->seed, "random seed (default 1)");
    cmd->add_option("-o,--output", o->output, "readings to write (CSV)")->required();
    cmd->callback([o, verdict] {
      const SimulationRun run = simulateBallbar(*o);
      printSimulation(*o, run);
      *verdict = run.verdict;
    });
  }
  {
    auto o = std::make_shared<CalibrateInputs>();
    CLI::App* cmd = app.add_subcommand(
        "calibrate",
        "Identify the machine's errors from ball-bar readings; writes the identified machine "
        "file and a report with uncertainties.");
    addMachineOptions(cmd, o->machine, "machine file (XML): topology and prior values");
    cmd->add_option("--readings", o->readings, "ball-bar readings (CSV)")->required();
    cmd->add_option("-o,--output", o->output, "identified machine file to write (XML)")->required();
    cmd->add_option("--report", o->report,
                    "report to write (JSON; default: the output path with .json)");
    cmd->add_option(
        "--heldout", o->heldout,
        "held-out readings (CSV) of the same set-ups, not fitted: RMS before and after");
    cmd->add_option("--balls", o->balls,
                    "identified ball positions to write (CSV; default: the output path with "
                    "_balls.csv)");
    cmd->add_option("--prior", o->prior,
                    "regularisation towards zero: auto (default: its scale from the readings' "
                    "evidence), none, or 'um,urad' per linear and angular coefficient");
    cmd->add_flag("--strict", o->strict, "refuse when some parameters cannot be identified");
    cmd->add_option(
           "--spindle-tilt-urad", o->spindle_tilt_urad,
           "prior of the spindle's tilt against the machine's axes (urad, 1 sigma), which a "
           "ball-bar cannot see (e.g. the tram tolerance over 2): added to every prediction's "
           "tool-axis band")
        ->check(CLI::Range(0.0, 1e5));
    cmd->add_flag("--keep-outliers", o->keep_outliers,
                  "fit every reading (gross readings are still named)");
    auto quiet = addQuietFlag(cmd);
    cmd->callback([o, verdict, quiet] {
      ProgressBar bar(!*quiet);
      const CalibrationRun run = calibrateMachine(*o, progressOf(bar));
      printCalibrationRun(run, *o);
      *verdict = run.verdict;
    });
  }
}

}  // namespace tolver::app
