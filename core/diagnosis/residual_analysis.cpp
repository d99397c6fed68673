#include "core/diagnosis/residual_analysis.h"

#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <map>

#include "core/numerics/chebyshev.h"
#include "core/numerics/statistics.h"

namespace tolver {
namespace {

constexpr double kPi = 3.141592653589793;

// Least-squares fit of y on the columns of X (X holds a constant column): the fraction of the
// variance of y it explains and the F-test p-value of that fraction.
ResidualFinding explain(const Eigen::MatrixXd& X, const Eigen::VectorXd& y, std::string variable,
                        std::string test) {
  ResidualFinding f;
  f.variable = std::move(variable);
  f.test = std::move(test);
  const int m = static_cast<int>(y.size()), p = static_cast<int>(X.cols());
  if (m <= p + 1) return f;
  const double tss = (y.array() - y.mean()).square().sum();
  if (!(tss > 0)) return f;
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(X);
  const double rss = (y - X * qr.solve(y)).squaredNorm();
  const int df1 = std::max(1, static_cast<int>(qr.rank()) - 1),
            df2 = m - static_cast<int>(qr.rank());
  f.strength = std::clamp(1.0 - rss / tss, 0.0, 1.0);
  f.p_value = fSurvival(((tss - rss) / df1) / (rss / df2), df1, df2);
  return f;
}

// Chebyshev columns T_0..T_degree of v normalised over its own range.
Eigen::MatrixXd polynomialColumns(const std::vector<double>& v, int degree) {
  const auto [lo, hi] = std::minmax_element(v.begin(), v.end());
  Eigen::MatrixXd X(v.size(), degree + 1);
  double T[16];
  for (size_t i = 0; i < v.size(); ++i) {
    chebyshevBasis(normalisedCoordinate(v[i], *lo, *hi), degree, T);
    for (int k = 0; k <= degree; ++k) X(i, k) = T[k];
  }
  return X;
}

double range(const std::vector<double>& v) {
  const auto [lo, hi] = std::minmax_element(v.begin(), v.end());
  return *hi - *lo;
}

// Readings grouped by pose (same set-up, joint values equal to 1e-6 mm or rad, same approach
// direction of every axis), in order of first appearance; poses measured once included.
std::vector<RepeatedPose> repeatedPoses(const BallbarTest& test) {
  std::vector<RepeatedPose> out;
  std::map<std::vector<long long>, int> group;
  for (int i = 0; i < static_cast<int>(test.readings.size()); ++i) {
    const BallbarReading& rd = test.readings[i];
    std::vector<long long> key{rd.setup};
    for (int a = 0; a < rd.q.size(); ++a) key.push_back(std::llround(rd.q[a] * 1e6));
    // Approached the same way: a backlash makes the same pose from the other side another one.
    for (int a = 0; a < rd.q.size() && a < static_cast<int>(rd.context.direction.size()); ++a)
      key.push_back(rd.context.direction[a]);
    auto [it, fresh] = group.emplace(key, static_cast<int>(out.size()));
    if (fresh) out.push_back({rd.setup, {}, 0.0});
    out[it->second].readings.push_back(i);
  }
  return out;
}

}  // namespace

LackOfFit lackOfFit(const BallbarTest& test, const Eigen::VectorXd& residuals, int fitted) {
  LackOfFit out;
  const int m = static_cast<int>(residuals.size());
  if (m != static_cast<int>(test.readings.size()) || m - fitted < 1) return out;
  const double rss = residuals.squaredNorm();
  double ss_pe = 0;
  for (const RepeatedPose& p : repeatedPoses(test)) {
    if (p.readings.size() < 2) continue;
    ++out.poses;
    out.repeats += static_cast<int>(p.readings.size());
    double mean = 0;
    for (int i : p.readings) mean += residuals[i];
    mean /= static_cast<double>(p.readings.size());
    for (int i : p.readings) ss_pe += (residuals[i] - mean) * (residuals[i] - mean);
    out.df_pure += static_cast<double>(p.readings.size()) - 1.0;
  }
  out.s_fit = std::sqrt(rss / (m - fitted));
  out.df_lack = (m - fitted) - out.df_pure;
  if (out.df_pure < 2 || out.df_lack < 1 || !(ss_pe > 0)) return out;
  out.tested = true;
  out.s_pure = std::sqrt(ss_pe / out.df_pure);
  const double ss_lof = std::max(0.0, rss - ss_pe);
  out.s_lack = std::sqrt(ss_lof / out.df_lack);
  out.f = (ss_lof / out.df_lack) / (ss_pe / out.df_pure);
  out.p_value = fSurvival(out.f, out.df_lack, out.df_pure);
  out.missing_rms = std::sqrt(std::max(0.0, out.s_fit * out.s_fit - out.s_pure * out.s_pure));
  return out;
}

// Long by design: the list of tests ([AM01] 4.9 and the periodogram [Lomb76]), one short block
// each, ranked at the end.
ResidualAnalysis analyseResiduals(const MachineModel& model, const BallbarTest& test,
                                  const Eigen::VectorXd& r) {
  ResidualAnalysis out;
  const int m = static_cast<int>(r.size());
  if (m < 8) return out;
  out.rms = std::sqrt(r.squaredNorm() / m);
  std::vector<double> y(r.data(), r.data() + m);
  auto column = [&](auto get) {
    std::vector<double> v(m);
    for (int i = 0; i < m; ++i) v[i] = get(test.readings[i]);
    return v;
  };

  for (int a = 0; a < static_cast<int>(model.axes.size()); ++a) {
    const Axis& ax = model.axes[a];
    const std::vector<double> s = column([&](const BallbarReading& rd) { return rd.q[a]; });
    if (range(s) <= 1e-9) continue;
    out.findings.push_back(explain(polynomialColumns(s, 5), r, ax.name, "trend"));
    // Periodogram against the coordinate.
    std::vector<double> omega;
    double independent = 8;
    if (ax.isRotary()) {
      for (int k = 1; k <= 8; ++k) omega.push_back(k);
    } else {
      const double span = range(s), f0 = 1.0 / 100.0, f1 = 1.0 / 2.0, df = 1.0 / (5.0 * span);
      for (double f = f0; f <= f1; f += df) omega.push_back(2 * kPi * f);
      independent = (f1 - f0) * span;
    }
    const std::vector<double> P = lombScargle(s, y, omega);
    const size_t k = std::max_element(P.begin(), P.end()) - P.begin();
    ResidualFinding f;
    f.variable = ax.name;
    f.test = "periodogram";
    f.strength = std::clamp(2.0 * P[k] / (m - 1), 0.0, 1.0);
    f.p_value = periodogramFalseAlarm(P[k], independent);
    f.period = ax.isRotary() ? omega[k] : 2 * kPi / omega[k];
    f.order = ax.isRotary();
    if (!ax.isRotary()) f.period_uncertainty = f.period * f.period / (2.0 * range(s));
    out.findings.push_back(f);
    // Approach direction.
    Eigen::MatrixXd X(m, 2);
    int both[2] = {0, 0};
    for (int i = 0; i < m; ++i) {
      const int d = test.readings[i].context.direction[a];
      X(i, 0) = 1.0;
      X(i, 1) = d;
      if (d != 0) both[d > 0]++;
    }
    if (both[0] > 2 && both[1] > 2)
      out.findings.push_back(explain(X, r, ax.name + " direction", "direction"));
  }
  const std::vector<double> t = column([](const BallbarReading& rd) { return rd.context.time_s; });
  if (std::all_of(t.begin(), t.end(), [](double v) { return std::isfinite(v); }) && range(t) > 0)
    out.findings.push_back(explain(polynomialColumns(t, 3), r, "time", "trend"));
  if (test.setups.size() > 1) {
    Eigen::MatrixXd X = Eigen::MatrixXd::Zero(m, test.setups.size());
    for (int i = 0; i < m; ++i) X(i, test.readings[i].setup) = 1.0;
    out.findings.push_back(explain(X, r, "set-up", "set-up means"));
  }
  const RunsTest runs = runsTest(y);
  out.runs_z = runs.z;
  out.runs_p = runs.p_value;
  ResidualFinding rf;
  rf.variable = "measurement order";
  rf.test = "runs";
  rf.p_value = runs.z < 0 ? runs.p_value : 1.0;  // only too few runs mean structure
  out.findings.push_back(rf);
  std::stable_sort(
      out.findings.begin(), out.findings.end(),
      [](const ResidualFinding& a, const ResidualFinding& b) { return a.p_value < b.p_value; });
  if (!out.findings.empty() && out.findings[0].p_value < 1e-3) {
    out.follows = out.findings[0].variable;
    out.follows_strength = out.findings[0].strength;
  }

  // Repeated poses.
  out.repeats = repeatedPoses(test);
  out.repeats.erase(std::remove_if(out.repeats.begin(), out.repeats.end(),
                                   [](const RepeatedPose& p) { return p.readings.size() < 3; }),
                    out.repeats.end());
  for (RepeatedPose& p : out.repeats) {
    double lo = INFINITY, hi = -INFINITY;
    for (int i : p.readings) {
      lo = std::min(lo, r[i]);
      hi = std::max(hi, r[i]);
    }
    p.span_mm = hi - lo;
  }
  return out;
}

}  // namespace tolver
