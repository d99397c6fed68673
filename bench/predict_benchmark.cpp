// Predicted CL points per second on one core: Matsuura MC-760VX with cubic motion errors on
// every component of every axis and every link and set-up error non-zero.
//   ./build/bench/predict_benchmark
#include <benchmark/benchmark.h>

#include <cmath>
#include <random>

#include "bench_fixtures.h"
#include "core/kinematics/forward_kinematics.h"
#include "core/kinematics/inverse_kinematics.h"
#include "core/path/compensation.h"
#include "core/path/tool_path_prediction.h"
#include "io/common/io_error.h"
#include "io/machine/machine_file.h"
#include "io/program/apt_reader.h"
#include "io/program/gcode_reader.h"
#include "pipeline/parallel_prediction.h"

namespace {

using tolver::bench::machineWithErrors;
using tolver::bench::path;

void BM_PredictToolPath(benchmark::State& state) {
  const tolver::Machine m = machineWithErrors();
  const auto p = path(static_cast<size_t>(state.range(0)));
  for (auto _ : state) {
    auto r = tolver::predictToolPath(m.model, m.params, p);
    benchmark::DoNotOptimize(r.summary.max_deviation);
  }
  state.SetItemsProcessed(state.iterations() * state.range(0));
}
BENCHMARK(BM_PredictToolPath)->Arg(100000)->Unit(benchmark::kMillisecond);

// The same with the result's storage reused across calls (batch work): no page faults.
void BM_PredictToolPathReusingStorage(benchmark::State& state) {
  const tolver::Machine m = machineWithErrors();
  const auto p = path(static_cast<size_t>(state.range(0)));
  tolver::PredictionResult r;
  for (auto _ : state) {
    tolver::predictToolPath(m.model, m.params, p, r);
    benchmark::DoNotOptimize(r.summary.max_deviation);
  }
  state.SetItemsProcessed(state.iterations() * state.range(0));
}
BENCHMARK(BM_PredictToolPathReusingStorage)->Arg(100000)->Unit(benchmark::kMillisecond);

// The same on two threads (pipeline/parallel_prediction.h): the figure for a 2-core machine.
void BM_PredictToolPathTwoThreads(benchmark::State& state) {
  const tolver::Machine m = machineWithErrors();
  const auto p = path(static_cast<size_t>(state.range(0)));
  tolver::PredictionResult r;  // reused, as the one-core figure's
  for (auto _ : state) {
    tolver::predictToolPathParallel(m.model, m.params, p, r, 20, nullptr, 2);
    benchmark::DoNotOptimize(r.summary.max_deviation);
  }
  state.SetItemsProcessed(state.iterations() * state.range(0));
}
BENCHMARK(BM_PredictToolPathTwoThreads)->Arg(100000)->Unit(benchmark::kMillisecond)->UseRealTime();

// Compensation of the same path (Newton on the full error model from the nominal IK): the
// issue's target is within 3x of predict's rate.
void BM_CompensateToolPath(benchmark::State& state) {
  const tolver::Machine m = machineWithErrors();
  const auto p = path(static_cast<size_t>(state.range(0)));
  const auto pred = tolver::predictToolPath(m.model, m.params, p);
  std::vector<tolver::JointVector> q0;
  for (const auto& pt : pred.points) q0.push_back(pt.q);
  double iterations = 0;
  for (auto _ : state) {
    auto r = tolver::compensateToolPath(m.model, m.params, p, q0, true, {}, &pred.points);
    benchmark::DoNotOptimize(r.points.back().q[0]);
    iterations = 0;
    for (const auto& c : r.points) iterations += c.iterations;
    iterations /= r.points.size();
  }
  state.counters["newton_steps"] = iterations;

  state.SetItemsProcessed(state.iterations() * state.range(0));
}
BENCHMARK(BM_CompensateToolPath)->Arg(100000)->Unit(benchmark::kMillisecond);

void BM_ForwardKinematicsWithErrors(benchmark::State& state) {
  const tolver::Machine m = machineWithErrors();
  const tolver::ForwardKinematics fk(m.model, m.params);
  tolver::JointVector q(5);
  q << 100, -50, 80, -0.5, 1.0;
  for (auto _ : state) {
    q[4] += 1e-6;
    benchmark::DoNotOptimize(fk.w_T_t(q));
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_ForwardKinematicsWithErrors);

void BM_TipAndAxisWithErrors(benchmark::State& state) {
  const tolver::Machine m = machineWithErrors();
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
BENCHMARK(BM_TipAndAxisWithErrors);

// The same, 1 024 configurations at a time through the batch carry (four side by side).
void BM_TipAndAxisBatch(benchmark::State& state) {
  const tolver::Machine m = machineWithErrors();
  const tolver::ForwardKinematics fk(m.model, m.params);
  tolver::bench::BatchJoints j;
  for (auto _ : state) {
    fk.tipAndAxisBatch(j.n, j.qp, j.cp, j.sp, j.pp, j.up);
    benchmark::DoNotOptimize(j.out.data());
  }
  state.SetItemsProcessed(state.iterations() * j.n);
}
BENCHMARK(BM_TipAndAxisBatch);

void BM_InverseKinematics(benchmark::State& state) {
  const tolver::Machine m = machineWithErrors();
  const tolver::InverseKinematics ik(m.model);
  const auto p = path(1000);
  size_t i = 0;
  tolver::JointVector prev = ik.solve(p[0].p_w, p[0].u_w, nullptr).q;
  for (auto _ : state) {
    const auto s = ik.solve(p[i].p_w, p[i].u_w, &prev);
    benchmark::DoNotOptimize(s.q);
    i = (i + 1) % p.size();
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_InverseKinematics);

// Reading posted G-code: LinuxCNC's boat program (1 881 lines, TCP mode, arcs), text in memory,
// on its machine; lines per second.
void BM_ReadGcodeBoat(benchmark::State& state) {
  const std::string dir = std::string(TOLVER_SOURCE_DIR);
  const tolver::Machine m =
      tolver::readMachineFile(dir + "/resources/machines/linuxcnc_xyzac_trt.xml");
  const std::string text = tolver::readFile(dir + "/samples/gcode/boat-xyzac.ngc");
  size_t lines = 0;
  for (auto _ : state) {
    const tolver::ClProgram p = tolver::parseGcode(text, "boat-xyzac.ngc", m.model);
    lines += p.lines.size();
    benchmark::DoNotOptimize(p.path.data());
  }
  state.counters["lines/s"] =
      benchmark::Counter(static_cast<double>(lines), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_ReadGcodeBoat)->Unit(benchmark::kMillisecond);

// The same for CL data: the sculptured finish (APT, 9 802 GOTO).
void BM_ReadAptSculptured(benchmark::State& state) {
  const std::string text =
      tolver::readFile(std::string(TOLVER_SOURCE_DIR) + "/samples/sculptured_finish.apt");
  size_t lines = 0;
  for (auto _ : state) {
    const tolver::ClProgram p = tolver::parseApt(text, "sculptured_finish.apt");
    lines += p.lines.size();
    benchmark::DoNotOptimize(p.path.data());
  }
  state.counters["lines/s"] =
      benchmark::Counter(static_cast<double>(lines), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_ReadAptSculptured)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
