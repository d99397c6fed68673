#include "core/kinematics/inverse_kinematics.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstring>
#include <limits>

#include "core/model/rigid_transform.h"
#include "core/numerics/lanes.h"
#include "core/numerics/units.h"

namespace tolver {
namespace {

constexpr double kTwoPi = 2.0 * kPi;
constexpr double kSingularEps = 1e-9;  // |component of a unit vector normal to an axis|
// (numerical floor; the control's singular band, NcControl::singular_band, widens it)
constexpr double kTravelEps = 1e-6;  // mm or rad of tolerance on travel limits: a CL file
                                     // written to 6 decimals may round a point at a limit over

// Paden-Kahan sub-problem 1: cos and sin of the angle theta with Rot(w, theta) p = q (p, q
// equally inclined to the unit axis w), without a trigonometric call. Returns false when p or q
// is along w (theta free).
bool subproblem1(const Eigen::Vector3d& w, const Eigen::Vector3d& p, const Eigen::Vector3d& q,
                 double* cos_theta, double* sin_theta) {
  const Eigen::Vector3d pp = p - w * w.dot(p);
  const Eigen::Vector3d qp = q - w * w.dot(q);
  constexpr double kEps2 = kSingularEps * kSingularEps;
  if (pp.squaredNorm() < kEps2 || qp.squaredNorm() < kEps2) return false;
  const double y = w.dot(pp.cross(qp)), x = pp.dot(qp);
  const double inv_r = 1.0 / std::sqrt(x * x + y * y);
  *cos_theta = x * inv_r;
  *sin_theta = y * inv_r;
  return true;
}

// The representative of angle + 2 pi k inside [lo, hi] nearest to ref, or NaN if none. The
// representatives inside the range are consecutive, so when the one nearest to ref lies outside,
// the nearest inside is the one at that end of the range: O(1) for any travel (endless axes).
double unwrapInto(double angle, double lo, double hi, double ref) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double lo_e = lo - kTravelEps, hi_e = hi + kTravelEps;
  double v = angle + kTwoPi * std::round((ref - angle) / kTwoPi);
  if (v < lo_e)
    v = angle + kTwoPi * std::ceil((lo_e - angle) / kTwoPi);
  else if (v > hi_e)
    v = angle + kTwoPi * std::floor((hi_e - angle) / kTwoPi);
  return (v >= lo_e && v <= hi_e) ? v : nan;
}

// unwrapInto, with the common case first: the representative nearest to ref, when it lies
// inside travel and no other one is as near.
double unwrapNear(double angle, double lo, double hi, double ref) {
  const double v = angle + kTwoPi * std::round((ref - angle) / kTwoPi);
  if (v >= lo - kTravelEps && v <= hi + kTravelEps && std::abs(v - ref) < kPi - 1e-9) return v;
  return unwrapInto(angle, lo, hi, ref);
}

}  // namespace

double InverseKinematics::RotaryCandidate::angleOf(int r) const {
  if (free[r]) return std::numeric_limits<double>::quiet_NaN();
  return known[r] ? angle[r] : std::atan2(sin[r], cos[r]);
}

// Long by design: the topology's classification once per model (axes, chains, the closed-form
// case), so that solve() is free of it.
InverseKinematics::InverseKinematics(const MachineModel& model) : model_(&model) {
  {
    const double sb = std::sin(std::clamp(model.control.singular_band, 0.0, 0.1));
    band_sq_ = std::max(kSingularEps * kSingularEps, sb * sb);
  }
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
  int column = 1;
  for (int b = 0; b < 2; ++b) {
    for (int a : b == 0 ? model.workpiece_chain : model.tool_chain) {
      ChainLink l;
      l.axis = a;
      l.link_R = model.axes[a].parent_T_joint.linear();
      l.link_Rt = l.link_R.transpose();
      l.link_p = model.axes[a].parent_T_joint.translation();
      l.direction = model.axes[a].direction;
      l.identity_link = model.axes[a].parent_T_joint.isApprox(Eigen::Isometry3d::Identity(), 0.0);
      l.identity_rotation = l.link_R == Eigen::Matrix3d::Identity();
      for (int c = 0; c < 3; ++c)
        if (model.axes[a].direction[c] == 1.0) l.principal = c;
      l.rotary = model.axes[a].isRotary();
      if (!l.rotary && column <= 3) column_axis_[column - 1] = a;
      if (!l.rotary) l.column = column++;
      chains_[b].push_back(l);
    }
  }
  if (rotary_.size() == 2) {
    w1_ = a_[0];
    w2_ = C1_ * a_[1];
    p2_ = C1_ * C2_ * Eigen::Vector3d::UnitZ();
    w12_ = w1_.cross(w2_);
    w1w2_ = w1_.dot(w2_);
    w2p2_ = w2_.dot(p2_);
    p2_sq_ = p2_.squaredNorm();
    w12_sq_ = w12_.squaredNorm();
    sub1_.u1 = w2_ - w1w2_ * w1_;
    sub1_.u2 = w1_ - w1w2_ * w2_;
    sub1_.v1 = w1_.cross(w12_);
    const Eigen::Vector3d pp2 = p2_ - w2_ * w2p2_, v2 = w2_.cross(pp2);
    sub1_.u1_sq = sub1_.u1.squaredNorm();
    sub1_.u2_sq = sub1_.u2.squaredNorm();
    sub1_.pp2_sq = pp2.squaredNorm();
    sub1_.pp2_u2 = pp2.dot(sub1_.u2);
    sub1_.pp2_w12 = pp2.dot(w12_);
    sub1_.v2_u2 = v2.dot(sub1_.u2);
    sub1_.v2_w12 = v2.dot(w12_);
  }
  // Two parallel rotary axes cannot orient the tool independently (sub-problem 2 degenerates).
  parallel_rotaries_ = rotary_.size() == 2 && std::abs(a_[0].dot(C1_ * a_[1])) > 1.0 - 1e-12;
  batchable_ = rotary_.size() == 2 && prismatic_.size() == 3 && !parallel_rotaries_ &&
               sub1_.pp2_sq >= band_sq_;
  for (int b = 0; b < 2; ++b)
    for (const ChainLink& l : chains_[b])
      if (l.rotary && l.principal < 0) batchable_ = false;
}

