#include "core/allocation/tolerance_allocation.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "core/allocation/nsga2.h"
#include "core/kinematics/forward_kinematics.h"
#include "core/kinematics/sensitivity_jacobian.h"

namespace tolver {

double costUnitValue(const MachineModel& m, const ToleranceTerm& t, double value) {
  return m.parameters[t.parameter].angular ? value * 1e3 : value;  // rad -> mm/m
}

double categoryWeight(const AllocationModel& a, ToleranceCategory c) {
  switch (c) {
    case ToleranceCategory::Positional:
      return a.h_p;
    case ToleranceCategory::LinearPositioning:
      return 1.0;
    case ToleranceCategory::AngularPositioning:
      return a.h_a;
    case ToleranceCategory::LinearNonPositioning:
      return a.h_d;
    case ToleranceCategory::AngularNonPositioning:
      return a.h_a * a.h_d;
  }
  return 1.0;
}

double manufacturingCost(const MachineModel& m, const std::vector<ToleranceTerm>& terms,
                         const Eigen::VectorXd& T, const AllocationModel& a) {
  double c = 0.0;
  for (size_t i = 0; i < terms.size(); ++i) {
    const double t = 0.5 * costUnitValue(m, terms[i], T[i]);
    c += std::pow(categoryWeight(a, terms[i].category) * t, -a.r);
  }
  return c;
}

double qualityLoss(const MachineModel& m, const std::vector<ToleranceTerm>& terms,
                   const Eigen::VectorXd& T, const AllocationModel& a) {
  if (a.loss_weight == 0.0) return 0.0;
  const double k = a.loss_normal ? 1.0 / 9.0 : 1.0 / 3.0;  // E[y^2] / t^2
  std::vector<double> inv_eta(terms.size());
  double sum_inv = 0.0;
  for (size_t i = 0; i < terms.size(); ++i) {
    const double t = 0.5 * costUnitValue(m, terms[i], T[i]);
    // Smaller-the-better SNR (eq. 10); kept positive (an error band of 1 cost unit or more
    // would make it vanish).
    const double eta = std::max(-10.0 * std::log10(k * t * t), 1e-6);
    inv_eta[i] = 1.0 / eta;
    sum_inv += inv_eta[i];
  }
  double loss = 0.0;
  for (size_t i = 0; i < terms.size(); ++i) {
    const double t = 0.5 * costUnitValue(m, terms[i], T[i]);
    loss += inv_eta[i] / sum_inv * t * t;  // eq. 11-13
  }
  return a.loss_weight * loss;
}

std::vector<JointVector> workspaceGrid(const MachineModel& m, int levels, int rotary_levels) {
  std::vector<JointVector> out;
  const int n = static_cast<int>(m.axes.size());
  std::vector<int> count(n), idx(n, 0);
  for (int a = 0; a < n; ++a) count[a] = std::max(1, m.axes[a].isRotary() ? rotary_levels : levels);
  while (true) {
    JointVector q(n);
    for (int a = 0; a < n; ++a) {
      const Axis& ax = m.axes[a];
      q[a] = count[a] == 1
                 ? 0.5 * (ax.travel_min + ax.travel_max)
                 : ax.travel_min + (ax.travel_max - ax.travel_min) * idx[a] / (count[a] - 1);
    }
    out.push_back(q);
    int a = 0;
    while (a < n && ++idx[a] == count[a]) idx[a++] = 0;
    if (a == n) break;
  }
  return out;
}

AccuracyModel buildAccuracyModel(const MachineModel& m, const std::vector<ToleranceTerm>& terms,
                                 const std::vector<JointVector>& poses) {
  AccuracyModel acc;
  acc.poses = poses;
  acc.J.resize(3 * poses.size(), terms.size());
  const ForwardKinematics fk(m, Eigen::VectorXd::Zero(m.parameterCount()));
  Eigen::MatrixXd J(6, m.parameterCount());
  for (size_t k = 0; k < poses.size(); ++k) {
    sensitivityJacobian(fk, poses[k], J);
    // Tip displacement d (in t) seen in machine axes: F_R_t d.
    const Eigen::Matrix3d F_R_t = fk.F_T_t(poses[k]).linear();
    for (size_t i = 0; i < terms.size(); ++i)
      acc.J.block<3, 1>(3 * k, i) = F_R_t * J.block<3, 1>(0, terms[i].parameter);
  }
  acc.absJ = acc.J.cwiseAbs();
  acc.J2 = acc.J.cwiseAbs2();
  return acc;
}

Eigen::Vector3d worstCaseLinear(const AccuracyModel& acc, const Eigen::VectorXd& T, bool rss) {
  const bool cached = acc.J2.rows() == acc.J.rows() && acc.J2.cols() == acc.J.cols();
  Eigen::VectorXd e;
  if (rss)
    e = cached ? Eigen::VectorXd((acc.J2 * (0.25 * T.cwiseAbs2())).cwiseSqrt())
               : Eigen::VectorXd((acc.J * (0.5 * T).asDiagonal()).rowwise().norm());
  else
    e = cached ? Eigen::VectorXd(acc.absJ * (0.5 * T))
               : Eigen::VectorXd(acc.J.cwiseAbs() * (0.5 * T));
  Eigen::Vector3d w = Eigen::Vector3d::Zero();
  for (int r = 0; r < e.size(); ++r) w[r % 3] = std::max(w[r % 3], e[r]);
  return w;
}

Eigen::Vector3d verifyAccuracy(const MachineModel& m, const std::vector<ToleranceTerm>& terms,
                               const AccuracyModel& acc, const Eigen::VectorXd& T, bool rss) {
  const ForwardKinematics nominal(m, Eigen::VectorXd::Zero(m.parameterCount()));
  Eigen::Vector3d w = Eigen::Vector3d::Zero();
  if (rss) {
    // Each term's exact effect alone, combined root-sum-square.
    std::vector<ForwardKinematics> single;
    for (size_t i = 0; i < terms.size(); ++i) {
      Eigen::VectorXd p = Eigen::VectorXd::Zero(m.parameterCount());
      p[terms[i].parameter] = 0.5 * T[i];
      single.emplace_back(m, p);
    }
    for (const JointVector& q : acc.poses) {
      const Eigen::Vector3d p0 = nominal.w_T_t(q).translation();
      const Eigen::Matrix3d F_R_w = nominal.F_T_w(q).linear();
      Eigen::Vector3d sum2 = Eigen::Vector3d::Zero();
      for (const ForwardKinematics& fk : single)
        sum2 += (F_R_w * (fk.w_T_t(q).translation() - p0)).cwiseAbs2();
      w = w.cwiseMax(sum2.cwiseSqrt());
    }
    return w;
  }
  for (size_t k = 0; k < acc.poses.size(); ++k) {
    const JointVector& q = acc.poses[k];
    const Eigen::Isometry3d w_T_t0 = nominal.w_T_t(q);
    const Eigen::Matrix3d F_R_w = nominal.F_T_w(q).linear();
    for (int d = 0; d < 3; ++d) {
      for (double sign : {1.0, -1.0}) {
        Eigen::VectorXd p = Eigen::VectorXd::Zero(m.parameterCount());
        for (size_t i = 0; i < terms.size(); ++i) {
          const double s = acc.J(3 * k + d, i) >= 0 ? 1.0 : -1.0;
          p[terms[i].parameter] += sign * s * 0.5 * T[i];
        }
        const ForwardKinematics fk(m, p);
        const Eigen::Vector3d delta = F_R_w * (fk.w_T_t(q).translation() - w_T_t0.translation());
        w[d] = std::max(w[d], std::abs(delta[d]));
      }
    }
  }
  return w;
}

CorrelationAnalysis correlateTerms(const AccuracyModel& acc, int groups) {
  CorrelationAnalysis c;
  const int n = static_cast<int>(acc.J.cols());
  Eigen::MatrixXd U = acc.J.rowwise() - acc.J.colwise().mean();
  for (int i = 0; i < n; ++i) {
    const double norm = U.col(i).norm();
    if (norm > 0) U.col(i) /= norm;
  }
  c.correlation = U.transpose() * U;
  for (int i = 0; i < n; ++i) c.correlation(i, i) = 1.0;
  // Average-linkage agglomerative clustering on 1 - |r|.
  std::vector<std::vector<int>> clusters(n);
  for (int i = 0; i < n; ++i) clusters[i] = {i};
  auto distance = [&](const std::vector<int>& a, const std::vector<int>& b) {
    double s = 0;
    for (int i : a)
      for (int j : b) s += 1.0 - std::abs(c.correlation(i, j));
    return s / (a.size() * b.size());
  };
  while (static_cast<int>(clusters.size()) > std::max(groups, 1)) {
    size_t bi = 0, bj = 1;
    double best = std::numeric_limits<double>::infinity();
    for (size_t i = 0; i < clusters.size(); ++i)
      for (size_t j = i + 1; j < clusters.size(); ++j) {
        const double d = distance(clusters[i], clusters[j]);
        if (d < best - 1e-15) {
          best = d;
          bi = i;
          bj = j;
        }
      }
    clusters[bi].insert(clusters[bi].end(), clusters[bj].begin(), clusters[bj].end());
    std::sort(clusters[bi].begin(), clusters[bi].end());
    clusters.erase(clusters.begin() + bj);
  }
  std::sort(clusters.begin(), clusters.end());
  c.members = clusters;
  c.group.assign(n, 0);
  for (size_t g = 0; g < clusters.size(); ++g)
    for (int i : clusters[g]) c.group[i] = static_cast<int>(g);
  return c;
}

double spreadObjective(const std::vector<ToleranceTerm>& terms, const CorrelationAnalysis& c,
                       const Eigen::VectorXd& T) {
  double m2 = 0.0;
  for (const auto& g : c.members) {
    double s = 0.0;
    for (int i : g) s += std::pow(T[i] / terms[i].standard, 2);
    m2 += std::sqrt(s);
  }
  return m2;
}

namespace {

// The problem as pagmo sees it: x_i = T_i / standard_i; objectives [M1, -M2].
struct Evaluator {
  const MachineModel* m;
  const std::vector<ToleranceTerm>* terms;
  const AllocationModel* a;
  const AccuracyModel* acc;
  const CorrelationAnalysis* corr;
  Eigen::MatrixXd absJ;  // |J|
  Eigen::VectorXd T_lo;  // lower bounds of T
  Eigen::VectorXd base;  // |J| t_lo per row
  double penalty_scale = 0;
  Eigen::Vector3d limit_scale = Eigen::Vector3d::Ones();  // < 1 to leave room for 2nd-order terms

