// The measurement behind docs/validation.md's "Predictions on independent data": machines simulated
// by the independent implementation (tests/independent_ballbar.h, seeds the tests do not use),
// calibrated by tolver from a three-set-up ball-bar test, then the tool tip (gauge length 100 mm)
// and tool axis predicted at random poses over the whole travel and inside the calibrated volume,
// after the set-up a shop measures (fitted over the poses, as predict does). Reported against the
// machine's own error (the truth against the nominal machine, after its own set-up fit) and the
// coverage of the 95 % band. Not a test: `./build/tests/prediction_campaign [machines] [prior_um
// prior_urad] [cone]` (prior -1 -1: chosen by the readings' evidence; cone: a D-optimal plan
// against a --for plan, judged at the cone sample's poses; probed: the set-up fitted to 12 probed
// points instead of the best fit to the truth, the prediction compared with the truth as it is;
// tram: probed, and a spindle tram at the middle of the volume; band [tilt_urad]: the band machine
// by machine along the tool axis and of the tool axis, with a stated spindle-tilt prior).
#include <unistd.h>

#include <Eigen/Eigenvalues>
#include <cstdio>
#include <cstdlib>
#include <memory>

#include "band_figures.h"
#include "core/numerics/statistics.h"
#include "core/path/prediction_uncertainty.h"
#include "core/path/probed_setup.h"
#include "independent_diagnosis.h"
#include "io/program/apt_reader.h"
#include "io/program/setup_file.h"

using namespace tolver;
using tolver::test::Figures;

namespace {

// The same, with the set-up from probed points (fitProbedSetup) instead of the best fit to the
// truth: 12 touches around the middle of the calibrated volume at three table orientations,
// where the truth puts the probe tip; the prediction then compared with the truth as it is.
// tram: also a spindle tram at the middle of the volume, rotaries at zero (the truth's tool axis
// in its table frame, which is its w).
Figures measureProbed(const indep::Machine& truth, Machine identified,
                      const std::vector<JointVector>& qs, bool tram) {
  identified.model.setup.gauge_length = 100;
  const IdentificationUncertainty& id = identified.identification;
  auto mid = [&](int a, double f) {
    return id.covered_min[a] + f * (id.covered_max[a] - id.covered_min[a]);
  };
  std::vector<ProbedPoint> probes;
  for (int k = 0; k < 12; ++k) {
    ProbedPoint pp;
    pp.q = JointVector::Zero(5);
    pp.q[0] = mid(0, k % 2 ? 0.35 : 0.65);
    pp.q[1] = mid(1, (k / 2) % 2 ? 0.35 : 0.65);
    pp.q[2] = mid(2, k % 3 == 0 ? 0.3 : 0.6);
    pp.q[3] = k >= 4 && k < 8 ? mid(3, 0.3) : 0.0;
    pp.q[4] = k < 8 ? 0.0 : M_PI / 2;
    indep::Pose p;
    for (int a = 0; a < 5; ++a) p.q[a] = pp.q[a];
    pp.p_w = truth.point(p, Eigen::Vector3d(0, 0, -100));
    pp.probe_length = 100;
    probes.push_back(pp);
  }
  if (tram) {
    ProbedPoint t;
    t.tram = true;
    t.q = JointVector::Zero(5);
    indep::Pose p;
    for (int a = 0; a < 3; ++a) t.q[a] = p.q[a] = mid(a, 0.5);
    t.tilt = (truth.point(p, Eigen::Vector3d::Zero()) - truth.point(p, Eigen::Vector3d(0, 0, -100)))
                 .normalized()
                 .head<2>();
    probes.push_back(t);
  }
  Machine nominal = identified;
  nominal.params.setZero();
  std::vector<Eigen::Vector3d> tip, axis;
  test::truthTipAndAxis(truth, qs, &tip, &axis);
  Figures f;
  int inside = 0;
  for (Machine* m : {&identified, &nominal}) {
    fitProbedSetup(*m, probes);
    const ForwardKinematics fk(m->model, m->params);
    double t = 0, a = 0;
    std::unique_ptr<PredictionUncertainty> pu;
    if (m == &identified) {
      pu = std::make_unique<PredictionUncertainty>(*m);
      pu->setupModuloProbed(probes);
    }
    for (size_t i = 0; i < qs.size(); ++i) {
      const Eigen::Isometry3d T = fk.w_T_t(qs[i]);
      const Eigen::Vector3d d = tip[i] - T.translation();
      t += d.squaredNorm();
      const double ang = std::acos(std::clamp(axis[i].dot(T.linear().col(2)), -1.0, 1.0));
      a += ang * ang;
      if (pu) {
        const PoseUncertainty u = pu->at(qs[i]);
        for (int k = 0; k < 3; ++k)
          inside += std::abs(d[k]) <= 1.96 * std::sqrt(u.tip_covariance_w(k, k));
      }
    }
    (m == &identified ? f.tip_rms : f.own_tip_rms) = std::sqrt(t / qs.size()) * 1e3;
    (m == &identified ? f.axis_rms : f.own_axis_rms) = std::sqrt(a / qs.size()) * 1e6;
  }
  f.coverage = inside / (3.0 * qs.size());
  return f;
}

}  // namespace

