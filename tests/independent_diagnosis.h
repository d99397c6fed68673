#pragma once
// One diagnosis case on independently simulated readings (tests/independent_ballbar.h): a
// Matsuura with random cubic errors and one or two undeclared effects, a three-set-up test
// (fit readings with a return to a reference pose every 8, and held-out readings at other poses
// measured in between), run through `diagnose` as the CLI runs it, judged on the held-out
// readings through the files a user takes away (machine file + ball positions, written and
// read back).
#include <filesystem>
#include <string>
#include <vector>

#include "core/calibration/ballbar_plan.h"
#include "core/calibration/calibration.h"
#include "core/diagnosis/diagnosis.h"
#include "core/model/effects.h"
#include "independent_ballbar.h"
#include "io/common/io_error.h"
#include "io/machine/ballbar_file.h"
#include "io/machine/machine_file.h"
#include "io/report/calibration_report.h"
#include "test_support.h"

namespace tolver::test {

struct DiagnosisCase {
  std::string name;                      // "reversal Y ey"
  std::vector<indep::Undeclared> truth;  // empty: clean
  // What tolver should name: (type name, axis name, component) per effect.
  std::vector<std::tuple<std::string, std::string, int>> expected;
  // An effect the library does not have: right when diagnose adds nothing and says the residual
  // still follows `unexplained_variable`.
  std::string unexplained_variable;
  // Outside the library and seen only as a lack of fit: right when the verdict is "incomplete".
  bool lack_of_fit = false;
};

struct DiagnosisOutcome {
  bool named_right = false;  // every expected effect added, nothing else (clean: nothing)
  std::vector<std::string> added;
  std::string message;
  bool unexplained = false;  // diagnose said so
  std::string unexplained_variable;
  double heldout_before_um = 0, heldout_after_um = 0;  // through the written files
  double written_vs_memory_um = 0;                     // |RMS written - RMS in memory|
  int gross_removed = 0;
  bool withdrawn = false;  // the final check took the effects back
  DiagnosisVerdict verdict = DiagnosisVerdict::NothingMissing;
  std::vector<std::string> implausible;  // candidates refused for their fitted value
  double heldout_gain_um2 = 0,
         heldout_gain_se_um2 = 0;              // mean squared held-out gain, its standard error
  double cv_gain_um2 = 0, cv_gain_se_um2 = 0;  // the same over the cross-validation's folds
  double lack_of_fit_p = 1;                    // of the final fit (1 when not tested)
  bool held_stayed_held = true;  // parameters the base fit held are at their prior values
  int held = 0;                  // how many the base fit held
};

// The independent simulator's set-ups for a plan's (ball position errors of 10 um, 1 sigma, drawn
// from ball_seed) and its poses (in the plan's order).
inline std::vector<indep::Setup> independentSetups(const BallbarTest& plan, unsigned ball_seed) {
  std::vector<indep::Setup> setups;
  std::mt19937 rng(ball_seed);
  std::normal_distribution<double> ball(0.0, 0.01);
  for (const BallbarSetup& s : plan.setups) {
    indep::Setup is;
    is.id = s.id;
    is.table_ball_w = s.table_ball_w;
    is.tool_ball_t = s.tool_ball_t;
    is.table_error_w = Eigen::Vector3d(ball(rng), ball(rng), ball(rng));
    is.tool_error_t = Eigen::Vector3d(ball(rng), ball(rng), ball(rng));
    setups.push_back(is);
  }
  return setups;
}

inline std::vector<indep::Pose> independentPoses(const BallbarTest& plan) {
  std::vector<indep::Pose> poses;
  for (const BallbarReading& r : plan.readings) {
    indep::Pose p;
    p.setup = r.setup;
    for (int a = 0; a < 5; ++a) p.q[a] = r.q[a];
    poses.push_back(p);
  }
  return poses;
}

// A truth machine measured on a plan (0.5 um noise from noise_seed, 20 s per reading) and
// calibrated by tolver from the CSV it writes, as `calibrate` does (regularised: --prior auto),
// the identified machine read back from its machine file.
inline Machine calibrateOnIndependent(const Machine& nominal, const std::vector<int>& unknowns,
                                      const indep::Machine& truth, const BallbarTest& plan,
                                      unsigned ball_seed, unsigned noise_seed, bool regularised,
                                      const std::string& dir, CalibrationResult* fit = nullptr) {
  const std::vector<indep::Setup> setups = independentSetups(plan, ball_seed);
  std::vector<indep::Pose> poses = independentPoses(plan);
  indep::measure(truth, poses, setups, 20.0, 0.5e-3, noise_seed);
  std::filesystem::create_directories(dir);
  indep::writeCsv(dir + "/fit.csv", poses, setups, false);
  const BallbarFile f = readBallbarFile(dir + "/fit.csv", nominal.model, true);
  CalibrationResult r = calibrate(nominal.model, nominal.params, f.test, unknowns);
  if (regularised) {
    PriorScaleEvidence evidence;
    const CalibrationOptions ro =
        evidencePrior(nominal.model, f.test, r, CalibrationOptions{}, nullptr, &evidence);
    const std::vector<int> free_identified = r.identified;
    r = calibrate(nominal.model, nominal.params, f.test, unknowns, ro);
    marginalisePriorScale(evidence, free_identified, &r);
  }
  Machine id = nominal;
  id.params = r.params;
  id.identification =
      identificationUncertainty(r, f.test, static_cast<int>(nominal.model.axes.size()));
  writeFileAtomically(dir + "/id.xml", formatMachineXml(id, "independent calibration"));
  if (fit) *fit = r;
  return readMachineFile(dir + "/id.xml");
}

// The cases: each kind of undeclared effect, two and three at once, one outside the library.
inline std::vector<DiagnosisCase> diagnosisCases() {
  using indep::Undeclared;
  const int X = indep::kX, Y = indep::kY, Z = indep::kZ, A = indep::kA, C = indep::kC;
  return {
      {"none", {}, {}},
      {"Y reversal 8 um", {{"reversal", Y, 1, 8e-3}}, {{"reversal", "Y", 1}}},
      {"X periodic 4 um, 16 mm", {{"periodic", X, 0, 4e-3, 16.0, 0.7}}, {{"periodic", "X", 0}}},
      {"C 2nd harmonic 5 um (ex)", {{"harmonic", C, 0, 5e-3, 2.0, 0.4}}, {{"harmonics", "C", 0}}},
      {"Z warm-up 20 um, 1200 s", {{"warmup", Z, 2, 20e-3, 1200.0}}, {{"warmup", "Z", 2}}},
      {"X straightness in Y, 6th order, 6 um",
       {{"straightness6", X, 1, 6e-3}},
       {{"chebyshev", "X", 1}}},
      {"Y drift 10 um/h", {{"drift", Y, 1, 10e-3}}, {{"drift", "Y", 1}}},
      {"Y pitch (gx) warm-up 60 urad, 1800 s",
       {{"warmup", Y, 3, 60e-6, 1800.0}},
       {{"warmup", "Y", 3}}},
      {"outside the library: X periodic 4 um, 70 mm",
       {{"periodic", X, 0, 4e-3, 70.0, 0.2}},
       {},
       "X"},
      {"outside the library: A tilt about y by direction, +-20 urad",
       {{"reversal", A, 4, 40e-6}},
       {},
       "",
       true},
      {"Y reversal + X periodic",
       {{"reversal", Y, 1, 8e-3}, {"periodic", X, 0, 4e-3, 16.0, 0.7}},
       {{"reversal", "Y", 1}, {"periodic", "X", 0}}},
      {"Y reversal + X periodic + Z warm-up",
       {{"reversal", Y, 1, 8e-3},
        {"periodic", X, 0, 4e-3, 16.0, 0.7},
        {"warmup", Z, 2, 20e-3, 1200.0}},
       {{"reversal", "Y", 1}, {"periodic", "X", 0}, {"warmup", "Z", 2}}},
  };
}

// on_axis: all tool balls on the spindle axis (else 25 mm off it, the planner's default).
// heldout_without_effects: the held-out readings come from the machine without the undeclared
// effects (a test of the final check: the augmented model must then be withdrawn).
inline DiagnosisOutcome runDiagnosisCase(const DiagnosisCase& c, bool on_axis, unsigned seed,
                                         const std::string& dir,
                                         bool heldout_without_effects = false,
                                         bool diagnose_with_heldout = true) {
  DiagnosisOutcome out;
  const Machine nominal = readMachineFile(sourcePath("resources/machines/matsuura_mc760vx.xml"));
  const std::vector<int> unknowns = defaultCalibrationUnknowns(nominal.model);
  // Poses: 320 for the fit (with a reference pose every 8), 80 held out, interleaved in time.
  BallbarPlanOptions po;
  po.poses = 400;
  po.seed = 7000 + seed;
  po.reference_every = 8;
  po.geometry = defaultBallbarSetups(3);
  if (on_axis)
    for (BallbarSetup& s : po.geometry) s.tool_ball_t = Eigen::Vector3d(0, 0, 0);
  const BallbarPlan plan = planBallbarTest(nominal.model, unknowns, po);
  const std::vector<indep::Setup> setups = independentSetups(plan.test, 9000 + seed);
  std::vector<indep::Pose> poses = independentPoses(plan.test);
  std::vector<int> count(setups.size(), 0), first(setups.size(), -1);
  for (size_t i = 0; i < poses.size(); ++i) {
    const BallbarReading& r = plan.test.readings[i];
    // Every fifth pose of a set-up is held out, except the returns to its reference pose.
    if (first[r.setup] < 0) first[r.setup] = static_cast<int>(i);
    const bool reference = (r.q - plan.test.readings[first[r.setup]].q).norm() < 1e-9;
    poses[i].heldout = !reference && (++count[r.setup] % 5 == 0);
  }
  indep::Machine machine(100 + seed);
  machine.effects = c.truth;
  indep::measure(machine, poses, setups, 20.0, 0.5e-3, 500 + seed);
  if (heldout_without_effects) {
    indep::Machine clean(100 + seed);
    std::vector<indep::Pose> again = poses;
    indep::measure(clean, again, setups, 20.0, 0.5e-3, 500 + seed);
    for (size_t i = 0; i < poses.size(); ++i)
      if (poses[i].heldout) poses[i].length = again[i].length;
  }
  std::filesystem::create_directories(dir);
  const std::string fit_csv = dir + "/fit.csv", held_csv = dir + "/held.csv";
  indep::writeCsv(fit_csv, poses, setups, false);
  indep::writeCsv(held_csv, poses, setups, true);

  // As `tolver diagnose --heldout` does it.
  const BallbarFile f = readBallbarFile(fit_csv, nominal.model, true);
  BallbarTest held = readBallbarFile(held_csv, nominal.model, true).test;
  alignHeldout(held, f.test, held_csv, fit_csv);
  const RobustCalibration rc =
      calibrateWithoutGross(nominal.model, nominal.params, f.test, unknowns);
  out.gross_removed = static_cast<int>(rc.removed.size());
  DiagnosisOptions opt;
  opt.base_unknowns = unknowns;
  // Without: the held-out readings only judge, through the written files.
  opt.heldout = diagnose_with_heldout ? &held : nullptr;
  const DiagnosisResult r = diagnose(nominal, rc.test, opt);
  out.cv_gain_um2 = r.cv_gain_mm2 * 1e6;
  out.cv_gain_se_um2 = r.cv_gain_se_mm2 * 1e6;
  out.message = r.message;
  out.withdrawn = !r.withdrawn.empty();
  out.held = static_cast<int>(r.base_fit.held.size());
  for (int p : r.base_fit.held)
    out.held_stayed_held = out.held_stayed_held && r.machine.params[p] == nominal.params[p] &&
                           std::find(r.final_fit.identified.begin(), r.final_fit.identified.end(),
                                     p) == r.final_fit.identified.end();
  out.verdict = r.verdict;
  out.heldout_gain_um2 = r.heldout_gain_mm2 * 1e6;
  out.heldout_gain_se_um2 = r.heldout_gain_se_mm2 * 1e6;
  for (const CandidateScore& cs : r.candidates)
    if (cs.verdict == CandidateVerdict::Implausible)
      out.implausible.push_back(cs.label + ": " + cs.reason);
  out.lack_of_fit_p = r.lack_of_fit_after.tested ? r.lack_of_fit_after.p_value : 1.0;
  out.unexplained = r.unexplained;
  if (r.unexplained) out.unexplained_variable = r.unexplained_finding.variable;
  for (const AddedEffect& a : r.added) out.added.push_back(a.label);
  Machine augmented = r.machine;
  writeFileAtomically(dir + "/aug.xml", formatMachineXml(augmented, "campaign"));
  writeFileAtomically(
      dir + "/aug_balls.csv",
      formatBallPositionsCsv(rc.test, r.final_fit.ball_errors, nullptr, {"campaign"}));
  const WrittenCheck w = checkWrittenFiles(dir + "/aug.xml", dir + "/aug_balls.csv", rc.test, held);
  // Before: the base fit, through its own written files.
  Machine base = nominal;
  base.params = r.base_fit.params;
  writeFileAtomically(dir + "/base.xml", formatMachineXml(base, "campaign"));
  writeFileAtomically(
      dir + "/base_balls.csv",
      formatBallPositionsCsv(rc.test, r.base_fit.ball_errors, nullptr, {"campaign"}));
  const WrittenCheck wb =
      checkWrittenFiles(dir + "/base.xml", dir + "/base_balls.csv", rc.test, held);
  out.heldout_before_um = wb.heldout.rms * 1e3;
  out.heldout_after_um = w.heldout.rms * 1e3;
  out.written_vs_memory_um = std::abs(w.heldout.rms - r.heldout_after.rms) * 1e3;
  // Named right: the added effects are exactly the expected ones (type, axis, component).
  const MachineModel& m = r.machine.model;
  int matched = 0;
  // An added effect names the truth when it is the truth or the readings cannot tell the two
  // apart (diagnose lists those as equivalent).
  const char* kComp[6] = {"ex", "ey", "ez", "gx", "gy", "gz"};
  for (const auto& [type, axis, comp] : c.expected) {
    const std::string label_start = type + " " + axis + " " + kComp[comp];
    for (const AddedEffect& a : r.added) {
      bool hit = traitsOf(a.spec.type).name == type && a.spec.axis >= 0 &&
                 m.axes[a.spec.axis].name == axis && a.spec.component == comp;
      for (const std::string& e : a.equivalent) hit = hit || e.rfind(label_start, 0) == 0;
      if (hit) {
        ++matched;
        break;
      }
    }
  }
  out.named_right =
      matched == static_cast<int>(c.expected.size()) && r.added.size() == c.expected.size();
  if (c.lack_of_fit)
    out.named_right = r.verdict == DiagnosisVerdict::Incomplete;
  else if (!c.unexplained_variable.empty())
    out.named_right = r.added.empty() && r.unexplained &&
                      r.unexplained_finding.variable == c.unexplained_variable;
  else if (r.unexplained || r.verdict == DiagnosisVerdict::Incomplete)
    out.named_right = false;  // something said to be missing where the truth has nothing more
  return out;
}

}  // namespace tolver::test
