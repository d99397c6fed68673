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
                 double* theta, double* cos_theta = nullptr, double* sin_theta = nullptr) {
  const Eigen::Vector3d pp = p - w * w.dot(p);
  const Eigen::Vector3d qp = q - w * w.dot(q);
  constexpr double kEps2 = kSingularEps * kSingularEps;
  if (pp.squaredNorm() < kEps2 || qp.squaredNorm() < kEps2) return false;
  const double y = w.dot(pp.cross(qp)), x = pp.dot(qp);
  *theta = std::atan2(y, x);
  if (cos_theta) {  // cos and sin of theta without another trigonometric call
    const double r = std::sqrt(x * x + y * y);
    *cos_theta = x / r;
    *sin_theta = y / r;
  }
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
    : model_(&model) {
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
  w_end_ = model.last_T_table * model.table_T_w();
  t_end_ = model.last_T_spindle * model.spindle_T_t();
  for (int b = 0; b < 2; ++b) {
    for (int a : b == 0 ? model.workpiece_chain : model.tool_chain) {
      ChainLink l;
      l.axis = a;
      l.link_R = model.axes[a].parent_T_joint.linear();
      l.link_p = model.axes[a].parent_T_joint.translation();
      l.identity_link = model.axes[a].parent_T_joint.isApprox(Eigen::Isometry3d::Identity(), 0.0);
      for (int c = 0; c < 3; ++c)
        if (model.axes[a].direction[c] == 1.0) l.principal = c;
      chains_[b].push_back(l);
    }
  }
  // Two parallel rotary axes cannot orient the tool independently (sub-problem 2 degenerates).
  parallel_rotaries_ =
      rotary_.size() == 2 && std::abs(a_[0].dot(C1_ * a_[1])) > 1.0 - 1e-12;
}

int InverseKinematics::rotaryCandidates(const Eigen::Vector3d& u_w, Eigen::Vector2d out[2],
                                        bool* singular, Eigen::Vector2d* cos_out,
                                        Eigen::Vector2d* sin_out) const {
  Eigen::Vector2d cos_local[2], sin_local[2];
  if (!cos_out) {
    cos_out = cos_local;
    sin_out = sin_local;
  }
  const double nan = std::numeric_limits<double>::quiet_NaN();
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
    double phi = 0.0, c1 = nan, s1 = nan;
    if (!subproblem1(a_[0], p, q, &phi, &c1, &s1)) {
      *singular = true;
      phi = nan;
    }
    cos_out[count] = Eigen::Vector2d(c1, 1.0);
    sin_out[count] = Eigen::Vector2d(sign_[0] * s1, 0.0);
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
    double phi1 = 0.0, phi2 = 0.0, c1 = nan, s1 = nan, c2 = nan, s2 = nan;
    bool free1 = !subproblem1(w1, z, q, &phi1, &c1, &s1);
    bool free2 = !subproblem1(w2, p, z, &phi2, &c2, &s2);
    if (free1 || free2) *singular = true;
    // A free angle is marked NaN; solve() fills it from the previous point.
    if (!free1 && !free2 && g < 1e-2) {
      // The closed form loses accuracy where gamma is small (the square root of a difference
      // amplifies rounding); two Gauss-Newton steps on Rot(w1, phi1) Rot(w2, phi2) p = q
      // restore it to rounding level.
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
      c1 = std::cos(phi1);
      s1 = std::sin(phi1);
      c2 = std::cos(phi2);
      s2 = std::sin(phi2);
    }
    if (free1) phi1 = c1 = s1 = nan;
    if (free2) phi2 = c2 = s2 = nan;
    // Joint value = sign * phi: the cosine is unchanged, the sine takes the sign.
    cos_out[count] = Eigen::Vector2d(c1, c2);
    sin_out[count] = Eigen::Vector2d(sign_[0] * s1, sign_[1] * s2);
    out[count++] = Eigen::Vector2d(sign_[0] * phi1, sign_[1] * phi2);
    if (g == 0.0) break;
  }
  return count;
}