template <typename L, typename M>
TOLVER_LANE_INLINE void InverseKinematics::candidatesL(const L u_w[3], L c[2][2], L s[2][2],
                                                       L* g_out, M* unreachable, M* free1, M* free2,
                                                       M* refine) const {
  using lanes::select;
  using lanes::sqrtL;
  // u = u_w normalised (as Eigen's normalized(): unchanged when zero), q = C0^T u.
  const L n2 = u_w[0] * u_w[0] + u_w[1] * u_w[1] + u_w[2] * u_w[2];
  const L root = sqrtL(n2);
  const M positive = n2 > 0.0;
  L u[3], q[3];
  for (int k = 0; k < 3; ++k) u[k] = select(positive, u_w[k] / root, u_w[k]);
  for (int i = 0; i < 3; ++i) q[i] = C0_(0, i) * u[0] + C0_(1, i) * u[1] + C0_(2, i) * u[2];
  // Rot(w1, phi1) Rot(w2, phi2) p = q: z = Rot(w2, phi2) p = alpha w1 + beta w2 + g w1 x w2.
  const double cw = w1w2_;
  const L w1q = w1_[0] * q[0] + w1_[1] * q[1] + w1_[2] * q[2];
  const double inv_den = 1.0 / (cw * cw - 1.0), inv_w12_sq = 1.0 / w12_sq_;
  const L alpha = (cw * w2p2_ - w1q) * inv_den;
  const L beta = (cw * w1q - w2p2_) * inv_den;
  L g2 = (p2_sq_ - alpha * alpha - beta * beta - 2.0 * alpha * beta * cw) * inv_w12_sq;
  *unreachable = lanes::maskOf(g2 < -1e-12);
  g2 = lanes::maxL(g2, lanes::splat<L>(0.0));
  const L g = sqrtL(g2);
  // The two sub-problems 1, Rot(w1, phi1) z = q and Rot(w2, phi2) p = z, in closed form: the
  // parts normal to each axis are zp1 = beta u1 +- g w12 and qp1 = q - w1 (w1.q), and pp2
  // (fixed) and zp2 = alpha u2 +- g w12 (sub1_ holds u1, u2 and the fixed dot products), so each
  // cosine and sine is a few multiplications; the same as subproblem1(w1, z, q) and
  // subproblem1(w2, p, z).
  L qp1[3];
  for (int k = 0; k < 3; ++k) qp1[k] = q[k] - w1_[k] * w1q;
  const auto dot = [&](const L* a, const Eigen::Vector3d& b)
                       TOLVER_LANE_LAMBDA { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; };
  const L qp1_w12 = dot(qp1, w12_), qp1_v1 = dot(qp1, sub1_.v1), qp1_u1 = dot(qp1, sub1_.u1);
  const L qp1_sq = qp1[0] * qp1[0] + qp1[1] * qp1[1] + qp1[2] * qp1[2];
  const double eps2 = band_sq_;
  const L gg = g2 * w12_sq_;
  *free1 = lanes::maskOf(qp1_sq < eps2) | lanes::maskOf(beta * beta * sub1_.u1_sq + gg < eps2);
  *free2 = lanes::maskOf(alpha * alpha * sub1_.u2_sq + gg < eps2);
  if (sub1_.pp2_sq < eps2) *free2 = lanes::maskOf(g == g) | lanes::maskOf(g != g);  // every lane
  *refine = lanes::maskOf(g < 1e-2);
  *g_out = g;
  for (int k = 0; k < 2; ++k) {
    const double sgn = k == 0 ? 1.0 : -1.0;
    const L sg = sgn * g;
    const L x1 = beta * qp1_u1 + sg * qp1_w12, y1 = beta * qp1_w12 + sg * qp1_v1;
    const L x2 = alpha * sub1_.pp2_u2 + sg * sub1_.pp2_w12;
    const L y2 = alpha * sub1_.v2_u2 + sg * sub1_.v2_w12;
    const L r1 = 1.0 / sqrtL(x1 * x1 + y1 * y1), r2 = 1.0 / sqrtL(x2 * x2 + y2 * y2);
    c[k][0] = x1 * r1;
    s[k][0] = y1 * r1;
    c[k][1] = x2 * r2;
    s[k][1] = y2 * r2;
  }
}

