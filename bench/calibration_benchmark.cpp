// Ball-bar calibration and diagnosis on one core. One calibration solve: Matsuura MC-760VX, full
// minimal-complete cubic model (92 coefficients + 18 ball positions), three set-ups, 600 readings,
// 0.5 um noise.
//   ./build/bench/calibration_benchmark
#include <benchmark/benchmark.h>

#include <random>

#include "bench_fixtures.h"
#include "core/allocation/tolerance_allocation.h"
#include "core/calibration/ballbar_plan.h"
#include "core/calibration/calibration.h"
#include "core/diagnosis/diagnosis.h"
#include "io/machine/ballbar_file.h"
#include "io/machine/machine_file.h"
#include "io/machine/tolerance_file.h"

namespace {

using tolver::bench::data;
using tolver::bench::Data;

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
  for (auto _ : state)
    benchmark::DoNotOptimize(tolver::identificationJacobian(fk, d.test, balls, d.unknowns));
}
BENCHMARK(BM_IdentificationJacobian600)->Unit(benchmark::kMillisecond);

// A full diagnosis of a 360-reading three-set-up test with two undeclared effects:
// base calibration, the minimal-complete set, every candidate of every type with its
// hyperparameter search and 18-block cross-validation, the nonlinear refits, residual analysis.
void BM_Diagnose360Readings(benchmark::State& state) {
  const tolver::Machine m = tolver::readMachineFile(std::string(TOLVER_SOURCE_DIR) +
                                                    "/resources/machines/matsuura_mc760vx.xml");
  const tolver::BallbarTest test =
      tolver::readBallbarFile(std::string(TOLVER_SOURCE_DIR) + "/samples/ballbar/two_effects.csv",
                              m.model, true)
          .test;
  size_t added = 0, candidates = 0;
  for (auto _ : state) {
    const tolver::DiagnosisResult r = tolver::diagnose(m, test);
    added = r.added.size();
    candidates = r.candidates.size();
    benchmark::DoNotOptimize(r.rms_after);
  }
  state.counters["effects_added"] = static_cast<double>(added);
  state.counters["candidates_scored"] = static_cast<double>(candidates);
}
BENCHMARK(BM_Diagnose360Readings)->Unit(benchmark::kMillisecond)->Iterations(3);

}  // namespace

// tolver allocate's optimisation on the XKH800 (README's root-sum-square run: 675 poses, 100 x 250
// NSGA-II, limits 15/15/10 um, lower bounds a quarter of the standard), both cores.
void BM_AllocateXkh800Rss(benchmark::State& state) {
  tolver::Machine m =
      tolver::readMachineFile(std::string(TOLVER_SOURCE_DIR) + "/resources/machines/xkh800.xml");
  m.model.setup.gauge_length = 150;
  std::vector<tolver::ToleranceTerm> terms = tolver::readToleranceFile(
      std::string(TOLVER_SOURCE_DIR) + "/resources/allocation/xkh800_standard.csv", m.model);
  for (auto& t : terms) t.lower = 0.25 * t.standard;
  tolver::AllocationModel a;
  a.limits = Eigen::Vector3d(0.015, 0.015, 0.010);
  a.rss = true;
  const tolver::AccuracyModel acc =
      tolver::buildAccuracyModel(m.model, terms, tolver::workspaceGrid(m.model, 3, 5));
  const tolver::CorrelationAnalysis corr = tolver::correlateTerms(acc, 4);
  for (auto _ : state) {
    const auto r =
        tolver::allocateTolerances(m.model, terms, a, acc, corr, tolver::AllocationOptions{});
    benchmark::DoNotOptimize(r.front.size());
  }
}
BENCHMARK(BM_AllocateXkh800Rss)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(3);

BENCHMARK_MAIN();