  // Repair: T = T_lo + alpha (T_x - T_lo) with the largest alpha in [0, 1] meeting the limits.
  Eigen::VectorXd repair(const Eigen::VectorXd& Tx, double* violation) const {
    double alpha = 1.0;
    *violation = 0.0;
    const Eigen::VectorXd dt = 0.5 * (Tx - T_lo);
    if (!a->rss) {
      // Row r: base_r + alpha b_r <= limit.
      const Eigen::VectorXd b = absJ * dt;
      for (int r = 0; r < b.size(); ++r) {
        const double limit = a->limits[r % 3] * limit_scale[r % 3];
        if (base[r] > limit) *violation = std::max(*violation, base[r] / limit - 1.0);
        if (b[r] > 0 && base[r] + b[r] > limit) alpha = std::min(alpha, (limit - base[r]) / b[r]);
      }
    } else {
      // Row r: |u + alpha v|^2 <= limit^2 with u = J_r t_lo, v = J_r dt (element-wise):
      // uu = J^2 t_lo^2, uv = J^2 (t_lo dt), vv = J^2 dt^2 (products with the cached J^2).
      const Eigen::VectorXd t_lo = 0.5 * T_lo;
      const Eigen::VectorXd UU = acc->J2 * t_lo.cwiseAbs2(), UV = acc->J2 * t_lo.cwiseProduct(dt),
                            VV = acc->J2 * dt.cwiseAbs2();
      for (int r = 0; r < UU.size(); ++r) {
        const double limit = a->limits[r % 3] * limit_scale[r % 3];
        const double uu = UU[r], uv = UV[r], vv = VV[r], l2 = limit * limit;
        if (uu > l2) *violation = std::max(*violation, std::sqrt(uu) / limit - 1.0);
        if (vv > 0 && uu + 2 * uv + vv > l2) {
          const double root = (-uv + std::sqrt(std::max(0.0, uv * uv - vv * (uu - l2)))) / vv;
          alpha = std::min(alpha, root);
        }
      }
    }
    alpha = std::clamp(alpha, 0.0, 1.0);
    return T_lo + alpha * (Tx - T_lo);
  }

