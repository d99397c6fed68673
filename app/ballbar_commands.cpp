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
#include "core/calibration/ballbar_plan.h"
#include "core/calibration/calibration.h"
#include "core/kinematics/inverse_kinematics.h"
#include "core/numerics/units.h"
#include "core/path/setup_search.h"
#include "io/common/io_error.h"
#include "io/common/text_util.h"
#include "io/machine/ballbar_file.h"
#include "io/machine/machine_file.h"
#include "io/report/calibration_report.h"
#include "pipeline/calibrate.h"

namespace tolver::app {
namespace {

struct PlanOptions {
  MachineOptions machine;
  BallbarPlanOptions plan;
  std::string output, gcode;
  double feed = 2000.0;
  std::vector<double> lengths;
  int heldout = 0;
  ProgramOptions program;  // --for: plan where this program cuts
  double noise_um = 0.5;   // for the expected prediction uncertainty
  bool volume = false;     // --volume: plan for predictions over the whole travel
  PlanOptions() { plan.reference_every = 8; }
};

std::string lengthText(const BallbarPlanOptions& p) {
  std::string out;
  char buf[32];
  for (double l : p.bar_lengths.empty() ? std::vector<double>{p.bar_length} : p.bar_lengths) {
    std::snprintf(buf, sizeof buf, "%s%.3f", out.empty() ? "" : ", ", l);
    out += buf;
  }
  return out + " mm";
}

// --for PROGRAM: the program's poses (at most about 500), the targets of an I-optimal design
// (about 60 of them) in o.plan.
std::vector<JointVector> programTargets(PlanOptions& o, const Machine& machine) {
  std::vector<JointVector> program_q;
  const ClProgram program = loadProgram(o.program, machine.model);
  int failed = 0, first = -1;
  const std::vector<AxisRange> ranges =
      jointRanges(machine.model, program.path, nullptr, &failed, &first);
  if (failed > 0)
    throw InputError(program.file, program.path[first].line, 0, "unreachable",
                     std::to_string(failed) +
                         " points need rotary angles outside travel with this "
                         "set-up; run tolver setup first");
  (void)ranges;  // rotary travel checked; the poses themselves may go anywhere
  // The set-up geometry stays the default: table balls on the part's points or tool balls at
  // several lengths gave larger expected uncertainties where the program cuts (measured on
  // the cone sample), the choice of poses is what helps.
  const std::vector<ClPoint>& path = program.path;
  const size_t step = std::max<size_t>(1, path.size() / 500);
  const InverseKinematics ik(machine.model);
  for (size_t i = 0; i < path.size(); i += step) {
    const IkSolution sol =
        ik.solve(path[i].p_w, path[i].u_w, program_q.empty() ? nullptr : &program_q.back());
    if (sol.status == IkStatus::Ok) program_q.push_back(sol.q);
  }
  // A subset of the program's poses as the targets of the design.
  const size_t tstep = std::max<size_t>(1, program_q.size() / 60);
  for (size_t i = 0; i < program_q.size(); i += tstep) o.plan.target_poses.push_back(program_q[i]);
  return program_q;
}

// --volume: poses drawn evenly over the travel (the rotary axes over theirs): the predictions the
// plan should serve are anywhere the machine can go.
std::vector<JointVector> volumeTargets(PlanOptions& o, const Machine& machine) {
  std::vector<JointVector> program_q;
  if (!program_q.empty())
    throw InputError("--volume", 0, 0, "--volume", "give --for PROGRAM or --volume, not both");
  // Poses drawn evenly over the travel (the rotary axes over theirs): the predictions the plan
  // should serve are anywhere the machine can go.
  std::mt19937 rng(o.plan.seed + 104729u);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int i = 0; i < 500; ++i) {
    JointVector q(machine.model.axes.size());
    for (size_t a = 0; a < machine.model.axes.size(); ++a) {
      const Axis& ax = machine.model.axes[a];
      q[a] = ax.travel_min + (ax.travel_max - ax.travel_min) * u(rng);
    }
    program_q.push_back(q);
  }
  for (size_t i = 0; i < program_q.size(); i += program_q.size() / 60)
    o.plan.target_poses.push_back(program_q[i]);
  return program_q;
}

void printPlan(const PlanOptions& o, const Machine& machine, const BallbarPlan& plan,
               size_t unknown_params) {
  std::printf("tolver plan-ballbar: %s\n", machine.model.name.c_str());
  std::printf("  bar %s, %zu set-ups, %zu poses (%d sampled, %d outside travel)\n",
              lengthText(o.plan).c_str(), plan.test.setups.size(), plan.test.readings.size(),
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
      plan.unknowns, unknown_params, plan.rank, plan.condition);
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
  if (static_cast<int>(plan.test.readings.size()) < 3 * plan.unknowns)
    std::fprintf(
        stderr,
        "tolver: warning: %zu readings for %d unknowns (fewer than 3 per unknown): the fit "
        "will follow the noise; ask for at least --poses %d\n",
        plan.test.readings.size(), plan.unknowns, 3 * plan.unknowns);
}

// What the plan would give where the program cuts (or over the travel), before anyone measures;
// and what the default plan (the whole travel, D-optimal) would give there.
void printExpected(const PlanOptions& o, const Machine& machine, const std::vector<int>& unknowns,
                   const BallbarPlan& plan, const std::vector<JointVector>& program_q,
                   const std::string& for_text) {
  // What the plan would give where the program cuts, before anyone measures; and what the
  // default plan (the whole travel) would give there.
  BallbarPlanOptions whole = o.plan;
  whole.target_poses.clear();
  whole.geometry.clear();
  const BallbarPlan general = planBallbarTest(machine.model, unknowns, whole);
  auto stats = [&](const BallbarPlan& p, double* med, double* mx) {
    std::vector<double> u =
        expectedTipUncertainty(machine.model, unknowns, p.test, umToMm(o.noise_um), program_q);
    std::sort(u.begin(), u.end());
    *med = u[u.size() / 2];
    *mx = u.back();
  };
  double m1, x1, m0, x0;
  stats(plan, &m1, &x1);
  stats(general, &m0, &x0);
  std::printf(
      "  for        %s: poses chosen by the tool tip's prediction variance at %zu of its "
      "%s, after the set-up a shop measures (I-optimal)\n",
      for_text.c_str(), o.plan.target_poses.size(), o.volume ? "poses" : "points");
  std::printf(
      "  expected   tip uncertainty %s (1 sigma, %.2f um readings, after the measured "
      "set-up, at %zu poses): median %.3f um, max %.3f um; the D-optimal plan of the same "
      "size: median %.3f um, max %.3f um\n",
      o.volume ? "over the whole travel" : "where the program cuts", o.noise_um, program_q.size(),
      mmToUm(m1), mmToUm(x1), mmToUm(m0), mmToUm(x0));
  // What the targeted plan buys, and when it buys little: the expected figures are those of a
  // model that fits (a real machine's realised uncertainty varies more from machine to machine
  // than a gain of a few per cent).
  const double gain = m0 > 0 ? 1.0 - m1 / m0 : 0.0;
  if (gain >= 0.1)
    std::printf("  buys       an expected %.0f %% lower median tip uncertainty at the target than the default plan\n",
                100.0 * gain);
  else
    std::printf("  buys       little: the expected median tip uncertainty at the target is %.0f %% %s than the "
                "default plan's, less than the spread between machines; the default plan (without --for or "
                "--volume) is as good here\n",
                100.0 * std::abs(gain), gain >= 0 ? "lower" : "higher");
}

void runPlan(PlanOptions o) {
  if (o.lengths.size() == 1) o.plan.bar_length = o.lengths[0];
  if (o.lengths.size() > 1) o.plan.bar_lengths = o.lengths;
  const Machine machine = loadMachine(o.machine);
  {
    int prismatic = 0;
    for (const Axis& ax : machine.model.axes) prismatic += ax.isRotary() ? 0 : 1;
    if (prismatic != 3)
      throw InputError(o.machine.machine, 0, 0, "axes",
                       "plan-ballbar places the tool ball with three prismatic axes; this machine has " +
                           std::to_string(prismatic));
  }
  const std::string gcode = o.gcode.empty() ? replaceExtension(o.output, ".nc") : o.gcode;
  checkOutputDir(o.output, "-o");
  checkOutputDir(gcode, "--gcode");
  const std::vector<int> unknowns = defaultCalibrationUnknowns(machine.model);
  // --for: poses chosen by the prediction variance of the tool tip at the program's poses
  // (I-optimal), modulo the set-up a shop measures; --volume: over the whole travel.
  if (!o.program.cl.empty() && o.volume)
    throw InputError("--volume", 0, 0, "--volume", "give --for PROGRAM or --volume, not both");
  const std::vector<JointVector> program_q = o.volume                ? volumeTargets(o, machine)
                                             : !o.program.cl.empty() ? programTargets(o, machine)
                                                                     : std::vector<JointVector>{};
  const std::string for_text = o.volume ? "the whole travel" : o.program.cl;
  const BallbarPlan plan = planBallbarTest(machine.model, unknowns, o.plan);
  if (static_cast<int>(plan.test.readings.size()) < o.plan.poses)
    throw InputError(o.machine.machine, 0, 0, "plan",
                     "only " + std::to_string(plan.test.readings.size()) +
                         " poses inside travel were found for a " + lengthText(o.plan) +
                         " bar; try another length or set-up");
  char head[256];
  std::snprintf(head, sizeof head,
                "tolver ball-bar plan for %s: bar %s, %d set-ups, %zu poses, seed %u",
                machine.model.name.c_str(), lengthText(o.plan).c_str(),
                static_cast<int>(plan.test.setups.size()), plan.test.readings.size(), o.plan.seed);
  // Held-out poses: other poses of the same set-ups (random, not chosen for the fit), in a plan
  // of their own, measured after the fit's.
  BallbarPlan held;
  const std::string held_file = replaceExtension(o.output, "") + "_heldout.csv";
  if (o.heldout > 0) {
    BallbarPlanOptions ho = o.plan;
    ho.geometry = plan.test.setups;
    ho.poses = o.heldout;
    ho.seed = o.plan.seed + 7919u;
    ho.reference_every = 0;
    ho.candidates_per_pose = 1;
    held = planBallbarTest(machine.model, unknowns, ho);
    checkOutputDir(held_file, "--heldout");
  }
  OutputSet files;  // the plan, its NC program and the held-out ones: all or none
  files.add(o.output, formatBallbarCsv(machine.model, plan.test, false, {head}));
  files.add(gcode, formatBallbarGcode(machine.model, plan.test, o.feed, 2.0));
  if (o.heldout > 0) {
    files.add(held_file, formatBallbarCsv(machine.model, held.test, false,
                                          {"held-out poses for " + o.output +
                                           " (measure them too; calibrate --heldout)"}));
    files.add(replaceExtension(held_file, ".nc"),
              formatBallbarGcode(machine.model, held.test, o.feed, 2.0));
  }
  files.commit();
  printPlan(o, machine, plan, unknowns.size());
  if (!program_q.empty()) printExpected(o, machine, unknowns, plan, program_q, for_text);
  std::printf("  wrote      %s (plan), %s (NC program)\n", o.output.c_str(), gcode.c_str());
  if (o.heldout > 0)
    std::printf(
        "  wrote      %s, %s (%zu held-out poses: measure them after the plan, give them "
        "to calibrate --heldout)\n",
        held_file.c_str(), replaceExtension(held_file, ".nc").c_str(), held.test.readings.size());
}

struct SimulateOptions {
  MachineOptions machine;
  std::string plan, output, balls, heldout_plan, heldout_output;
  double noise_um = 0.0;
  double ball_error_um = 0.0;
  double seconds_per_reading = 20.0;
  unsigned seed = 1;
};

void runSimulate(const SimulateOptions& o) {
  const Machine machine = loadMachine(o.machine);
  BallbarFile f = readBallbarFile(o.plan, machine.model, false);
  checkOutputDir(o.output, "-o");
  std::mt19937 rng(o.seed);
  std::normal_distribution<double> noise(0.0, umToMm(o.noise_um)),
      ball(0.0, umToMm(o.ball_error_um));
  // Ball positions: the plan's nominal ones, or those of --balls (identified by calibrate), plus
  // the random errors asked for.
  std::vector<BallErrors> balls = o.balls.empty() ? std::vector<BallErrors>(f.test.setups.size())
                                                  : readBallPositionsFile(o.balls, f.test);
  for (BallErrors& b : balls) {
    b.table_w += Eigen::Vector3d(ball(rng), ball(rng), ball(rng));
    b.tool_t += Eigen::Vector3d(ball(rng), ball(rng), ball(rng));
  }
  const ForwardKinematics fk(machine.model, machine.params);
  for (size_t i = 0; i < f.test.readings.size(); ++i) {
    BallbarReading& r = f.test.readings[i];
    if (std::isnan(r.context.time_s))
      r.context.time_s = o.seconds_per_reading * static_cast<double>(i);
    r.length =
        ballbarLength(fk, r.q, f.test.setups[r.setup], balls[r.setup], &r.context) + noise(rng);
  }
  // Held-out poses: measured after the plan, on the same set-ups (the same ball errors), time
  // running on.
  BallbarTest held;
  const std::string held_out =
      o.heldout_output.empty() ? replaceExtension(o.output, "") + "_heldout.csv" : o.heldout_output;
  if (!o.heldout_plan.empty()) {
    held = readBallbarFile(o.heldout_plan, machine.model, false).test;
    alignHeldout(held, f.test, o.heldout_plan, o.plan);
    checkOutputDir(held_out, "--heldout-output");
    const size_t n = f.test.readings.size();
    for (size_t i = 0; i < held.readings.size(); ++i) {
      BallbarReading& r = held.readings[i];
      if (std::isnan(r.context.time_s))
        r.context.time_s = o.seconds_per_reading * static_cast<double>(n + i);
      r.length =
          ballbarLength(fk, r.q, held.setups[r.setup], balls[r.setup], &r.context) + noise(rng);
    }
  }
  char head[256];
  std::snprintf(head, sizeof head,
                "simulated by tolver from %s: noise %.3f um, ball errors %.3f um, seed %u",
                o.machine.machine.c_str(), o.noise_um, o.ball_error_um, o.seed);
  writeFileAtomically(o.output, formatBallbarCsv(machine.model, f.test, true, {head}));
  if (!o.heldout_plan.empty())
    writeFileAtomically(held_out, formatBallbarCsv(machine.model, held, true,
                                                   {std::string(head) + "; held-out poses of " +
                                                    o.heldout_plan + ", measured after the plan"}));
  std::printf("tolver simulate-ballbar: %zu readings from %s (%s)\n", f.test.readings.size(),
              machine.model.name.c_str(), o.machine.machine.c_str());
  std::printf("  noise %.3f um (1 sigma), ball position errors %.3f um (1 sigma), seed %u\n",
              o.noise_um, o.ball_error_um, o.seed);
  std::printf("  wrote      %s\n", o.output.c_str());
  if (!o.heldout_plan.empty())
    std::printf("  wrote      %s (%zu held-out readings: the same set-ups, measured after)\n",
                held_out.c_str(), held.readings.size());
}

struct CalibrateOptions {
  CalibrateInputs in;
  std::string output, report, balls;
};

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

void printCalibration(const CalibrationRun& run, const CalibrateOptions& o) {
  const MachineModel& m = run.machine.model;
  const CalibrationResult& r = run.fit;
  const BallbarTest& test = run.file.test;
  std::printf("tolver calibrate: %s from %zu readings in %zu set-ups\n", m.name.c_str(),
              test.readings.size(), test.setups.size());
  std::printf("  unknowns   %d (%zu machine parameters + 6 ball positions per set-up)\n",
              r.unknowns, r.identified.size());
  for (const std::string& w : testDesignWarnings(m, test, r.unknowns))
    std::fprintf(stderr, "tolver: warning: %s: %s\n", o.in.readings.c_str(), w.c_str());
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
  printGross(o.in.readings, test, run.gross, o.in.keep_outliers, run.robust.with_all, r,
             run.robust.limit_reached);
  std::printf("  residual   RMS %.3f um, max %.3f um, sigma %.3f um (the %zu readings fitted)\n",
              mmToUm(r.rms_residual), mmToUm(r.max_residual), mmToUm(r.residual_sigma),
              run.used.readings.size());
  std::printf("  lack of fit %s\n", describeLackOfFit(run.lack_of_fit, 1e-3).c_str());
  if (run.lack_of_fit.tested && run.lack_of_fit.p_value < 1e-3)
    std::printf("             the model lacks something the readings repeat: tolver diagnose looks for what\n");
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
        ho.before.readings, o.in.heldout.c_str(), mmToUm(ho.before.rms), mmToUm(ho.after.rms),
        mmToUm(ho.before.max), mmToUm(ho.after.max));
    heldoutWarning(o.in.heldout, ho.after, r.rms_residual);
  }
}

