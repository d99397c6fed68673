#pragma once
// The prediction benchmarks' machine and path, shared by predict_benchmark and peer_benchmark so
// that both measure the same work.
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "core/calibration/ballbar_plan.h"
#include "core/calibration/calibration.h"
#include "core/path/tool_path_prediction.h"
#include "io/machine/machine_file.h"

namespace tolver::bench {

// Matsuura MC-760VX with every error parameter non-zero: cubic motion errors on all 30
// components (20 um, 20 urad RMS) and every link and set-up error.
inline Machine machineWithErrors() {
  Machine m =
      readMachineFile(std::string(TOLVER_SOURCE_DIR) + "/resources/machines/matsuura_mc760vx.xml");
  std::mt19937 rng(1);
  std::normal_distribution<double> n(0.0, 1.0);
  for (int i = 0; i < m.model.parameterCount(); ++i)
    m.params[i] = n(rng) * (m.model.parameters[i].angular ? 20e-6 : 0.005);
  m.model.setup.gauge_length = 100;
  m.model.setup.part_zero_table = Eigen::Vector3d(0, 0, 50);
  return m;
}

// A five-axis path: a spiral on a hemisphere with the tool normal to it.
inline std::vector<ClPoint> path(size_t n) {
  std::vector<ClPoint> out(n);
  for (size_t i = 0; i < n; ++i) {
    const double t = static_cast<double>(i) / n;
    const double polar = 0.05 + 0.9 * t * M_PI / 3, az = 40.0 * M_PI * t;
    const Eigen::Vector3d u(std::sin(polar) * std::cos(az), std::sin(polar) * std::sin(az),
                            std::cos(polar));
    out[i].p_w = 60.0 * u;
    out[i].u_w = u;
  }
  return out;
}

// 1 024 configurations of the five axes, in the structure-of-arrays layout
// ForwardKinematics::tipAndAxisBatch takes (joint values, their cos and sin, by axis; the tip
// and axis out, by coordinate): the batch forward benchmarks' input.
struct BatchJoints {
  static constexpr int n = 1024;
  std::vector<double> q = std::vector<double>(5 * n), c = q, s = q,
                      out = std::vector<double>(6 * n);
  const double *qp[5], *cp[5], *sp[5];
  double *pp[3], *up[3];
  BatchJoints() {
    for (int i = 0; i < n; ++i) {
      const double v[5] = {100.0 - 0.1 * i, -50.0 + 0.05 * i, 80.0, -0.5 + 1e-3 * i,
                           1.0 - 2e-3 * i};
      for (int a = 0; a < 5; ++a) {
        q[a * n + i] = v[a];
        c[a * n + i] = std::cos(v[a]);
        s[a * n + i] = std::sin(v[a]);
      }
    }
    for (int a = 0; a < 5; ++a) {
      qp[a] = &q[a * n];
      cp[a] = &c[a * n];
      sp[a] = &s[a * n];
    }
    for (int k = 0; k < 3; ++k) {
      pp[k] = &out[k * n];
      up[k] = &out[(3 + k) * n];
    }
  }
  BatchJoints(const BatchJoints&) = delete;
  BatchJoints& operator=(const BatchJoints&) = delete;
};

// One calibration problem: the same machine with its minimal-complete cubic model (92
// coefficients + 18 ball positions), three set-ups, 600 readings simulated from random errors
// with 0.5 um noise.
struct Data {
  Machine m;
  std::vector<int> unknowns;
  BallbarTest test;
};

inline const Data& data() {
  static const Data d = [] {
    Data x;
    x.m = readMachineFile(std::string(TOLVER_SOURCE_DIR) +
                          "/resources/machines/matsuura_mc760vx.xml");
    x.unknowns = defaultCalibrationUnknowns(x.m.model);
    BallbarPlanOptions o;
    o.poses = 600;
    x.test = planBallbarTest(x.m.model, x.unknowns, o).test;
    std::mt19937 rng(1);
    std::normal_distribution<double> n(0.0, 1.0);
    Eigen::VectorXd truth = Eigen::VectorXd::Zero(x.m.model.parameterCount());
    for (int p : x.unknowns) truth[p] = n(rng) * (x.m.model.parameters[p].angular ? 20e-6 : 0.005);
    const ForwardKinematics fk(x.m.model, truth);
    for (auto& r : x.test.readings)
      r.length = ballbarLength(fk, r.q, x.test.setups[r.setup]) + 0.5e-3 * n(rng);
    return x;
  }();
  return d;
}

}  // namespace tolver::bench