template <typename L>
TOLVER_LANE_INLINE auto InverseKinematics::prismaticL(const L* q, const L* c, const L* sn,
                                                      const double m0[3], const L p_w[3],
                                                      L out[3]) const {
  // With the rotary angles fixed the tip is affine in the prismatic joints: p_w = p0 + G s.
  // One nominal pass with s = 0 carries the tool point (column 0) and each prismatic joint's
  // direction (its column, from the joint on) along the chains into w: the tool branch from its
  // last joint to the foundation, then the workpiece branch inverted from the foundation on (a
  // workpiece-branch joint moves the part, so the tip moves by -direction in w).
  L M[3][4];
  for (int i = 0; i < 3; ++i) {
    M[i][0] = lanes::splat<L>(m0[i]);
    for (int j = 1; j < 4; ++j) M[i][j] = lanes::splat<L>(0.0);
  }
  const auto multiply = [&](const Eigen::Matrix3d& R) TOLVER_LANE_LAMBDA {
    for (int j = 0; j < 4; ++j) {
      const L m0j = M[0][j], m1j = M[1][j], m2j = M[2][j];
      for (int i = 0; i < 3; ++i) M[i][j] = R(i, 0) * m0j + R(i, 1) * m1j + R(i, 2) * m2j;
    }
  };
  const auto rotate = [&](const ChainLink& l, bool inverse) TOLVER_LANE_LAMBDA {
    const L cs = c[l.axis], s = inverse ? -sn[l.axis] : sn[l.axis];
    if (l.principal >= 0) {
      const int i = (l.principal + 1) % 3, j = (l.principal + 2) % 3;
      for (int col = 0; col < 4; ++col) {
        const L mi = M[i][col], mj = M[j][col];
        M[i][col] = cs * mi - s * mj;
        M[j][col] = s * mi + cs * mj;
      }
    } else if constexpr (sizeof(L) == sizeof(double)) {
      multiply(Eigen::AngleAxisd(inverse ? -q[l.axis] : q[l.axis], model_->axes[l.axis].direction)
                   .toRotationMatrix());
    }
  };
  const auto& tool = chains_[1];
  for (auto it = tool.rbegin(); it != tool.rend(); ++it) {
    const ChainLink& l = *it;
    if (l.rotary)
      rotate(l, false);
    else
      for (int i = 0; i < 3; ++i) M[i][l.column] = lanes::splat<L>(l.direction[i]);
    if (!l.identity_link) {
      if (!l.identity_rotation) multiply(l.link_R);
      for (int i = 0; i < 3; ++i) M[i][0] += l.link_p[i];
    }
  }
  for (const ChainLink& l : chains_[0]) {
    if (!l.identity_link) {
      for (int i = 0; i < 3; ++i) M[i][0] -= l.link_p[i];
      if (!l.identity_rotation) multiply(l.link_Rt);
    }
    if (l.rotary)
      rotate(l, true);
    else
      for (int i = 0; i < 3; ++i) M[i][l.column] = lanes::splat<L>(-l.direction[i]);
  }
  // In w: p0 = Rw^T (m0 - tw), G = Rw^T [m1 m2 m3] with (Rw, tw) = w_end; so G s = p_w - p0
  // is [m1 m2 m3] s = y with y = Rw p_w + tw - m0, solved by Cramer's rule (det G = det M).
  const Eigen::Matrix3d& Rw = w_end_.linear();
  L y[3];
  for (int i = 0; i < 3; ++i)
    y[i] = Rw(i, 0) * p_w[0] + Rw(i, 1) * p_w[1] + Rw(i, 2) * p_w[2] + w_end_.translation()[i] -
           M[i][0];
  const auto cross = [&](int a, int b, L r[3]) TOLVER_LANE_LAMBDA {
    r[0] = M[1][a] * M[2][b] - M[2][a] * M[1][b];
    r[1] = M[2][a] * M[0][b] - M[0][a] * M[2][b];
    r[2] = M[0][a] * M[1][b] - M[1][a] * M[0][b];
  };
  L c23[3], c31[3], c12[3];
  cross(2, 3, c23);
  cross(3, 1, c31);
  cross(1, 2, c12);
  const L det = M[0][1] * c23[0] + M[1][1] * c23[1] + M[2][1] * c23[2];
  const auto ok = lanes::maskOf(lanes::absL(det) > 1e-12);
  const L inv_det = 1.0 / det;
  out[0] = (y[0] * c23[0] + y[1] * c23[1] + y[2] * c23[2]) * inv_det;
  out[1] = (y[0] * c31[0] + y[1] * c31[1] + y[2] * c31[2]) * inv_det;
  out[2] = (y[0] * c12[0] + y[1] * c12[1] + y[2] * c12[2]) * inv_det;
  return ok;
}