void runCalibrate(const CalibrateOptions& o, int* exit_code) {
  const CalibrationOutputs out = calibrationOutputs(o.output, o.balls, o.report);
  const CalibrationRun run = runCalibration(o.in);
  for (const std::string& w : run.file.warnings)
    std::fprintf(stderr, "tolver: warning: %s: %s\n", o.in.readings.c_str(), w.c_str());
  printCalibration(run, o);
  // The machine, its ball positions and the report as a set: all three or none.
  const WrittenCheck check = writeCalibration(run, o.in, out);
  std::printf("  written    %s + %s reproduce the fitted readings at RMS %.3f um",
              out.machine.c_str(), out.balls.c_str(), mmToUm(check.fit.rms));
  if (check.heldout.readings > 0)
    std::printf(", the held-out ones at %.3f um", mmToUm(check.heldout.rms));
  std::printf("\n");
  std::printf("  wrote      %s (identified machine), %s (ball positions), %s (report)\n",
              out.machine.c_str(), out.balls.c_str(), out.report.c_str());
  *exit_code = run.fit.status == CalibrationStatus::Converged ? 0 : 1;
}

}  // namespace

// Long by design: the options of plan-ballbar, simulate-ballbar and calibrate, one per line.
void registerBallbar(CLI::App& app, int* exit_code) {
  {
    auto o = std::make_shared<PlanOptions>();
    CLI::App* cmd = app.add_subcommand(
        "plan-ballbar",
        "Plan a three-set-up ball-bar test: poses inside travel at the bar length, chosen for "
        "identifiability; writes the plan (CSV) and an NC program.");
    addMachineOptions(cmd, o->machine, "machine file (XML)");
    cmd->add_option("--length", o->lengths,
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
    cmd->callback([o, exit_code] {
      runPlan(*o);
      *exit_code = 0;
    });
  }
  {
    auto o = std::make_shared<SimulateOptions>();
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
    cmd->callback([o, exit_code] {
      runSimulate(*o);
      *exit_code = 0;
    });
  }
  {
    auto o = std::make_shared<CalibrateOptions>();
    CLI::App* cmd = app.add_subcommand(
        "calibrate",
        "Identify the machine's errors from ball-bar readings; writes the identified machine "
        "file and a report with uncertainties.");
    addMachineOptions(cmd, o->in.machine, "machine file (XML): topology and prior values");
    cmd->add_option("--readings", o->in.readings, "ball-bar readings (CSV)")->required();
    cmd->add_option("-o,--output", o->output, "identified machine file to write (XML)")->required();
    cmd->add_option("--report", o->report,
                    "report to write (JSON; default: the output path with .json)");
    cmd->add_option(
        "--heldout", o->in.heldout,
        "held-out readings (CSV) of the same set-ups, not fitted: RMS before and after");
    cmd->add_option("--balls", o->balls,
                    "identified ball positions to write (CSV; default: the output path with "
                    "_balls.csv)");
    cmd->add_option("--prior", o->in.prior,
                    "regularisation towards zero: auto (default: its scale from the readings' "
                    "evidence), none, or 'um,urad' per linear and angular coefficient");
    cmd->add_flag("--strict", o->in.strict, "refuse when some parameters cannot be identified");
    cmd->add_option("--spindle-tilt-urad", o->in.spindle_tilt_urad,
                    "prior of the spindle's tilt against the machine's axes (urad, 1 sigma), which a "
                    "ball-bar cannot see (e.g. the tram tolerance over 2): added to every prediction's "
                    "tool-axis band")
        ->check(CLI::Range(0.0, 1e5));
    cmd->add_flag("--keep-outliers", o->in.keep_outliers,
                  "fit every reading (gross readings are still named)");
    cmd->callback([o, exit_code] { runCalibrate(*o, exit_code); });
  }
}

}  // namespace tolver::app