int main(int argc, char** argv) {
  const int machines = argc > 1 ? std::atoi(argv[1]) : 3;
  // Optional prior (regularisation): linear um and angular urad per coefficient.
  const double prior_um = argc > 3 ? std::atof(argv[2]) : 0.0,
               prior_urad = argc > 3 ? std::atof(argv[3]) : 0.0;
  const std::string dir = "/tmp/tolver_prediction_campaign_" + std::to_string(::getpid());
  std::filesystem::create_directories(dir);
  const Machine nominal =
      readMachineFile(test::sourcePath("resources/machines/matsuura_mc760vx.xml"));
  const std::vector<int> unknowns = defaultCalibrationUnknowns(nominal.model);
  std::printf(
      "| machine (seed) | where | tip error after set-up, RMS (um) | machine's own (um) | ratio | "
      "tool axis RMS (urad) | own (urad) | 95 %% band coverage "
      "|\n|---|---|---|---|---|---|---|---|\n");
  // The cone sample's poses on the Matsuura (its set-up file): where a --for plan aims.
  std::vector<JointVector> cone;
  {
    Machine m = nominal;
    m.model.setup = readSetupFile(test::sourcePath("samples/matsuura_setup.txt"), m.model.setup);
    const ClProgram program = readAptFile(test::sourcePath("samples/nas979_cone.apt"));
    const PredictionResult pr = predictToolPath(m.model, m.params, program.path);
    for (size_t i = 0; i < pr.points.size(); i += 4) cone.push_back(pr.points[i].q);
  }
  const bool for_mode = argc > 4 && std::string(argv[4]) == "cone";
  const bool tram_mode = argc > 4 && std::string(argv[4]) == "tram";
  const bool probed_mode = tram_mode || (argc > 4 && std::string(argv[4]) == "probed");
  // band [tilt_urad]: the band's coverage machine by machine (issue 33), with a stated spindle
  // tilt prior (default 10 urad, the simulator's scale of an angular coefficient).
  const bool band_mode = argc > 4 && std::string(argv[4]) == "band";
  const double tilt_urad = argc > 5 ? std::atof(argv[5]) : 10.0;
  if (band_mode)
    std::printf(
        "| machine (seed) | where | tip RMS (um) | along-axis coverage | RMS(r/sigma) along | "
        "effective dof | the band's 90 %% range of RMS(r/sigma) | "
        "tool axis RMS (urad) | axis coverage (95 %% radius) | axis coverage (1.96 worst) | tip "
        "coordinate coverage |\n|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (int k = 0; k < machines; ++k) {
    const unsigned seed = 900 + k;
    indep::Machine truth(seed);
    auto calibrateWith = [&](const BallbarPlanOptions& po) {
      const BallbarPlan plan = planBallbarTest(nominal.model, unknowns, po);
      if (prior_um < 0)  // auto: as calibrate --prior auto
        return test::calibrateOnIndependent(nominal, unknowns, truth, plan.test, seed, 700 + seed,
                                            true, dir);
      if (prior_um == 0)
        return test::calibrateOnIndependent(nominal, unknowns, truth, plan.test, seed, 700 + seed,
                                            false, dir);
      // A fixed prior: measure, then calibrate with it.
      const std::vector<indep::Setup> setups = test::independentSetups(plan.test, seed);
      std::vector<indep::Pose> poses = test::independentPoses(plan.test);
      indep::measure(truth, poses, setups, 20.0, 0.5e-3, 700 + seed);
      indep::writeCsv(dir + "/fit.csv", poses, setups, false);
      const BallbarFile f = readBallbarFile(dir + "/fit.csv", nominal.model, true);
      CalibrationOptions co;
      co.prior_linear = prior_um * 1e-3;
      co.prior_angular = prior_urad * 1e-6;
      const CalibrationResult r = calibrate(nominal.model, nominal.params, f.test, unknowns, co);
      Machine id = nominal;
      id.params = r.params;
      id.identification = identificationUncertainty(r, f.test, 5);
      return id;
    };
    BallbarPlanOptions po;
    po.poses = 360;
    po.seed = 5000 + seed;
    po.reference_every = 8;
    if (for_mode) {
      for (bool aimed : {false, true}) {
        BallbarPlanOptions pa = po;
        if (aimed)
          for (size_t i = 0; i < cone.size(); i += std::max<size_t>(1, cone.size() / 60))
            pa.target_poses.push_back(cone[i]);
        const Figures g = test::measure(truth, calibrateWith(pa), cone);
        std::printf("| %u | %s | the cone's poses | %.2f | %.2f | %.2f | %.1f | %.1f | %.3f |\n",
                    seed, aimed ? "--for the cone" : "D-optimal", g.tip_rms, g.own_tip_rms,
                    g.tip_rms / g.own_tip_rms, g.axis_rms, g.own_axis_rms, g.coverage);
        std::fflush(stdout);
      }
      continue;
    }
    Machine id = calibrateWith(po);
    if (band_mode) id.identification.spindle_tilt_rad = tilt_urad * 1e-6;
    std::mt19937 prng(seed + 1);
    for (bool inside : {false, true}) {
      const std::vector<JointVector> qs = test::randomPoses(id, inside, 500, prng);
      const Figures g =
          probed_mode ? measureProbed(truth, id, qs, tram_mode) : test::measure(truth, id, qs);
      if (band_mode) {
        std::printf(
            "| %u | %s | %.2f | %.3f | %.2f | %.1f | %.2f-%.2f | %.1f | %.3f | %.3f | %.3f |\n",
            seed, inside ? "inside" : "whole travel", g.tip_rms, g.along_coverage, g.along_z_rms,
            g.effective_dof, g.z_rms_lo, g.z_rms_hi, g.axis_rms, g.axis_coverage,
            g.axis_coverage_worst, g.coverage);
        std::fflush(stdout);
        continue;
      }
      std::printf("| %u | %s | %.2f | %.2f | %.2f | %.1f | %.1f | %.3f |\n", seed,
                  inside ? "inside the calibrated volume" : "whole travel", g.tip_rms,
                  g.own_tip_rms, g.tip_rms / g.own_tip_rms, g.axis_rms, g.own_axis_rms, g.coverage);
      std::fflush(stdout);
    }
  }
  return 0;
}
