#pragma once
// The figures of a calibrated machine's predictions against the independent simulator's truth
// (tests/independent_ballbar.h): the tip and tool axis errors after the set-up a shop measures,
// and how the 95 % band covers them, machine by machine (issue 33). Shared by the campaign
// (tests/prediction_campaign.cpp) and the band's test (tests/prediction_uncertainty_test.cpp).
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "core/numerics/statistics.h"
#include "core/path/prediction_uncertainty.h"
#include "independent_diagnosis.h"

namespace tolver::test {

struct Figures {
  double tip_rms = 0, axis_rms = 0, own_tip_rms = 0, own_axis_rms = 0, coverage = 0;
  // Along the predicted tool axis: the share of poses whose deviation lies in the 95 % band, and
  // RMS(deviation / sigma). The tool axis: the share inside the 95 % radius of its covariance,
  // and inside 1.96 sigma of the worst direction (compensate's band before).
  double along_coverage = 0, along_z_rms = 0, axis_coverage = 0, axis_coverage_worst = 0;
  // The band's own statement of how far one machine's RMS(r/sigma) may fall from 1: the along-
  // axis errors of the poses are correlated (one calibration's error reaches every pose), so
  // mean(z^2) ~ g chi2_h / h with h = N^2 / tr(C^2), C their correlation matrix (Welch-
  // Satterthwaite); the 5 % and 95 % points of RMS(r/sigma) under the band's own Gaussian.
  double effective_dof = 0, z_rms_lo = 0, z_rms_hi = 0;
};

// The truth's tool tip (100 mm below the gauge point) and tool axis at the poses.
inline void truthTipAndAxis(const indep::Machine& truth, const std::vector<JointVector>& qs,
                            std::vector<Eigen::Vector3d>* tip, std::vector<Eigen::Vector3d>* axis) {
  tip->resize(qs.size());
  axis->resize(qs.size());
  for (size_t i = 0; i < qs.size(); ++i) {
    indep::Pose p;
    for (int a = 0; a < 5; ++a) p.q[a] = qs[i][a];
    (*tip)[i] = truth.point(p, Eigen::Vector3d(0, 0, -100));
    (*axis)[i] = (truth.point(p, Eigen::Vector3d(0, 0, 0)) - (*tip)[i]).normalized();
  }
}

// n random poses, uniform over the whole travel or inside the volume the calibration covered.
inline std::vector<JointVector> randomPoses(const Machine& identified, bool inside, int n,
                                            std::mt19937& prng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const IdentificationUncertainty& id = identified.identification;
  std::vector<JointVector> qs;
  for (int i = 0; i < n; ++i) {
    JointVector q(5);
    for (int a = 0; a < 5; ++a) {
      const double lo = inside ? id.covered_min[a] : identified.model.axes[a].travel_min;
      const double hi = inside ? id.covered_max[a] : identified.model.axes[a].travel_max;
      q[a] = lo + (hi - lo) * u(prng);
    }
    qs.push_back(q);
  }
  return qs;
}

// Truth and prediction at the poses, each after its own best set-up (applyMeasuredSetup, as
// predict does): the identified machine's prediction, and the nominal machine's (what assuming
// no errors predicts: the machine's own error).
inline Figures measure(const indep::Machine& truth, Machine identified,
                       const std::vector<JointVector>& qs) {
  identified.model.setup.gauge_length = 100;
  Machine nominal = identified;
  nominal.params.setZero();
  std::vector<Eigen::Vector3d> tip, axis;
  truthTipAndAxis(truth, qs, &tip, &axis);
  // Errors of a machine's prediction after the set-up that best fits the truth.
  auto errors = [&](Machine m, std::vector<double>* tip_err, std::vector<double>* axis_err) {
    std::vector<Eigen::Vector3d> d(qs.size());
    {
      const ForwardKinematics fk(m.model, m.params);
      for (size_t i = 0; i < qs.size(); ++i) d[i] = fk.w_T_t(qs[i]).translation() - tip[i];
    }
    applyMeasuredSetup(m, qs, d);
    const ForwardKinematics fk(m.model, m.params);
    for (size_t i = 0; i < qs.size(); ++i) {
      const Eigen::Isometry3d T = fk.w_T_t(qs[i]);
      tip_err->push_back((T.translation() - tip[i]).norm());
      axis_err->push_back(std::acos(std::clamp(axis[i].dot(T.linear().col(2)), -1.0, 1.0)));
    }
    return m;
  };
  std::vector<double> tp, ap, to, ao;
  const Machine after = errors(identified, &tp, &ap);
  errors(nominal, &to, &ao);
  // Coverage of the band: the truth against the prediction after its set-up.
  Figures f;
  PredictionUncertainty pu(after);
  pu.setupModulo(qs);
  const ForwardKinematics fk(after.model, after.params);
  int inside = 0, along_in = 0, axis_in = 0, axis_in_worst = 0;
  double z2 = 0;
  Eigen::MatrixXd rows(qs.size(), after.identification.parameters.size());
  Eigen::VectorXd sig(qs.size());
  for (size_t i = 0; i < qs.size(); ++i) {
    const Eigen::Isometry3d T = fk.w_T_t(qs[i]);
    const Eigen::Vector3d d = tip[i] - T.translation();
    const PoseUncertainty u = pu.at(qs[i]);
    for (int k = 0; k < 3; ++k)
      inside += std::abs(d[k]) <= 1.96 * std::sqrt(u.tip_covariance_w(k, k));
    const Eigen::Vector3d n = T.linear().col(2);
    const double s = PredictionUncertainty::along(u, n), r = d.dot(n);
    rows.row(i) = pu.alongRoot(qs[i], n) / s;
    sig[i] = after.identification.lack_of_fit_mm / s;
    along_in += std::abs(r) <= 1.96 * s;
    z2 += (r / s) * (r / s);
    const Eigen::Vector2d e = (T.linear().transpose() * axis[i]).head<2>();
    axis_in += e.norm() <= PredictionUncertainty::axisRadius95(u);
    axis_in_worst += e.norm() <= 1.96 * u.axis;
  }
  {
    Eigen::MatrixXd C = rows * rows.transpose();
    C.diagonal() += sig.cwiseAbs2();
    const double N = static_cast<double>(qs.size());
    f.effective_dof = N * N / C.cwiseAbs2().sum();
    const double h = f.effective_dof;
    f.z_rms_lo = std::sqrt(chiSquareQuantile(0.05, h) / h);
    f.z_rms_hi = std::sqrt(chiSquareQuantile(0.95, h) / h);
  }
  f.along_coverage = along_in / double(qs.size());
  f.along_z_rms = std::sqrt(z2 / qs.size());
  f.axis_coverage = axis_in / double(qs.size());
  f.axis_coverage_worst = axis_in_worst / double(qs.size());
  auto rms = [](const std::vector<double>& v, double k) {
    double s = 0;
    for (double x : v) s += x * x;
    return std::sqrt(s / v.size()) * k;
  };
  f.tip_rms = rms(tp, 1e3);
  f.own_tip_rms = rms(to, 1e3);
  f.axis_rms = rms(ap, 1e6);
  f.own_axis_rms = rms(ao, 1e6);
  f.coverage = inside / (3.0 * qs.size());
  return f;
}

}  // namespace tolver::test