// Long by design: the closed-form rotary solutions, one short case per topology (one or two
// rotary axes, orthogonal or not, singular or not).
int InverseKinematics::rotaryCandidates(const Eigen::Vector3d& u_w, RotaryCandidate out[2],
                                        bool* singular) const {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  int count = 0;
  *singular = false;
  const Eigen::Vector3d k = Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d u = u_w.normalized();
  if (rotary_.empty()) {
    if ((C0_ * k - u).norm() < 1e-9) out[count++] = RotaryCandidate{};
    return count;
  }
  // Joint value = sign * phi: the cosine is unchanged, the sine takes the sign.
  auto set = [&](RotaryCandidate& c, int r, bool solved, double cs, double sn) {
    c.free[r] = !solved;
    c.cos[r] = solved ? cs : nan;
    c.sin[r] = solved ? sign_[r] * sn : nan;
  };
  if (rotary_.size() == 1) {
    // Rot(a1, phi) (C1 k) = C0^T u
    const Eigen::Vector3d p = C1_ * k, q = C0_.transpose() * u;
    if (std::abs(a_[0].dot(p) - a_[0].dot(q)) > 1e-9) return count;
    double c1 = 0.0, s1 = 0.0;
    const bool solved = subproblem1(a_[0], p, q, &c1, &s1);
    *singular = !solved;
    RotaryCandidate& c = out[count++];
    c = RotaryCandidate{};
    set(c, 0, solved, c1, s1);
    c.cos[1] = 1.0;  // the unused second slot: angle 0
    c.known[1] = true;
    return count;
  }
  // Two rotary axes: the closed form (candidatesL), refined where it loses accuracy.
  const double uw[3] = {u_w[0], u_w[1], u_w[2]};
  double cc[2][2], ss[2][2], g = 0.0;
  bool unreachable = false, free1 = false, free2 = false, refine = false;
  candidatesL(uw, cc, ss, &g, &unreachable, &free1, &free2, &refine);
  if (unreachable) return count;
  const Eigen::Vector3d& w1 = w1_;
  const Eigen::Vector3d& w2 = w2_;
  const Eigen::Vector3d& p = p2_;
  for (int ci = 0; ci < 2; ++ci) {
    RotaryCandidate& out_c = out[count++];
    out_c = RotaryCandidate{};
    double c1 = cc[ci][0], s1 = ss[ci][0], c2 = cc[ci][1], s2 = ss[ci][1];
    const bool solved1 = !free1, solved2 = !free2;
    if (!solved1 || !solved2) *singular = true;
    // A free angle is marked; solve() fills it from the previous point.
    if (solved1 && solved2 && refine) {
      // The closed form loses accuracy where gamma is small (the square root of a difference
      // amplifies rounding); two Gauss-Newton steps on Rot(w1, phi1) Rot(w2, phi2) p = q
      // restore it to rounding level.
      const Eigen::Vector3d q = C0_.transpose() * u;
      double phi1 = std::atan2(s1, c1), phi2 = std::atan2(s2, c2);
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
      phi1 = std::remainder(phi1, kTwoPi);
      phi2 = std::remainder(phi2, kTwoPi);
      c1 = std::cos(phi1);
      s1 = std::sin(phi1);
      c2 = std::cos(phi2);
      s2 = std::sin(phi2);
      out_c.angle = {sign_[0] * phi1, sign_[1] * phi2};
      out_c.known = {true, true};
    }
    set(out_c, 0, solved1, c1, s1);
    set(out_c, 1, solved2, c2, s2);
    if (g == 0.0) break;
  }
  return count;
}

