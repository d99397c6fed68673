#include "core/inverse_kinematics.h"

#include <cmath>
#include <limits>

namespace tolver {
namespace {

constexpr double kTwoPi = 2.0 * M_PI;
constexpr double kSingularEps = 1e-9;   // |component of a unit vector normal to an axis|
constexpr double kTravelEps = 1e-9;     // mm or rad of tolerance on travel limits

// Paden-Kahan sub-problem 1: the angle theta with Rot(w, theta) p = q (p, q equally inclined
// to the unit axis w). Returns false when p is along w (theta free).
bool subproblem1(const Eigen::Vector3d& w, const Eigen::Vector3d& p, const Eigen::Vector3d& q,
                 double* theta) {
  const Eigen::Vector3d pp = p - w * w.dot(p);
  const Eigen::Vector3d qp = q - w * w.dot(q);
  if (pp.norm() < kSingularEps || qp.norm() < kSingularEps) return false;
  *theta = std::atan2(w.dot(pp.cross(qp)), pp.dot(qp));
  return true;
}

// The representative of angle + 2 pi k inside [lo, hi] nearest to ref, or NaN if none.
double unwrapInto(double angle, double lo, double hi, double ref) {
  double best = std::numeric_limits<double>::quiet_NaN();
  double best_dist = std::numeric_limits<double>::infinity();
  const double k0 = std::floor((lo - angle) / kTwoPi);
  for (double k = k0; angle + k * kTwoPi <= hi + kTravelEps; k += 1.0) {
    const double v = angle + k * kTwoPi;
    if (v < lo - kTravelEps) continue;
    if (std::abs(v - ref) < best_dist) {
      best_dist = std::abs(v - ref);
      best = v;
    }
  }
  return best;
}

}  // namespace

InverseKinematics::InverseKinematics(const MachineModel& model)
    : model_(&model), nominal_(model, Eigen::VectorXd::Zero(model.parameterCount())) {
  // Orientation factors from w to t: table_T_w^T, then the workpiece chain backwards (each
  // joint inverted), then the tool chain forwards, then spindle_T_t.
  struct Factor {
    Eigen::Matrix3d R;
    int axis;  // -1 for a constant factor
    double sign;
  };
  std::vector<Factor> f;
  f.push_back({(model.last_T_table * model.table_T_w()).linear().transpose(), -1, 0});
  for (auto it = model.workpiece_chain.rbegin(); it != model.workpiece_chain.rend(); ++it) {
    const Axis& ax = model.axes[*it];
    if (ax.isRotary()) f.push_back({Eigen::Matrix3d::Identity(), *it, -1.0});
    f.push_back({ax.parent_T_joint.linear().transpose(), -1, 0});
  }
  for (int a : model.tool_chain) {
    const Axis& ax = model.axes[a];
    f.push_back({ax.parent_T_joint.linear(), -1, 0});
    if (ax.isRotary()) f.push_back({Eigen::Matrix3d::Identity(), a, 1.0});
  }
  f.push_back({(model.last_T_spindle * model.spindle_T_t()).linear(), -1, 0});

  Eigen::Matrix3d C[3] = {Eigen::Matrix3d::Identity(), Eigen::Matrix3d::Identity(),
                          Eigen::Matrix3d::Identity()};
  int stage = 0;
  for (const Factor& x : f) {
    if (x.axis < 0) {
      C[stage] = C[stage] * x.R;
    } else {
      if (stage < 2) {
        sign_[stage] = x.sign;
        a_[stage] = model.axes[x.axis].direction.normalized();
      }
      rotary_.push_back(x.axis);
      ++stage;
      if (stage > 2) break;  // more than two rotary axes: reported by solve()
    }
  }
  C0_ = C[0];
  C1_ = C[1];
  C2_ = C[2];
  for (int a = 0; a < static_cast<int>(model.axes.size()); ++a)
    if (!model.axes[a].isRotary()) prismatic_.push_back(a);
  // Two parallel rotary axes cannot orient the tool independently (sub-problem 2 degenerates).
  parallel_rotaries_ =
      rotary_.size() == 2 && std::abs(a_[0].dot(C1_ * a_[1])) > 1.0 - 1e-12;
}

int InverseKinematics::rotaryCandidates(const Eigen::Vector3d& u_w, Eigen::Vector2d out[2],
                                        bool* singular) const {
  int count = 0;
  *singular = false;
  const Eigen::Vector3d k = Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d u = u_w.normalized();
  if (rotary_.empty()) {
    if ((C0_ * k - u).norm() < 1e-9) out[count++] = Eigen::Vector2d(0.0, 0.0);
    return count;
  }
  if (rotary_.size() == 1) {
    // Rot(a1, phi) (C1 k) = C0^T u
    const Eigen::Vector3d p = C1_ * k, q = C0_.transpose() * u;
    if (std::abs(a_[0].dot(p) - a_[0].dot(q)) > 1e-9) return count;
    double phi = 0.0;
    if (!subproblem1(a_[0], p, q, &phi)) {
      *singular = true;
      phi = std::numeric_limits<double>::quiet_NaN();
    }
    out[count++] = Eigen::Vector2d(sign_[0] * phi, 0.0);
    return count;
  }
  // Rot(w1, phi1) Rot(w2, phi2) p = q.
  const Eigen::Vector3d w1 = a_[0], w2 = C1_ * a_[1];
  const Eigen::Vector3d p = C1_ * C2_ * k, q = C0_.transpose() * u;
  const double c = w1.dot(w2);
  const double den = c * c - 1.0;
  const double alpha = (c * w2.dot(p) - w1.dot(q)) / den;
  const double beta = (c * w1.dot(q) - w2.dot(p)) / den;
  const Eigen::Vector3d w12 = w1.cross(w2);
  double g2 = (p.squaredNorm() - alpha * alpha - beta * beta - 2.0 * alpha * beta * c) /
              w12.squaredNorm();
  if (g2 < -1e-12) return count;
  g2 = std::max(g2, 0.0);
  const double g = std::sqrt(g2);
  for (double sgn : {1.0, -1.0}) {
    const Eigen::Vector3d z = alpha * w1 + beta * w2 + sgn * g * w12;
    double phi1 = 0.0, phi2 = 0.0;
    bool free1 = !subproblem1(w1, z, q, &phi1);
    bool free2 = !subproblem1(w2, p, z, &phi2);
    if (free1 || free2) *singular = true;
    // A free angle is marked NaN; solve() fills it from the previous point.
    if (!free1 && !free2) {
      // The closed form loses accuracy where gamma is small (sqrt of a difference); two
      // Gauss-Newton steps on Rot(w1, phi1) Rot(w2, phi2) p = q restore it to rounding level.
      for (int it = 0; it < 2; ++it) {
        const Eigen::Matrix3d R1 = Eigen::AngleAxisd(phi1, w1).toRotationMatrix();
        const Eigen::Vector3d r2p = Eigen::AngleAxisd(phi2, w2) * p;
        const Eigen::Vector3d f = R1 * r2p;
        Eigen::Matrix<double, 3, 2> J;
        J.col(0) = w1.cross(f);
        J.col(1) = R1 * w2.cross(r2p);
        const Eigen::Matrix2d JtJ = J.transpose() * J;
        if (std::abs(JtJ.determinant()) < 1e-20) break;
        const Eigen::Vector2d d = JtJ.ldlt().solve(J.transpose() * (q - f));
        phi1 += d[0];
        phi2 += d[1];
      }
    }
    if (free1) phi1 = std::numeric_limits<double>::quiet_NaN();
    if (free2) phi2 = std::numeric_limits<double>::quiet_NaN();
    out[count++] = Eigen::Vector2d(sign_[0] * phi1, sign_[1] * phi2);
    if (g == 0.0) break;
  }
  return count;
}

bool InverseKinematics::solvePrismatic(const Eigen::Vector3d& p_w, JointVector& q) const {
  // The tip is affine in the prismatic joints once the rotary angles are fixed.
  for (int a : prismatic_) q[a] = 0.0;
  const Eigen::Vector3d p0 = nominal_.w_T_t(q).translation();
  Eigen::Matrix3d G;
  for (int i = 0; i < 3; ++i) {
    q[prismatic_[i]] = 1.0;
    G.col(i) = nominal_.w_T_t(q).translation() - p0;
    q[prismatic_[i]] = 0.0;
  }
  const Eigen::Vector3d s = G.partialPivLu().solve(p_w - p0);
  for (int i = 0; i < 3; ++i) q[prismatic_[i]] = s[i];
  return s.allFinite();
}

IkSolution InverseKinematics::solve(const Eigen::Vector3d& p_w, const Eigen::Vector3d& u_w,
                                    const JointVector* previous) const {
  IkSolution sol;
  const int n = static_cast<int>(model_->axes.size());
  sol.q = JointVector::Zero(n);
  if (rotary_.size() > 2 || prismatic_.size() != 3 || parallel_rotaries_) {
    sol.status = IkStatus::UnsupportedTopology;
    return sol;
  }
  bool singular = false;
  Eigen::Vector2d candidates[2];
  const int ncand = rotaryCandidates(u_w, candidates, &singular);
  if (ncand == 0) {
    sol.status = IkStatus::UnreachableOrientation;
    return sol;
  }
  const int nr = static_cast<int>(std::min<size_t>(rotary_.size(), 2));
  double best_cost = std::numeric_limits<double>::infinity();
  JointVector best_q;
  bool best_singular = false;
  auto violation = [&](int axis, double value) {
    if (sol.violated_axis < 0) {
      sol.violated_axis = axis;
      sol.violated_value = value;
    }
  };
  // Each rotary candidate is completed with its prismatic solution and checked against every
  // axis's travel; among the feasible ones the rotary motion from `previous` is smallest.
  for (int ci = 0; ci < ncand; ++ci) {
    const Eigen::Vector2d& cand = candidates[ci];
    JointVector q = JointVector::Zero(n);
    bool ok = true;
    double cost = 0.0;
    for (int r = 0; r < nr && ok; ++r) {
      const Axis& ax = model_->axes[rotary_[r]];
      const double ref = previous ? (*previous)[rotary_[r]] : 0.0;
      double angle = cand[r];
      if (std::isnan(angle)) angle = ref;  // free angle: keep the previous value
      const double v = unwrapInto(angle, ax.travel_min, ax.travel_max, ref);
      if (std::isnan(v)) {
        violation(rotary_[r], angle);
        ok = false;
      } else {
        q[rotary_[r]] = v;
        cost += std::abs(v - ref);
      }
    }
    if (!ok || cost >= best_cost) continue;
    if (!solvePrismatic(p_w, q)) continue;
    for (int a : prismatic_) {
      const Axis& ax = model_->axes[a];
      if (q[a] < ax.travel_min - kTravelEps || q[a] > ax.travel_max + kTravelEps) {
        violation(a, q[a]);
        ok = false;
        break;
      }
    }
    if (!ok) continue;
    best_cost = cost;
    best_q = q;
    best_singular = singular;
  }
  if (!std::isfinite(best_cost)) {
    sol.status = IkStatus::OutOfTravel;
    return sol;
  }
  sol.q = best_q;
  sol.singular = best_singular;
  sol.violated_axis = -1;
  return sol;
}

}  // namespace tolver
