// One ball-bar calibration solve on one core: Matsuura MC-760VX, full minimal-complete cubic
// model (92 coefficients + 18 ball positions), three set-ups, 600 readings, 0.5 um noise.
//   ./build/bench/calibration_benchmark
#include <benchmark/benchmark.h>

#include <random>

#include "core/ballbar_plan.h"
#include "core/calibration.h"
#include "io/machine_file.h"

namespace {

struct Data {
  tolver::Machine m;
  std::vector<int> unknowns;
  tolver::BallbarTest test;
};

const Data& data() {
  static const Data d = [] {
    Data x;
    x.m = tolver::readMachineFile(std::string(TOLVER_SOURCE_DIR) +
                                  "/resources/machines/matsuura_mc760vx.xml");
    x.unknowns = tolver::defaultCalibrationUnknowns(x.m.model);
    tolver::BallbarPlanOptions o;
    o.poses = 600;
    x.test = tolver::planBallbarTest(x.m.model, x.unknowns, o).test;
    std::mt19937 rng(1);
    std::normal_distribution<double> n(0.0, 1.0);
    Eigen::VectorXd truth = Eigen::VectorXd::Zero(x.m.model.parameterCount());
    for (int p : x.unknowns) truth[p] = n(rng) * (x.m.model.parameters[p].angular ? 20e-6 : 0.005);
    const tolver::ForwardKinematics fk(x.m.model, truth);
    for (auto& r : x.test.readings)
      r.length = tolver::ballbarLength(fk, r.q, x.test.setups[r.setup]) + 0.5e-3 * n(rng);
    return x;
  }();
  return d;
}

void BM_Calibrate600Readings(benchmark::State& state) {
  const Data& d = data();
  const Eigen::VectorXd prior = Eigen::VectorXd::Zero(d.m.model.parameterCount());
  int iterations = 0;
  for (auto _ : state) {
    const auto r = tolver::calibrate(d.m.model, prior, d.test, d.unknowns);
    iterations = r.iterations;
    benchmark::DoNotOptimize(r.rms_residual);
  }
  state.counters["gauss_newton_iterations"] = iterations;
}
BENCHMARK(BM_Calibrate600Readings)->Unit(benchmark::kMillisecond);

void BM_IdentificationJacobian600(benchmark::State& state) {
  const Data& d = data();
  const tolver::ForwardKinematics fk(d.m.model, Eigen::VectorXd::Zero(d.m.model.parameterCount()));
  const std::vector<tolver::BallErrors> balls(3);
  for (auto _ : state) benchmark::DoNotOptimize(tolver::identificationJacobian(fk, d.test, balls, d.unknowns));
}
BENCHMARK(BM_IdentificationJacobian600)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