bool InverseKinematics::solvePrismatic(const Eigen::Vector3d& p_w, JointVector& q,
                                       IkSolution* trig, const Eigen::Vector3d& b_t,
                                       bool trig_given) const {
  // With the rotary angles fixed the tip is affine in the prismatic joints: p_w = p0 + G s.
  // One nominal pass with s = 0 gives p0 and each prismatic joint's direction in F; a joint on
  // the workpiece branch moves the part, so the tip moves by -g in w, a tool-branch joint by +g.
  Eigen::Vector3d g_F[3];
  int k = 0;
  Eigen::Matrix3d R[2];
  Eigen::Vector3d p[2];
  for (int b = 0; b < 2; ++b) {
    R[b].setIdentity();
    p[b].setZero();
    for (const ChainLink& l : chains_[b]) {
      if (!l.identity_link) {
        p[b] += R[b] * l.link_p;
        R[b] = R[b] * l.link_R;
      }
      const Axis& ax = model_->axes[l.axis];
      if (!ax.isRotary()) {
        g_F[k++] = (b == 0 ? -1.0 : 1.0) * (R[b] * ax.direction);
        continue;
      }
      if (!trig_given) {
        trig->cos_q[l.axis] = std::cos(q[l.axis]);
        trig->sin_q[l.axis] = std::sin(q[l.axis]);
      }
      const double c = trig->cos_q[l.axis], sn = trig->sin_q[l.axis];
      if (l.principal >= 0) {
        const int i = (l.principal + 1) % 3, j = (l.principal + 2) % 3;
        const Eigen::Vector3d ci = R[b].col(i), cj = R[b].col(j);
        R[b].col(i) = c * ci + sn * cj;
        R[b].col(j) = c * cj - sn * ci;
      } else {
        R[b] = R[b] * Eigen::AngleAxisd(q[l.axis], ax.direction).toRotationMatrix();
      }
    }
  }
  const Eigen::Matrix3d Rw = R[0] * w_end_.linear();
  const Eigen::Vector3d pw = p[0] + R[0] * w_end_.translation();
  const Eigen::Vector3d pt = p[1] + R[1] * (t_end_ * b_t);
  const Eigen::Vector3d p0 = Rw.transpose() * (pt - pw);
  Eigen::Matrix3d G;
  for (int i = 0; i < 3; ++i) G.col(i) = Rw.transpose() * g_F[i];
  if (!(std::abs(G.determinant()) > 1e-12)) return false;
  const Eigen::Vector3d s = G.inverse() * (p_w - p0);
  // Prismatic joints in chain order (workpiece branch first), as g_F was filled.
  k = 0;
  for (int b = 0; b < 2; ++b)
    for (const ChainLink& l : chains_[b])
      if (!model_->axes[l.axis].isRotary()) q[l.axis] = s[k++];
  return s.allFinite();
}

bool InverseKinematics::placeToolPoint(const Eigen::Vector3d& b_t, const Eigen::Vector3d& target_w,
                                       JointVector& q, int* violated_axis) const {
  IkSolution scratch;
  *violated_axis = -1;
  if (prismatic_.size() != 3 || !solvePrismatic(target_w, q, &scratch, b_t)) return false;
  for (int a : prismatic_) {
    const Axis& ax = model_->axes[a];
    if (q[a] < ax.travel_min - kTravelEps || q[a] > ax.travel_max + kTravelEps) {
      *violated_axis = a;
      return false;
    }
  }
  return true;
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
  Eigen::Vector2d candidates[2], ccos[2], csin[2];
  const int ncand = rotaryCandidates(u_w, candidates, &singular, ccos, csin);
  if (ncand == 0) {
    sol.status = IkStatus::UnreachableOrientation;
    return sol;
  }
  const int nr = static_cast<int>(std::min<size_t>(rotary_.size(), 2));
  auto violation = [&](int axis, double value) {
    if (sol.violated_axis < 0) {
      sol.violated_axis = axis;
      sol.violated_value = value;
    }
  };
  // Rotary candidates in order of rotary motion from `previous` (continuity; each angle
  // unwrapped by 2 pi into travel); the first whose prismatic solution is inside every axis's
  // travel wins.
  JointVector cq[2];
  double ccost[2] = {std::numeric_limits<double>::infinity(),
                     std::numeric_limits<double>::infinity()};
  for (int ci = 0; ci < ncand; ++ci) {
    JointVector q = JointVector::Zero(n);
    bool ok = true;
    double cost = 0.0;
    for (int r = 0; r < nr && ok; ++r) {
      const Axis& ax = model_->axes[rotary_[r]];
      const double ref = previous ? (*previous)[rotary_[r]] : 0.0;
      double angle = candidates[ci][r];
      if (std::isnan(angle)) {  // free angle: keep the previous value
        angle = ref;
        ccos[ci][r] = std::cos(ref);
        csin[ci][r] = std::sin(ref);
      }
      const double v = unwrapInto(angle, ax.travel_min, ax.travel_max, ref);
      if (std::isnan(v)) {
        violation(rotary_[r], angle);
        ok = false;
      } else {
        q[rotary_[r]] = v;
        cost += std::abs(v - ref);
      }
    }
    if (ok) {
      cq[ci] = q;
      ccost[ci] = cost;
    }
  }
  const int order[2] = {ccost[1] < ccost[0] ? 1 : 0, ccost[1] < ccost[0] ? 0 : 1};
  for (int ci : order) {
    if (ci >= ncand || !std::isfinite(ccost[ci])) continue;
    JointVector q = cq[ci];
    // Unwrapping by 2 pi keeps the cosine and sine of the candidate's angles.
    for (int r = 0; r < nr; ++r) {
      sol.cos_q[rotary_[r]] = ccos[ci][r];
      sol.sin_q[rotary_[r]] = csin[ci][r];
    }
    if (!solvePrismatic(p_w, q, &sol, Eigen::Vector3d::Zero(), true)) continue;
    bool ok = true;
    for (int a : prismatic_) {
      const Axis& ax = model_->axes[a];
      if (q[a] < ax.travel_min - kTravelEps || q[a] > ax.travel_max + kTravelEps) {
        violation(a, q[a]);
        ok = false;
        break;
      }
    }
    if (!ok) continue;
    sol.q = q;
    sol.singular = singular;
    sol.violated_axis = -1;
    return sol;
  }
  sol.status = IkStatus::OutOfTravel;
  return sol;
}

}  // namespace tolver
