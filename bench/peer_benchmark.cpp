// tolver's prediction against the kinematics library a user would pick instead, Orocos KDL,
// measured in the same run on one core, with the ratios printed at the end.
//   ./build/bench/peer_benchmark
// KDL side: ChainFkSolverPos_recursive::JntToCart on the Matsuura MC-760VX's five joints as one
// serial chain from the workpiece to the tool (C, A, X, Y on the table side inverted, Z on the
// tool side), each segment carrying a constant error frame (a link error): the full pose only.
// tolver side, on the same machine with every error parameter non-zero (bench_fixtures.h):
//   - BM_Tolver_PredictedPoint: a CL point predicted (inverse kinematics on the nominal machine,
//     then the tool tip and axis with 162 error parameters: cubic motion errors on all 30
//     components, link and set-up errors; deviations and statistics), per point of a 100 000-point
//     five-axis path;
//   - BM_Tolver_FullPose: the forward model alone, full 4x4 pose, motion errors evaluated;
//   - BM_Tolver_TipAndAxis: the forward model alone, tool tip and axis (what prediction needs).
// Issue 18's goal: predicted points at >= 3x KDL's poses per second.
//
// Calibration against Ceres Solver's dense Levenberg-Marquardt (DENSE_QR) on the same problem
// (bench_fixtures.h: 600 readings, 110 unknowns): Ceres is given tolver's own residuals and
// identification Jacobian (the model is the same; the solvers differ). tolver's figure
// includes what Ceres does not do: the rank decisions (which unknowns the readings can see),
// the covariance and the per-parameter uncertainties.
#include <benchmark/benchmark.h>
#include <ceres/ceres.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <kdl/chain.hpp>
#include <kdl/chainfksolverpos_recursive.hpp>
#include <kdl/frames.hpp>
#include <kdl/jntarray.hpp>
#include <map>
#include <string>
#include <vector>

#include "bench_fixtures.h"
#include "core/calibration/ballbar.h"
#include "core/kinematics/forward_kinematics.h"
#include "pipeline/parallel_prediction.h"

