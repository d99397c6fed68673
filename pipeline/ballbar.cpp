#include "pipeline/ballbar.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

#include "core/calibration/calibration.h"
#include "core/kinematics/inverse_kinematics.h"
#include "core/numerics/quantities.h"
#include "core/numerics/units.h"
#include "core/path/setup_search.h"
#include "io/common/io_error.h"
#include "io/machine/ballbar_file.h"
#include "io/report/calibration_report.h"

namespace tolver {
namespace {

std::string lengthText(const BallbarPlanOptions& p) {
  std::string out;
  char buf[32];
  for (double l : p.bar_lengths.empty() ? std::vector<double>{p.bar_length} : p.bar_lengths) {
    std::snprintf(buf, sizeof buf, "%s%.3f", out.empty() ? "" : ", ", l);
    out += buf;
  }
  return out + " mm";
}

// A program target: the program's poses (at most about 500); about 60 of them become the targets
// of an I-optimal design in `plan`.
std::vector<JointVector> programTargets(const ProgramOptions& po, const Machine& machine,
                                        BallbarPlanOptions& plan) {
  std::vector<JointVector> program_q;
  const ClProgram program = loadProgram(po, machine.model);
  int failed = 0, first = -1;
  jointRanges(machine.model, program.path, nullptr, &failed, &first);
  if (failed > 0)
    throw InputError(program.file, program.path[first].line, 0, "unreachable",
                     std::to_string(failed) +
                         " points need rotary angles outside travel with this "
                         "set-up; run tolver setup first");
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
  const size_t tstep = std::max<size_t>(1, program_q.size() / 60);
  for (size_t i = 0; i < program_q.size(); i += tstep) plan.target_poses.push_back(program_q[i]);
  return program_q;
}

// The whole travel as the target: poses drawn evenly over it (the rotary axes over theirs).
std::vector<JointVector> volumeTargets(const Machine& machine, BallbarPlanOptions& plan) {
  std::vector<JointVector> program_q;
  std::mt19937 rng(plan.seed + 104729u);
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
    plan.target_poses.push_back(program_q[i]);
  return program_q;
}

ExpectedUncertainty expectedAt(const Machine& machine, const std::vector<int>& unknowns,
                               const BallbarPlan& p, double noise_um,
                               const std::vector<JointVector>& q) {
  std::vector<double> u =
      expectedTipUncertainty(machine.model, unknowns, p.test, umToMm(noise_um), q);
  std::sort(u.begin(), u.end());
  return {mmToUm(u[u.size() / 2]), mmToUm(u.back())};
}

}  // namespace

PlanRun planBallbar(const PlanBallbarInputs& in, const Progress& progress) {
  PlanRun run;
  BallbarPlanOptions opt = in.plan;
  if (progress) opt.progress = [&progress](double f) { progress("choosing poses", f); };
  if (in.lengths_mm.size() == 1) opt.bar_length = in.lengths_mm[0];
  if (in.lengths_mm.size() > 1) opt.bar_lengths = in.lengths_mm;
  for (double l : in.lengths_mm)
    if (const std::string problem = outOfRange(Quantity::BarLength, l); !problem.empty())
      throw FieldError("lengths_mm", problem);
  if (!in.program.cl.empty() && in.volume)
    throw FieldError("volume", "give a program (" + inputName("cl") + ") or " +
                                   inputName("volume") + ", not both");
  run.machine = loadMachine(in.machine);
  const Machine& machine = run.machine;
  int prismatic = 0;
  for (const Axis& ax : machine.model.axes) prismatic += ax.isRotary() ? 0 : 1;
  if (prismatic != 3)
    throw InputError(
        in.machine.machine, 0, 0, "axes",
        "plan-ballbar places the tool ball with three prismatic axes; this machine has " +
            std::to_string(prismatic));
  run.output = in.output;
  run.gcode = in.gcode.empty() ? replaceExtension(in.output, ".nc") : in.gcode;
  checkOutputDir(run.output, "output");
  checkOutputDir(run.gcode, "gcode");
  run.unknowns = defaultCalibrationUnknowns(machine.model);
  run.lengths_text = lengthText(opt);
  // A target: poses chosen by the prediction variance of the tool tip at the program's poses
  // (I-optimal), modulo the set-up a shop measures; or over the whole travel.
  run.target_q = in.volume                ? volumeTargets(machine, opt)
                 : !in.program.cl.empty() ? programTargets(in.program, machine, opt)
                                          : std::vector<JointVector>{};
  run.target_text = in.volume ? "the whole travel" : in.program.cl;
  run.targets = opt.target_poses.size();
  run.plan = planBallbarTest(machine.model, run.unknowns, opt);
  const BallbarPlan& plan = run.plan;
  if (static_cast<int>(plan.test.readings.size()) < opt.poses)
    throw InputError(in.machine.machine, 0, 0, "plan",
                     "only " + std::to_string(plan.test.readings.size()) +
                         " poses inside travel were found for a " + run.lengths_text +
                         " bar; try another length or set-up");
  run.too_few_readings = static_cast<int>(plan.test.readings.size()) < 3 * plan.unknowns;
  char head[256];
  std::snprintf(head, sizeof head,
                "tolver ball-bar plan for %s: bar %s, %d set-ups, %zu poses, seed %u",
                machine.model.name.c_str(), run.lengths_text.c_str(),
                static_cast<int>(plan.test.setups.size()), plan.test.readings.size(), opt.seed);
  // Held-out poses: other poses of the same set-ups (random, not chosen for the fit), in a plan
  // of their own, measured after the fit's.
  if (in.heldout > 0) {
    BallbarPlanOptions ho = opt;
    ho.geometry = plan.test.setups;
    ho.poses = in.heldout;
    ho.seed = opt.seed + 7919u;
    ho.reference_every = 0;
    ho.candidates_per_pose = 1;
    if (progress) ho.progress = [&progress](double f) { progress("choosing held-out poses", f); };
    run.held = planBallbarTest(machine.model, run.unknowns, ho);
    run.heldout_output = replaceExtension(in.output, "") + "_heldout.csv";
    run.heldout_gcode = replaceExtension(run.heldout_output, ".nc");
    checkOutputDir(run.heldout_output, "heldout");
  }
  OutputSet files;  // the plan, its NC program and the held-out ones: all or none
  files.add(run.output, formatBallbarCsv(machine.model, plan.test, false, {head}));
  files.add(run.gcode, formatBallbarGcode(machine.model, plan.test, in.feed, 2.0));
  if (in.heldout > 0) {
    files.add(run.heldout_output, formatBallbarCsv(machine.model, run.held.test, false,
                                                   {"held-out poses for " + in.output +
                                                    " (measure them too; calibrate --heldout)"}));
    files.add(run.heldout_gcode, formatBallbarGcode(machine.model, run.held.test, in.feed, 2.0));
  }
  files.commit();
  if (!run.target_q.empty()) {
    // What the plan would give at the target before anyone measures, and what the default plan
    // (the whole travel, D-optimal, the same size) would give there.
    BallbarPlanOptions whole = opt;
    if (progress)
      whole.progress = [&progress](double f) { progress("the default plan, to compare", f); };
    whole.target_poses.clear();
    whole.geometry.clear();
    const BallbarPlan general = planBallbarTest(machine.model, run.unknowns, whole);
    run.expected = expectedAt(machine, run.unknowns, plan, in.noise_um, run.target_q);
    run.expected_default = expectedAt(machine, run.unknowns, general, in.noise_um, run.target_q);
    run.gain = run.expected_default.median_um > 0
                   ? 1.0 - run.expected.median_um / run.expected_default.median_um
                   : 0.0;
  }
  return run;
}

SimulationRun simulateBallbar(const SimulateBallbarInputs& in) {
  if (!(in.noise_um >= 0 && in.noise_um < 1e4))
    throw FieldError("noise_um", "expected 0 to 1e4 um");
  if (!(in.ball_error_um >= 0 && in.ball_error_um < 1e4))
    throw FieldError("ball_error_um", "expected 0 to 1e4 um");
  if (!(std::abs(in.seconds_per_reading) < 1e6))
    throw FieldError("seconds_per_reading", "expected a finite step below 1e6 s");
  SimulationRun run;
  run.machine = loadMachine(in.machine);
  const Machine& machine = run.machine;
  BallbarFile f = readBallbarFile(in.plan, machine.model, false);
  run.output = in.output;
  checkOutputDir(run.output, "output");
  std::mt19937 rng(in.seed);
  std::normal_distribution<double> noise(0.0, umToMm(in.noise_um)),
      ball(0.0, umToMm(in.ball_error_um));
  // Ball positions: the plan's nominal ones, or those of `balls` (identified by calibrate), plus
  // the random errors asked for.
  std::vector<BallErrors> balls = in.balls.empty() ? std::vector<BallErrors>(f.test.setups.size())
                                                   : readBallPositionsFile(in.balls, f.test);
  for (BallErrors& b : balls) {
    b.table_w += Eigen::Vector3d(ball(rng), ball(rng), ball(rng));
    b.tool_t += Eigen::Vector3d(ball(rng), ball(rng), ball(rng));
  }
  const ForwardKinematics fk(machine.model, machine.params);
  for (size_t i = 0; i < f.test.readings.size(); ++i) {
    BallbarReading& r = f.test.readings[i];
    if (std::isnan(r.context.time_s))
      r.context.time_s = in.seconds_per_reading * static_cast<double>(i);
    r.length =
        ballbarLength(fk, r.q, f.test.setups[r.setup], balls[r.setup], &r.context) + noise(rng);
  }
  run.readings = f.test.readings.size();
  // Held-out poses: measured after the plan, on the same set-ups (the same ball errors), time
  // running on.
  BallbarTest held;
  if (!in.heldout_plan.empty()) {
    run.heldout_output = in.heldout_output.empty()
                             ? replaceExtension(in.output, "") + "_heldout.csv"
                             : in.heldout_output;
    held = readBallbarFile(in.heldout_plan, machine.model, false).test;
    alignHeldout(held, f.test, in.heldout_plan, in.plan);
    checkOutputDir(run.heldout_output, "heldout_output");
    const size_t n = f.test.readings.size();
    for (size_t i = 0; i < held.readings.size(); ++i) {
      BallbarReading& r = held.readings[i];
      if (std::isnan(r.context.time_s))
        r.context.time_s = in.seconds_per_reading * static_cast<double>(n + i);
      r.length =
          ballbarLength(fk, r.q, held.setups[r.setup], balls[r.setup], &r.context) + noise(rng);
    }
    run.heldout_readings = held.readings.size();
  }
  char head[256];
  std::snprintf(head, sizeof head,
                "simulated by tolver from %s: noise %.3f um, ball errors %.3f um, seed %u",
                in.machine.machine.c_str(), in.noise_um, in.ball_error_um, in.seed);
  OutputSet files;  // the readings and the held-out ones: both or neither
  files.add(run.output, formatBallbarCsv(machine.model, f.test, true, {head}));
  if (!in.heldout_plan.empty())
    files.add(run.heldout_output,
              formatBallbarCsv(machine.model, held, true,
                               {std::string(head) + "; held-out poses of " + in.heldout_plan +
                                ", measured after the plan"}));
  files.commit();
  return run;
}

}  // namespace tolver