  AllocationSolution evaluate(const Eigen::VectorXd& T) const {
    AllocationSolution s;
    s.T = T;
    s.cost = manufacturingCost(*m, *terms, T, *a);
    s.loss = qualityLoss(*m, *terms, T, *a);
    s.m1 = s.cost + s.loss;
    s.m2 = spreadObjective(*terms, *corr, T);
    s.worst_linear = worstCaseLinear(*acc, T, a->rss);
    return s;
  }
};

}  // namespace

// Long by design: the NSGA-II run as the paper sets it up ([Cai] 4.2): the problem, the
// population, the evolution and the pick of the chosen solution share the bounds and the model.
AllocationResult allocateTolerances(const MachineModel& m, const std::vector<ToleranceTerm>& terms,
                                    const AllocationModel& a, const AccuracyModel& acc_in,
                                    const CorrelationAnalysis& corr, const AllocationOptions& o) {
  // |J| and J^2 once (a model built elsewhere may lack them).
  AccuracyModel filled;
  const bool has = acc_in.J2.rows() == acc_in.J.rows() && acc_in.absJ.rows() == acc_in.J.rows();
  if (!has) {
    filled = acc_in;
    filled.absJ = acc_in.J.cwiseAbs();
    filled.J2 = acc_in.J.cwiseAbs2();
  }
  const AccuracyModel& acc = has ? acc_in : filled;
  AllocationResult res;
  res.correlation = corr;
  res.constraint_handling =
      "repair: an infeasible candidate is moved towards the lower bounds along the straight line "
      "to the largest step that meets the limits (exact for the first-order worst case); "
      "penalty only when the lower bounds themselves violate the limits";
  const int n = static_cast<int>(terms.size());
  Evaluator ev{&m, &terms, &a, &acc, &corr, acc.absJ, Eigen::VectorXd(n), Eigen::VectorXd(), 0};
  Eigen::VectorXd Tstd(n);
  for (int i = 0; i < n; ++i) {
    ev.T_lo[i] = terms[i].lower;
    Tstd[i] = terms[i].standard;
  }
  ev.base = ev.absJ * (0.5 * ev.T_lo);
  res.standard = ev.evaluate(Tstd);
  res.standard.worst_exact = verifyAccuracy(m, terms, acc, Tstd, a.rss);
  res.standard_feasible = (res.standard.worst_linear.array() <= a.limits.array()).all();
  const Eigen::Vector3d lower_worst = worstCaseLinear(acc, ev.T_lo, a.rss);
  if ((lower_worst.array() > a.limits.array()).any()) return res;  // nothing can be feasible
  ev.penalty_scale = 10.0 * std::max(res.standard.m1, 1.0);

  std::vector<double> lb, ub;
  for (int i = 0; i < n; ++i) {
    lb.push_back(terms[i].lower / terms[i].standard);
    ub.push_back(terms[i].upper / terms[i].standard);
  }
  const Nsga2Fitness fitness = [&ev](const std::vector<double>& x) {
    Eigen::VectorXd Tx(static_cast<Eigen::Index>(x.size()));
    for (size_t i = 0; i < x.size(); ++i) Tx[i] = x[i] * (*ev.terms)[i].standard;
    double violation = 0.0;
    const AllocationSolution s = ev.evaluate(ev.repair(Tx, &violation));
    const double pen = violation * ev.penalty_scale;
    return std::array<double, 2>{s.m1 + pen, -s.m2 + pen};
  };
  Nsga2Run run;
  run.population = std::max(8, (o.population + 3) / 4 * 4);
  run.generations = o.generations;
  run.mutation_probability = 1.0 / n;
  run.seed = o.seed;
  const std::vector<std::vector<double>> final_x = nsga2(fitness, lb, ub, run);

  // The repaired final population, its non-dominated front, by increasing M1.
  std::vector<AllocationSolution> all;
  for (const auto& x : final_x) {
    Eigen::VectorXd Tx(n);
    for (int i = 0; i < n; ++i) Tx[i] = x[i] * terms[i].standard;
    double violation = 0.0;
    const Eigen::VectorXd T = ev.repair(Tx, &violation);
    if (violation > 0) continue;
    all.push_back(ev.evaluate(T));
  }
  for (size_t i = 0; i < all.size(); ++i) {
    bool dominated = false;
    for (size_t j = 0; j < all.size() && !dominated; ++j) {
      if (i == j) continue;
      const bool no_worse = all[j].m1 <= all[i].m1 && all[j].m2 >= all[i].m2;
      const bool better = all[j].m1 < all[i].m1 || all[j].m2 > all[i].m2;
      dominated = no_worse && better;
    }
    if (dominated) continue;
    bool duplicate = false;
    for (const auto& f : res.front) duplicate |= (f.T - all[i].T).norm() == 0.0;
    if (!duplicate) res.front.push_back(all[i]);
  }
  std::sort(
      res.front.begin(), res.front.end(),
      [](const AllocationSolution& a1, const AllocationSolution& a2) { return a1.m1 < a2.m1; });
  // The nonlinear check: where second-order terms push a solution past a limit, repair it again
  // against limits tightened by the excess, until the forward model agrees.
  for (auto& sol : res.front) {
    Evaluator tight = ev;
    for (int it = 0; it < 6; ++it) {
      sol.worst_exact = verifyAccuracy(m, terms, acc, sol.T, a.rss);
      bool ok = true;
      for (int d = 0; d < 3; ++d)
        if (sol.worst_exact[d] > a.limits[d]) {
          ok = false;
          tight.limit_scale[d] *= a.limits[d] / sol.worst_exact[d] * (1.0 - 1e-9);
        }
      if (ok) break;
      double violation = 0.0;
      const Eigen::VectorXd Tfixed = tight.repair(sol.T, &violation);
      const Eigen::Vector3d exact = sol.worst_exact;
      sol = tight.evaluate(Tfixed);
      sol.worst_exact = exact;
    }
  }
  // Compromise: the front point closest to the ideal (least M1, largest M2), both normalised.
  if (!res.front.empty()) {
    double lo1 = res.front.front().m1, hi1 = res.front.back().m1, lo2 = 1e300, hi2 = -1e300;
    for (const auto& s : res.front) {
      lo2 = std::min(lo2, s.m2);
      hi2 = std::max(hi2, s.m2);
    }
    double best = std::numeric_limits<double>::infinity();
    for (size_t i = 0; i < res.front.size(); ++i) {
      const double d1 = hi1 > lo1 ? (res.front[i].m1 - lo1) / (hi1 - lo1) : 0.0;
      const double d2 = hi2 > lo2 ? (hi2 - res.front[i].m2) / (hi2 - lo2) : 0.0;
      const double d = std::hypot(d1, d2);
      if (d < best) {
        best = d;
        res.chosen = static_cast<int>(i);
      }
    }
  }
  return res;
}

}  // namespace tolver