namespace {

// A small constant frame (a few um and urad), different per segment: the link error.
KDL::Frame errorFrame(int i) {
  const double e = 1e-3 * (i + 1), r = 10e-6 * (i + 1);
  return KDL::Frame(KDL::Rotation::RPY(r, -0.5 * r, 0.3 * r), KDL::Vector(e, -0.7 * e, 0.4 * e));
}

KDL::Chain matsuuraChain() {
  KDL::Chain c;
  // Workpiece side from w outwards (C, A, X, Y: the table axes, entered inverted), then Z.
  c.addSegment(KDL::Segment(KDL::Joint(KDL::Joint::RotZ, -1.0), errorFrame(0)));
  c.addSegment(KDL::Segment(KDL::Joint(KDL::Joint::RotX, -1.0), errorFrame(1)));
  c.addSegment(KDL::Segment(KDL::Joint(KDL::Joint::TransX, -1.0), errorFrame(2)));
  c.addSegment(KDL::Segment(KDL::Joint(KDL::Joint::TransY, -1.0), errorFrame(3)));
  c.addSegment(KDL::Segment(KDL::Joint(KDL::Joint::TransZ), errorFrame(4)));
  return c;
}

void BM_Kdl_FullPose(benchmark::State& state) {
  const KDL::Chain chain = matsuuraChain();
  KDL::ChainFkSolverPos_recursive fk(chain);
  KDL::JntArray q(5);
  q(0) = 1.0;
  q(1) = -0.5;
  q(2) = 100;
  q(3) = -50;
  q(4) = 80;
  KDL::Frame f;
  for (auto _ : state) {
    q(0) += 1e-6;
    fk.JntToCart(q, f);
    benchmark::DoNotOptimize(f.p.data[0]);
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_Kdl_FullPose);

void BM_Tolver_PredictedPoint(benchmark::State& state) {
  const tolver::Machine m = tolver::bench::machineWithErrors();
  const auto p = tolver::bench::path(100000);
  tolver::PredictionResult r;
  for (auto _ : state) {
    tolver::predictToolPath(m.model, m.params, p, r);
    benchmark::DoNotOptimize(r.summary.max_deviation);
  }
  state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(p.size()));
}
BENCHMARK(BM_Tolver_PredictedPoint)->Unit(benchmark::kMillisecond);

void BM_Tolver_FullPose(benchmark::State& state) {
  const tolver::Machine m = tolver::bench::machineWithErrors();
  const tolver::ForwardKinematics fk(m.model, m.params);
  tolver::JointVector q(5);
  q << 100, -50, 80, -0.5, 1.0;
  for (auto _ : state) {
    q[4] += 1e-6;
    benchmark::DoNotOptimize(fk.w_T_t(q));
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_Tolver_FullPose);

void BM_Tolver_TipAndAxis(benchmark::State& state) {
  const tolver::Machine m = tolver::bench::machineWithErrors();
  const tolver::ForwardKinematics fk(m.model, m.params);
  tolver::JointVector q(5);
  q << 100, -50, 80, -0.5, 1.0;
  Eigen::Vector3d p, u;
  for (auto _ : state) {
    q[4] += 1e-6;
    fk.tipAndAxis(q, &p, &u);
    benchmark::DoNotOptimize(p);
    benchmark::DoNotOptimize(u);
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_Tolver_TipAndAxis);

// The forward model alone, tip and axis, 1 024 configurations at a time (the batch carry that
// prediction uses: four side by side).
void BM_Tolver_BatchTipAndAxis(benchmark::State& state) {
  const tolver::Machine m = tolver::bench::machineWithErrors();
  const tolver::ForwardKinematics fk(m.model, m.params);
  tolver::bench::BatchJoints j;
  for (auto _ : state) {
    fk.tipAndAxisBatch(j.n, j.qp, j.cp, j.sp, j.pp, j.up);
    benchmark::DoNotOptimize(j.out.data());
  }
  state.SetItemsProcessed(state.iterations() * j.n);
}
BENCHMARK(BM_Tolver_BatchTipAndAxis);

// A predicted CL point on both cores of this machine (pipeline/parallel_prediction.h).
void BM_Tolver_PredictedPointTwoCores(benchmark::State& state) {
  const tolver::Machine m = tolver::bench::machineWithErrors();
  const auto p = tolver::bench::path(100000);
  tolver::PredictionResult r;  // reused, as the one-core figure's
  for (auto _ : state) {
    tolver::predictToolPathParallel(m.model, m.params, p, r, 20, nullptr, 2);
    benchmark::DoNotOptimize(r.summary.max_deviation);
  }
  state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(p.size()));
}
BENCHMARK(BM_Tolver_PredictedPointTwoCores)->Unit(benchmark::kMillisecond)->UseRealTime();

// The calibration as one Ceres cost: x = [unknown machine parameters, per set-up table-ball xyz,
// tool-ball xyz], residuals model - measured (mm) with tolver's identification Jacobian.
class BallbarCost : public ceres::CostFunction {
 public:
  explicit BallbarCost(const tolver::bench::Data& d) : d_(d) {
    set_num_residuals(static_cast<int>(d.test.readings.size()));
    mutable_parameter_block_sizes()->push_back(unknowns());
  }
  int unknowns() const { return static_cast<int>(d_.unknowns.size() + 6 * d_.test.setups.size()); }
  bool Evaluate(double const* const* x, double* residuals, double** jacobians) const override {
    Eigen::VectorXd params = Eigen::VectorXd::Zero(d_.m.model.parameterCount());
    const int np = static_cast<int>(d_.unknowns.size());
    for (int k = 0; k < np; ++k) params[d_.unknowns[k]] = x[0][k];
    std::vector<tolver::BallErrors> balls(d_.test.setups.size());
    for (size_t s = 0; s < balls.size(); ++s)
      for (int c = 0; c < 3; ++c) {
        balls[s].table_w[c] = x[0][np + 6 * s + c];
        balls[s].tool_t[c] = x[0][np + 6 * s + 3 + c];
      }
    const tolver::ForwardKinematics fk(d_.m.model, params);
    Eigen::VectorXd r;
    const Eigen::MatrixXd J = tolver::identificationJacobian(fk, d_.test, balls, d_.unknowns, &r);
    Eigen::Map<Eigen::VectorXd>(residuals, r.size()) = -r;
    if (jacobians && jacobians[0])
      Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
          jacobians[0], J.rows(), J.cols()) = J;
    return true;
  }

 private:
  const tolver::bench::Data& d_;
};

void BM_Ceres_Calibrate600(benchmark::State& state) {
  const tolver::bench::Data& d = tolver::bench::data();
  double rms = 0;
  int iterations = 0;
  for (auto _ : state) {
    BallbarCost* cost = new BallbarCost(d);
    std::vector<double> x(cost->unknowns(), 0.0);
    ceres::Problem problem;
    problem.AddResidualBlock(cost, nullptr, x.data());
    ceres::Solver::Options o;
    o.linear_solver_type = ceres::DENSE_QR;
    o.minimizer_type = ceres::TRUST_REGION;
    o.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
    o.num_threads = 1;
    o.logging_type = ceres::SILENT;
    ceres::Solver::Summary summary;
    ceres::Solve(o, &problem, &summary);
    rms = std::sqrt(2.0 * summary.final_cost / d.test.readings.size());
    iterations = static_cast<int>(summary.iterations.size());
  }
  state.counters["rms_um"] = rms * 1e3;
  state.counters["iterations"] = iterations;
}
BENCHMARK(BM_Ceres_Calibrate600)->Unit(benchmark::kMillisecond);

void BM_Tolver_Calibrate600(benchmark::State& state) {
  const tolver::bench::Data& d = tolver::bench::data();
  const Eigen::VectorXd prior = Eigen::VectorXd::Zero(d.m.model.parameterCount());
  double rms = 0;
  int iterations = 0;
  for (auto _ : state) {
    const auto r = tolver::calibrate(d.m.model, prior, d.test, d.unknowns);
    rms = r.rms_residual;
    iterations = r.iterations;
  }
  state.counters["rms_um"] = rms * 1e3;
  state.counters["iterations"] = iterations;
}
BENCHMARK(BM_Tolver_Calibrate600)->Unit(benchmark::kMillisecond);

// Console output as usual, and each benchmark's items per second kept for the ratios: every
// repetition's (--benchmark_repetitions, ideally with --benchmark_enable_random_interleaving,
// so that a change of the machine's speed during the run falls on both sides of a ratio).
class RateReporter : public benchmark::ConsoleReporter {
 public:
  std::map<std::string, std::vector<double>> rates;
  void ReportRuns(const std::vector<Run>& runs) override {
    for (const Run& r : runs) {
      if (r.run_type != Run::RT_Iteration) continue;  // (aggregates: computed below)
      const auto it = r.counters.find("items_per_second");
      if (it != r.counters.end())
        rates[r.benchmark_name()].push_back(it->second);
      else if (r.iterations > 0)
        rates[r.benchmark_name()].push_back(r.iterations / r.real_accumulated_time);
    }
    ConsoleReporter::ReportRuns(runs);
  }
};

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n == 0 ? 0.0 : n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  RateReporter reporter;
  benchmark::RunSpecifiedBenchmarks(&reporter);
  const auto all = [&](const char* prefix) {
    for (const auto& [name, r] : reporter.rates)
      if (name == prefix || name.rfind(std::string(prefix) + "/", 0) == 0) return r;
    return std::vector<double>{};
  };
  const auto find = [&](const char* prefix) { return median(all(prefix)); };
  const double kdl = find("BM_Kdl_FullPose");
  if (kdl > 0) {
    const size_t runs = all("BM_Kdl_FullPose").size();
    std::printf("\nratios to KDL's full poses per second (same run; KDL on one core%s):\n",
                runs > 1 ? "; medians of the repetitions, range in brackets" : "");
    for (const char* n :
         {"BM_Tolver_PredictedPoint", "BM_Tolver_PredictedPointTwoCores", "BM_Tolver_FullPose",
          "BM_Tolver_TipAndAxis", "BM_Tolver_BatchTipAndAxis"}) {
      const std::vector<double> r = all(n);
      if (r.empty()) continue;
      std::printf("  %-26s %6.2f M/s   %5.2fx KDL (%.2f M/s)", n, find(n) / 1e6, find(n) / kdl,
                  kdl / 1e6);
      if (r.size() > 1) {
        const auto [lo, hi] = std::minmax_element(r.begin(), r.end());
        const std::vector<double> k = all("BM_Kdl_FullPose");
        const auto [klo, khi] = std::minmax_element(k.begin(), k.end());
        std::printf("   [tolver %.2f-%.2f, KDL %.2f-%.2f M/s]", *lo / 1e6, *hi / 1e6, *klo / 1e6,
                    *khi / 1e6);
      }
      std::printf("\n");
    }
  }
  const double ceres = find("BM_Ceres_Calibrate600"), own = find("BM_Tolver_Calibrate600");
  if (ceres > 0 && own > 0)
    std::printf(
        "\ncalibration, 600 readings, 110 unknowns: tolver %.1f ms, Ceres %.1f ms: %.2fx Ceres\n",
        1e3 / own, 1e3 / ceres, own / ceres);
  benchmark::Shutdown();
  return 0;
}