bool InverseKinematics::solvePrismatic(const Eigen::Vector3d& p_w, JointVector& q, IkSolution* trig,
                                       const Eigen::Vector3d& b_t, bool trig_given) const {
  double qv[kMaxAxes], c[kMaxAxes], sn[kMaxAxes];
  for (int b = 0; b < 2; ++b)
    for (const ChainLink& l : chains_[b]) {
      qv[l.axis] = q[l.axis];
      if (!l.rotary) continue;
      if (!trig_given) {
        trig->cos_q[l.axis] = std::cos(q[l.axis]);
        trig->sin_q[l.axis] = std::sin(q[l.axis]);
      }
      c[l.axis] = trig->cos_q[l.axis];
      sn[l.axis] = trig->sin_q[l.axis];
    }
  const Eigen::Vector3d m0 = t_end_ * b_t;
  const double m0a[3] = {m0[0], m0[1], m0[2]}, pw[3] = {p_w[0], p_w[1], p_w[2]};
  double s[3];
  if (!prismaticL(qv, c, sn, m0a, pw, s)) return false;
  for (int b = 0; b < 2; ++b)
    for (const ChainLink& l : chains_[b])
      if (!l.rotary) q[l.axis] = s[l.column - 1];
  return std::isfinite(s[0]) && std::isfinite(s[1]) && std::isfinite(s[2]);
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

namespace {

// The continuity reference: the previous rotary values (zero at the start), with their cos and
// sin (given by the caller, or computed here).
struct RotaryReference {
  double angle[2] = {0.0, 0.0}, cos[2] = {1.0, 1.0}, sin[2] = {0.0, 0.0};
};

RotaryReference rotaryReference(const std::vector<int>& rotary, const JointVector* previous,
                                const double* previous_cos, const double* previous_sin) {
  RotaryReference ref;
  for (size_t r = 0; r < rotary.size() && previous; ++r) {
    const int a = rotary[r];
    ref.angle[r] = (*previous)[a];
    if (previous_cos) {
      ref.cos[r] = previous_cos[a];
      ref.sin[r] = previous_sin[a];
    } else {
      ref.cos[r] = std::cos(ref.angle[r]);
      ref.sin[r] = std::sin(ref.angle[r]);
    }
  }
  return ref;
}

// A free angle (a singular orientation) keeps the reference's value.
void pinFreeAngles(InverseKinematics::RotaryCandidate* cand, int ncand, int nr,
                   const RotaryReference& ref) {
  for (int ci = 0; ci < ncand; ++ci)
    for (int r = 0; r < nr; ++r)
      if (cand[ci].free[r]) {
        cand[ci].angle[r] = ref.angle[r];
        cand[ci].cos[r] = ref.cos[r];
        cand[ci].sin[r] = ref.sin[r];
        cand[ci].known[r] = true;
        cand[ci].free[r] = false;
      }
}

// Of two candidates, the one nearer to the reference by chords: the squared chord between the
// unit vectors (cos, sin) of candidate and reference, summed over the angles, in chord2.
int nearerByChords(const InverseKinematics::RotaryCandidate* cand, int nr,
                   const RotaryReference& ref, double chord2[2]) {
  for (int ci = 0; ci < 2; ++ci) {
    chord2[ci] = 0.0;
    for (int r = 0; r < nr; ++r) {
      const double dc = cand[ci].cos[r] - ref.cos[r], ds = cand[ci].sin[r] - ref.sin[r];
      chord2[ci] += dc * dc + ds * ds;
    }
  }
  return chord2[1] < chord2[0] ? 1 : 0;
}

}  // namespace

// The prediction's hot loop (a few hundred ns per point): the candidates' evaluation and
// attempt are lambdas over one stack frame so that nothing is allocated or copied between them.
IkSolution InverseKinematics::solve(const Eigen::Vector3d& p_w, const Eigen::Vector3d& u_w,
                                    const JointVector* previous, const double* previous_cos,
                                    const double* previous_sin, bool exact_angles) const {
  IkSolution sol;
  const int n = static_cast<int>(model_->axes.size());
  if (rotary_.size() > 2 || prismatic_.size() != 3 || parallel_rotaries_) {
    sol.q = JointVector::Zero(n);
    sol.status = IkStatus::UnsupportedTopology;
    return sol;
  }
  bool singular = false;
  RotaryCandidate cand[2];
  const int ncand = rotaryCandidates(u_w, cand, &singular);
  if (ncand == 0) {
    sol.q = JointVector::Zero(n);
    sol.status = IkStatus::UnreachableOrientation;
    return sol;
  }
  const int nr = static_cast<int>(rotary_.size());
  const RotaryReference reference = rotaryReference(rotary_, previous, previous_cos, previous_sin);
  const double* ref = reference.angle;
  const double* ref_cos = reference.cos;
  const double* ref_sin = reference.sin;
  pinFreeAngles(cand, ncand, nr, reference);
  auto violation = [&](int axis, double value) {
    if (sol.violated_axis < 0) {
      sol.violated_axis = axis;
      sol.violated_value = value;
    }
  };
  // A candidate's rotary values, unwrapped by 2 pi to the representatives inside travel nearest
  // to the reference, and its cost: the rotary motion from the reference (infinite when an angle
  // has no representative inside travel).
  double value[2][2] = {}, cost[2];
  bool evaluated[2] = {false, false};
  auto evaluate = [&](int ci) {
    if (evaluated[ci]) return;
    evaluated[ci] = true;
    cost[ci] = 0.0;
    for (int r = 0; r < nr; ++r) {
      const Axis& ax = model_->axes[rotary_[r]];
      // An endless axis (no stops) takes any representative: the continuity choice unwraps it.
      const double inf = std::numeric_limits<double>::infinity();
      const double lo = ax.endless ? -inf : ax.travel_min, hi = ax.endless ? inf : ax.travel_max;
      const RotaryCandidate& k = cand[ci];
      // Near the reference (the usual step along a path), the value is ref + delta with delta
      // from the cos and sin of the difference by atan's series: the representative nearest to
      // ref, without atan2 and unwrapping.
      double v = std::numeric_limits<double>::quiet_NaN();
      const double dc = k.cos[r] * ref_cos[r] + k.sin[r] * ref_sin[r];
      const double ds = k.sin[r] * ref_cos[r] - k.cos[r] * ref_sin[r];
      if (!exact_angles && !k.known[r] && dc > 0.0 && std::abs(ds) <= kAtanSeriesMax * dc) {
        v = ref[r] + atanOfSmall(ds / dc);
        if (v < lo - kTravelEps || v > hi + kTravelEps)
          v = std::numeric_limits<double>::quiet_NaN();
      }
      if (std::isnan(v)) {
        const double angle = k.angleOf(r);
        v = unwrapNear(angle, lo, hi, ref[r]);
        if (std::isnan(v)) {
          violation(rotary_[r], angle);
          cost[ci] = std::numeric_limits<double>::infinity();
          return;
        }
      }
      value[ci][r] = v;
      cost[ci] += std::abs(v - ref[r]);
    }
  };
  // The candidate with the prismatic solution, if inside every axis's travel.
  auto attempt = [&](int ci) {
    evaluate(ci);
    if (!std::isfinite(cost[ci])) return false;
    JointVector q(n);
    // Unwrapping by 2 pi keeps the cosine and sine of the candidate's angles.
    for (int r = 0; r < nr; ++r) {
      q[rotary_[r]] = value[ci][r];
      sol.cos_q[rotary_[r]] = cand[ci].cos[r];
      sol.sin_q[rotary_[r]] = cand[ci].sin[r];
    }
    if (!solvePrismatic(p_w, q, &sol, Eigen::Vector3d::Zero(), true)) return false;
    for (int a : prismatic_) {
      const Axis& ax = model_->axes[a];
      if (q[a] < ax.travel_min - kTravelEps || q[a] > ax.travel_max + kTravelEps) {
        violation(a, q[a]);
        return false;
      }
    }
    sol.q = q;
    sol.singular = singular;
    sol.violated_axis = -1;
    return true;
  };
  auto costOrder = [&](int order[2]) {
    for (int ci = 0; ci < ncand; ++ci) evaluate(ci);
    const bool swap = ncand == 2 && cost[1] < cost[0];
    order[0] = swap ? 1 : 0;
    order[1] = swap ? 0 : 1;
  };
  // Candidates in order of cost. Each angle's motion is at least the chord between the unit
  // vectors (cos, sin) of the candidate and of the reference, and a sum at least the root of
  // the sum of squares; so when the candidate nearer by chords costs less than the other's
  // bound, the other's angles (two atan2) are needed only if the first fails.
  int order[2] = {0, 1};
  if (ncand == 2) {
    double chord2[2];
    const int first = nearerByChords(cand, nr, reference, chord2);
    evaluate(first);
    if (std::isfinite(cost[first]) &&
        cost[first] * cost[first] < chord2[1 - first] * (1.0 - 1e-9)) {
      order[0] = first;
      order[1] = 1 - first;
    } else {
      costOrder(order);
    }
  }
  for (int k = 0; k < 2; ++k)
    if (order[k] < ncand && attempt(order[k])) return sol;
  // Nothing fits: report the violation of the solution the continuity choice prefers (the
  // cheapest by rotary motion): its rotary travel, then its prismatic solution.
  evaluated[0] = evaluated[1] = false;
  costOrder(order);  // (evaluating records the rotary violations of both: start afresh)
  sol.violated_axis = -1;
  evaluated[0] = evaluated[1] = false;
  if (order[0] < ncand) attempt(order[0]);
  if (sol.violated_axis < 0 && order[1] < ncand) attempt(order[1]);
  sol.q = JointVector::Zero(n);
  sol.status = IkStatus::OutOfTravel;
  return sol;
}

}  // namespace tolver

namespace tolver {

struct IkLaneKernels {
  template <typename V>
  TOLVER_LANE_INLINE static void blockLanes(const InverseKinematics& ik,
                                            InverseKinematics::Block& b);
  static void blockLanes4(const InverseKinematics& ik, InverseKinematics::Block& b);
  static void blockLanes8(const InverseKinematics& ik, InverseKinematics::Block& b);
  // Candidate k's prismatic solution at points i.. (L's width of them) from its cos and sin
  // (the sine's sign applied) into b.prism[k], and whether it lies inside travel into
  // b.prism_ok[k].
  template <typename L>
  TOLVER_LANE_INLINE static void prism(const InverseKinematics& ik, InverseKinematics::Block& b,
                                       int k, int i, L c0, L s0, L c1, L s1, const L p[3]) {
    using M = decltype(L{} < L{});
    const double m0[3] = {ik.t_end_.translation()[0], ik.t_end_.translation()[1],
                          ik.t_end_.translation()[2]};
    L cs[kMaxAxes], sn[kMaxAxes], out[3];
    cs[ik.rotary_[0]] = c0;
    sn[ik.rotary_[0]] = s0;
    cs[ik.rotary_[1]] = c1;
    sn[ik.rotary_[1]] = s1;
    M ok = ik.prismaticL(cs, cs, sn, m0, p, out);  // (q is read only off +x/+y/+z)
    for (int j = 0; j < 3; ++j) {
      const Axis& ax = ik.model_->axes[ik.column_axis_[j]];
      const double lo = ax.travel_min - kTravelEps, hi = ax.travel_max + kTravelEps;
      lanes::storeL<L>(b.prism[k][j] + i, out[j]);
      ok = ok & lanes::maskOf((out[j] - out[j]) == 0.0) & lanes::maskOf(!(out[j] < lo)) &
           lanes::maskOf(!(out[j] > hi));
    }
    lanes::storeMask<M>(b.prism_ok[k] + i, ok);
  }
  // The same for one point, where the lane stage left it (Block::prism_only).
  static void prismAt(const InverseKinematics& ik, InverseKinematics::Block& b, int k, int i) {
    const double p[3] = {b.p[0][i], b.p[1][i], b.p[2][i]};
    prism<double>(ik, b, k, i, b.cand_c[k][0][i + 1], b.cand_s[k][0][i + 1], b.cand_c[k][1][i + 1],
                  b.cand_s[k][1][i + 1], p);
  }
};

// solveBlock's lane stage: the candidates and both prismatic solutions of every point, then the
// angle steps from each candidate of the previous point, V's width of points at a time (the
// tail one at a time, with the same operations).
template <typename V>
TOLVER_LANE_INLINE void IkLaneKernels::blockLanes(const InverseKinematics& ik,
                                                  InverseKinematics::Block& b) {
  using lanes::loadL;
  using lanes::loadMask;
  using lanes::storeL;
  using lanes::storeMask;
  const int n = b.n;
  const double sign0 = ik.sign_[0], sign1 = ik.sign_[1];
  const int only = b.prism_only;
  auto points = [&](auto lanes_tag, int i) TOLVER_LANE_LAMBDA {
    using L = decltype(lanes_tag);
    using M = decltype(L{} < L{});
    const L u[3] = {loadL<L>(b.u[0] + i), loadL<L>(b.u[1] + i), loadL<L>(b.u[2] + i)};
    const L p[3] = {loadL<L>(b.p[0] + i), loadL<L>(b.p[1] + i), loadL<L>(b.p[2] + i)};
    L c[2][2], s[2][2], g;
    M unreachable, free1, free2, refine;
    ik.candidatesL(u, c, s, &g, &unreachable, &free1, &free2, &refine);
    storeMask<M>(b.irregular + i, unreachable | free1 | free2 | refine);
    for (int k = 0; k < 2; ++k) {
      const L s0 = sign0 * s[k][0], s1 = sign1 * s[k][1];
      storeL<L>(b.cand_c[k][0] + i + 1, c[k][0]);
      storeL<L>(b.cand_s[k][0] + i + 1, s0);
      storeL<L>(b.cand_c[k][1] + i + 1, c[k][1]);
      storeL<L>(b.cand_s[k][1] + i + 1, s1);
      if (only < 0 || k == only)
        prism<L>(ik, b, k, i, c[k][0], s0, c[k][1], s1, p);
      else
        storeMask<M>(b.prism_ok[k] + i, M{});  // (blockChoice computes it when needed)
    }
  };
  auto steps = [&](auto lanes_tag, int i) TOLVER_LANE_LAMBDA {
    using L = decltype(lanes_tag);
    using M = decltype(L{} < L{});
    for (int j = 0; j < 2; ++j)
      for (int k = 0; k < 2; ++k) {
        L chord = lanes::splat<L>(0.0);
        for (int r = 0; r < 2; ++r) {
          const L ref_c = loadL<L>(b.cand_c[j][r] + i), ref_s = loadL<L>(b.cand_s[j][r] + i);
          const L kc = loadL<L>(b.cand_c[k][r] + i + 1), ks = loadL<L>(b.cand_s[k][r] + i + 1);
          // As solve()'s chords.
          const L ec = kc - ref_c, es = ks - ref_s;
          chord += ec * ec + es * es;
          // As solve()'s evaluate: the step from the reference by atan's series; along a path
          // the branch continues (k = j), the other steps are taken point by point when needed.
          if (j != k) continue;
          const L dc = kc * ref_c + ks * ref_s;
          const L ds = ks * ref_c - kc * ref_s;
          const M ok =
              lanes::maskOf(dc > 0.0) & lanes::maskOf(lanes::absL(ds) <= kAtanSeriesMax * dc);
          storeL<L>(b.delta[k][r] + i, atanOfSmallL(ds / dc));
          storeMask<M>(b.delta_ok[k][r] + i, ok);
        }
        storeL<L>(b.chord2[j][k] + i, chord);
      }
    for (int j = 0; j < 2; ++j) {
      // blockChoice's first == j, first = chord2[j][1] < chord2[j][0] ? 1 : 0
      const L same = loadL<L>(b.chord2[j][j] + i), other = loadL<L>(b.chord2[j][1 - j] + i);
      const M first_is_j = j == 0 ? lanes::maskOf(!(other < same)) : lanes::maskOf(same < other);
      const M common = lanes::notMask(loadMask<M>(b.irregular + i)) & first_is_j &
                       loadMask<M>(b.delta_ok[j][0] + i) & loadMask<M>(b.delta_ok[j][1] + i) &
                       loadMask<M>(b.prism_ok[j] + i);
      storeMask<M>(b.common[j] + i, common);
    }
  };
  constexpr int width = lanes::widthOf<V>();
  int i = 0;
  for (; i + width <= n; i += width) points(V{}, i);
  for (; i < n; ++i) points(0.0, i);
  for (i = 0; i + width <= n; i += width) steps(V{}, i);
  for (; i < n; ++i) steps(0.0, i);
}

TOLVER_LANE_CLONES
void IkLaneKernels::blockLanes4(const InverseKinematics& ik, InverseKinematics::Block& b) {
  blockLanes<lanes::Lane4>(ik, b);
}

#if TOLVER_HAS_WIDE_LANES
TOLVER_LANE_WIDE
void IkLaneKernels::blockLanes8(const InverseKinematics& ik, InverseKinematics::Block& b) {
  blockLanes<lanes::Lane8>(ik, b);
}
#else
void IkLaneKernels::blockLanes8(const InverseKinematics& ik, InverseKinematics::Block& b) {
  blockLanes4(ik, b);
}
#endif

// Long by design: solve()'s continuity choice written out for the common case, on the lane
// stage's numbers, with solve() itself for every other case.
void InverseKinematics::blockLanes(Block& b) const {
  assert(batchable_);
  // Index 0: the candidates of the point before the block (the lane stage's operations), read
  // only when that point was solved from one of them.
  double cc[2][2] = {{1.0, 1.0}, {1.0, 1.0}}, ss[2][2] = {};
  if (b.has_before) {
    double g;
    bool unreachable, free1, free2, refine;
    candidatesL(b.u_before, cc, ss, &g, &unreachable, &free1, &free2, &refine);
    for (int k = 0; k < 2; ++k)
      for (int r = 0; r < 2; ++r) ss[k][r] = sign_[r] * ss[k][r];
  }
  for (int k = 0; k < 2; ++k)
    for (int r = 0; r < 2; ++r) {
      b.cand_c[k][r][0] = cc[k][r];
      b.cand_s[k][r][0] = ss[k][r];
    }
  if (lanes::wideLanes())
    IkLaneKernels::blockLanes8(*this, b);
  else
    IkLaneKernels::blockLanes4(*this, b);
}

void InverseKinematics::blockChoice(Block& b, Cursor& cursor) const {
  const int n = b.n;
  const int axes = static_cast<int>(model_->axes.size());
  const int ra[2] = {rotary_[0], rotary_[1]};
  double lo[2], hi[2];
  for (int r = 0; r < 2; ++r) {
    const Axis& ax = model_->axes[ra[r]];
    const double inf = std::numeric_limits<double>::infinity();
    lo[r] = (ax.endless ? -inf : ax.travel_min) - kTravelEps;
    hi[r] = (ax.endless ? inf : ax.travel_max) + kTravelEps;
  }
  // The common case's state in locals, which the loop keeps in registers: the candidate the
  // previous point was solved from (-1: none), its rotary values, and the last point solved
  // here since the cursor was written (-1: none). The cursor is written from the block's
  // numbers before solve() reads it and at the end.
  int j = cursor.previous_candidate;
  double ref[2] = {0.0, 0.0};
  if (j >= 0)
    for (int r = 0; r < 2; ++r) ref[r] = cursor.previous[ra[r]];
  int last = -1, from_lanes = 0;
  const auto writeCursor = [&] {
    if (last < 0) return;
    const int k = b.taken[last];  // (= j)
    for (int r = 0; r < 2; ++r) {
      cursor.previous[ra[r]] = b.q[ra[r]][last];
      cursor.previous_cos[ra[r]] = b.cand_c[k][r][last + 1];
      cursor.previous_sin[ra[r]] = b.cand_s[k][r][last + 1];
    }
    for (int col = 0; col < 3; ++col) cursor.previous[column_axis_[col]] = b.prism[k][col][last];
    cursor.previous_candidate = k;
    last = -1;
  };
  for (int i = 0; i < n; ++i) {
    const bool exact = i == 0 && b.exact_first;  // (solve() only)
    // The common case, tested in lanes: the branch continues, its steps give the values.
    if (!exact && j >= 0 && b.common[j][i]) {
      const double v0 = ref[0] + b.delta[j][0][i], v1 = ref[1] + b.delta[j][1][i];
      if (!(v0 < lo[0] || v0 > hi[0] || v1 < lo[1] || v1 > hi[1])) {
        const double cost = std::abs(v0 - ref[0]) + std::abs(v1 - ref[1]);
        if (cost * cost < b.chord2[j][1 - j][i] * (1.0 - 1e-9)) {
          b.q[ra[0]][i] = ref[0] = v0;
          b.q[ra[1]][i] = ref[1] = v1;
          b.taken[i] = static_cast<signed char>(j);
          last = i;
          ++from_lanes;
          continue;
        }
      }
    }
    // The same written out for any regular point after a point solved from its own candidate
    // (a change of branch included).
    int chosen = -1;
    double value[2][2];
    if (!exact && j >= 0 && !b.irregular[i]) {
      double cost[2];
      auto evaluate = [&](int k) {
        cost[k] = 0.0;
        for (int r = 0; r < 2; ++r) {
          double delta;
          if (k == j) {
            if (!b.delta_ok[k][r][i]) return false;
            delta = b.delta[k][r][i];
          } else {  // the lane stage's operations, for a branch change
            const double ref_c = b.cand_c[j][r][i], ref_s = b.cand_s[j][r][i];
            const double kc = b.cand_c[k][r][i + 1], ks = b.cand_s[k][r][i + 1];
            const double dc = kc * ref_c + ks * ref_s;
            const double ds = ks * ref_c - kc * ref_s;
            if (!(dc > 0.0 && std::abs(ds) <= kAtanSeriesMax * dc)) return false;
            delta = atanOfSmallL(ds / dc);
          }
          const double v = ref[r] + delta;
          if (v < lo[r] || v > hi[r]) return false;
          value[k][r] = v;
          cost[k] += std::abs(v - ref[r]);
        }
        return true;
      };
      const int first = b.chord2[j][1][i] < b.chord2[j][0][i] ? 1 : 0;
      // solve()'s shortcut: the candidate nearer by chords, when it costs less than the other
      // could (two candidates that near each other are near the pole: left to solve()).
      if (evaluate(first) && cost[first] * cost[first] < b.chord2[j][1 - first][i] * (1.0 - 1e-9))
        chosen = first;
      if (chosen >= 0 && b.prism_only >= 0 && chosen != b.prism_only)
        IkLaneKernels::prismAt(*this, b, chosen, i);
      if (chosen >= 0 && !b.prism_ok[chosen][i]) chosen = -1;
    }
    if (chosen >= 0) {
      for (int r = 0; r < 2; ++r) b.q[ra[r]][i] = ref[r] = value[chosen][r];
      b.taken[i] = static_cast<signed char>(chosen);
      j = chosen;
      last = i;
      ++from_lanes;
      continue;
    }
    // Anything else: solve() itself, from the same reference.
    b.taken[i] = -1;
    writeCursor();
    const Eigen::Vector3d p(b.p[0][i], b.p[1][i], b.p[2][i]), u(b.u[0][i], b.u[1][i], b.u[2][i]);
    const IkSolution sol = solve(p, u, cursor.has_previous ? &cursor.previous : nullptr,
                                 cursor.previous_cos.data(), cursor.previous_sin.data(), exact);
    b.status[i] = sol.status;
    b.singular[i] = sol.singular;
    b.violated_axis[i] = sol.violated_axis;
    b.violated_value[i] = sol.violated_value;
    const bool ok = sol.status == IkStatus::Ok;
    for (int a = 0; a < axes; ++a) {
      const bool rotary = model_->axes[a].isRotary();
      b.q[a][i] = ok ? sol.q[a] : 0.0;
      b.c[a][i] = ok && rotary ? sol.cos_q[a] : 1.0;
      b.s[a][i] = ok && rotary ? sol.sin_q[a] : 0.0;
    }
    cursor.has_previous = ok;
    cursor.previous_candidate = j = -1;
    if (!ok) continue;
    cursor.previous = sol.q;
    cursor.previous_cos = sol.cos_q;
    cursor.previous_sin = sol.sin_q;
    // The next point can start from the lane stage's steps if this solution is one of the
    // candidates, bit for bit.
    for (int k = 0; k < 2 && !b.irregular[i]; ++k)
      if (sol.cos_q[ra[0]] == b.cand_c[k][0][i + 1] && sol.sin_q[ra[0]] == b.cand_s[k][0][i + 1] &&
          sol.cos_q[ra[1]] == b.cand_c[k][1][i + 1] && sol.sin_q[ra[1]] == b.cand_s[k][1][i + 1]) {
        cursor.previous_candidate = j = k;
        break;
      }
    for (int r = 0; r < 2; ++r) ref[r] = sol.q[ra[r]];
  }
  // The other numbers of the points solved from a candidate: its cos and sin (c and s of the
  // prismatic axes are not read: Block's rotary ones only) and its prismatic solution.
  for (int i = 0; i < n; ++i) {
    const int k = b.taken[i];
    if (k < 0) continue;
    for (int r = 0; r < 2; ++r) {
      b.c[ra[r]][i] = b.cand_c[k][r][i + 1];
      b.s[ra[r]][i] = b.cand_s[k][r][i + 1];
    }
    for (int col = 0; col < 3; ++col) b.q[column_axis_[col]][i] = b.prism[k][col][i];
    b.status[i] = IkStatus::Ok;
    b.singular[i] = false;
    b.violated_axis[i] = -1;
    b.violated_value[i] = 0.0;
  }
  writeCursor();
  b.from_lanes = from_lanes;
}

}  // namespace tolver
