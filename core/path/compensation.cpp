#include "core/path/compensation.h"

#include <Eigen/LU>
#include <Eigen/QR>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <random>

#include "core/kinematics/forward_kinematics.h"

namespace tolver {
namespace {

constexpr double kLever = 100.0;  // mm: orientation rows scaled to tip-like units
constexpr int kMaxRows = 5;

using Residual = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxRows, 1>;
using Jac = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxRows, kMaxAxes>;

double angleBetween(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b));
}

}  // namespace

CompensationResult compensateToolPath(const MachineModel& model, const Eigen::VectorXd& params,
                                      const std::vector<ClPoint>& path,
                                      const std::vector<JointVector>& q0, bool orientation,
                                      const CompensationOptions& opt,
                                      const std::vector<PredictedPoint>* predicted) {
  const ForwardKinematics fk(model, params);
  const ForwardKinematics nominal(model, Eigen::VectorXd::Zero(params.size()));
  const int n = static_cast<int>(model.axes.size());
  std::vector<int> all, prismatic;  // the joints Newton moves: all of them, or the linear ones
  for (int a = 0; a < n; ++a) {
    all.push_back(a);
    if (!model.axes[a].isRotary()) prismatic.push_back(a);
  }
  CompensationResult out;
  out.points.resize(path.size());
  Residual r(5), r_new(5);
  // The Jacobian of the residual by forward differences, kept from point to point while it still
  // converges (a chord method: a path's poses change slowly), with its LU, the joints it was
  // taken at and which unknowns it is for. The orientation rows use a basis across the tool axis
  // carried along the path (parallel transport), so that the kept Jacobian stays valid.
  Jac J(5, n);
  using Lu = Eigen::PartialPivLU<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxRows, kMaxRows>>;
  Lu lu;
  bool have_J = false, J_axis = false;
  JointVector J_q;
  double J_cond = 1;
  Eigen::Vector3d e1 = Eigen::Vector3d::Zero();
  bool warm_ok = false, warm_axis = false;  // the previous point's correction, for a warm start
  JointVector warm_q0, warm_dq;
  for (size_t i = 0; i < path.size(); ++i) {
    CompensatedPoint& c = out.points[i];
    const ClPoint& target = path[i];
    const Eigen::Vector3d u_t = target.u_w.normalized();
    {
      const Eigen::Vector3d t = e1 - e1.dot(u_t) * u_t;
      e1 = t.norm() > 0.5 ? t.normalized() : u_t.unitOrthogonal();
    }
    const Eigen::Vector3d e2 = u_t.cross(e1);
    c.q0 = q0[i];
    Eigen::Vector3d p0, u0;  // the machine's pose at q0
    if (predicted) {
      p0 = (*predicted)[i].p_pred_w;
      u0 = (*predicted)[i].u_pred_w;
    } else {
      fk.tipAndAxis(q0[i], &p0, &u0);
    }
    // Newton from q0 on the chosen joints and rows; returns whether it converged.
    auto solve = [&](bool with_axis, JointVector& q, Eigen::Vector3d& p, Eigen::Vector3d& u, double* cond) {
      const std::vector<int>& vars = with_axis ? all : prismatic;
      const int rows = with_axis ? 5 : 3, nv = static_cast<int>(vars.size());
      r.resize(rows);
      r_new.resize(rows);
      auto toResidual = [&](const Eigen::Vector3d& pp, const Eigen::Vector3d& uu, Residual& res) {
        res.head<3>() = pp - target.p_w;
        if (with_axis) {
          res[3] = kLever * e1.dot(uu);
          res[4] = kLever * e2.dot(uu);
        }
      };
      auto freshJacobian = [&](const JointVector& at) {
        J.resize(rows, nv);
        Residual r0(rows), rh(rows);
        Eigen::Vector3d pa, ua;
        fk.tipAndAxis(at, &pa, &ua);
        toResidual(pa, ua, r0);
        for (int k = 0; k < nv; ++k) {
          const double h = 1e-6;
          JointVector qh = at;
          qh[vars[k]] += h;
          Eigen::Vector3d ph, uh;
          fk.tipAndAxis(qh, &ph, &uh);
          toResidual(ph, uh, rh);
          J.col(k) = (rh - r0) / h;
        }
        if (rows == nv) {
          lu.compute(J);
          J_cond = 1.0 / std::max(lu.rcond(), 1e-300);
        } else {
          const Eigen::JacobiSVD<Jac> svd(J);
          const auto sv = svd.singularValues();
          J_cond = sv[sv.size() - 1] > 0 ? sv[0] / sv[sv.size() - 1] : INFINITY;
        }
        have_J = true;
        J_axis = with_axis;
        J_q = at;
      };
      // Whether the kept Jacobian may serve this point: same unknowns, nearby joints.
      auto near = [&](const JointVector& a, const JointVector& b) {
        for (int k = 0; k < n; ++k)
          if (std::abs(a[k] - b[k]) > (model.axes[k].isRotary() ? 0.05 : 50.0)) return false;
        return true;
      };
      q = q0[i];
      p = p0;
      u = u0;
      toResidual(p, u, r);
      // Warm start: the previous point's correction (corrections vary slowly along a path).
      if (warm_ok && warm_axis == with_axis && near(warm_q0, q0[i])) {
        JointVector qs = q0[i] + warm_dq;
        Eigen::Vector3d ps, us;
        Residual rs(rows);
        fk.tipAndAxis(qs, &ps, &us);
        toResidual(ps, us, rs);
        if (rs.norm() < r.norm()) {
          q = qs;
          p = ps;
          u = us;
          r = rs;
        }
      }
      bool fresh = false;
      if (!(have_J && J_axis == with_axis && J_q.size() == q.size() && near(J_q, q))) {
        freshJacobian(q);
        fresh = true;
      }
      *cond = J_cond;
      for (int it = 0; it <= opt.max_iterations; ++it) {
        // |u x u_t| is the angle to 1e-18 here (and u . u_t > 0: the axis is never reversed).
        const double ang_err = with_axis ? u.cross(u_t).norm() : 0.0;
        if (r.head<3>().norm() <= opt.tolerance && ang_err <= opt.angle_tolerance && u.dot(u_t) > 0) return true;
        if (it == opt.max_iterations) return false;
        c.iterations = it + 1;
        if (J_cond > opt.max_condition) {
          if (fresh) return false;
          freshJacobian(q);  // the kept one may be the ill-conditioned one: look again here
          fresh = true;
          *cond = J_cond;
          --it;
          continue;
        }
        Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxAxes, 1> dq;
        if (rows == nv)
          dq = lu.solve(r);
        else
          dq = J.completeOrthogonalDecomposition().solve(r);
        JointVector q_new = q;
        for (int k = 0; k < nv; ++k) q_new[vars[k]] -= dq[k];
        Eigen::Vector3d p_new, u_new;
        fk.tipAndAxis(q_new, &p_new, &u_new);
        toResidual(p_new, u_new, r_new);
        if (r_new.norm() > 0.1 * r.norm() && !fresh) {
          // The kept Jacobian no longer converges fast: a fresh one where the step landed (or
          // here, when the step did not help).
          const bool better = r_new.norm() < r.norm();
          freshJacobian(better ? q_new : q);
          fresh = true;
          *cond = J_cond;
          if (!better) continue;
        }
        q = q_new;
        p = p_new;
        u = u_new;
        r = r_new;
      }
      return false;
    };
    JointVector q;
    Eigen::Vector3d p, u;
    c.before_w = p0 - target.p_w;
    c.before_axis = angleBetween(u0, u_t);
    double cond = 1;
    bool converged = solve(orientation, q, p, u, &cond);
    c.condition = cond;
    if (orientation && !converged && cond > opt.max_condition) {
      // Near a singular pose: correcting the tool axis would swing a rotary axis. The axis is
      // left as programmed, the tip compensated by the linear joints.
      c.status = CompensationStatus::IllConditioned;
      double cond3 = 1;
      converged = solve(false, q, p, u, &cond3);
      if (!converged) c.status = CompensationStatus::NotConverged;
    } else {
      c.status = converged ? CompensationStatus::Compensated : CompensationStatus::NotConverged;
    }
    for (int a = 0; a < n && c.status != CompensationStatus::NotConverged; ++a) {
      const Axis& ax = model.axes[a];
      if (ax.endless) continue;
      const double slack = ax.isRotary() ? 1e-9 : 1e-7;
      if (q[a] < ax.travel_min - slack || q[a] > ax.travel_max + slack) {
        c.status = CompensationStatus::OutOfTravel;
        c.axis_out = a;
        break;
      }
    }
    if (c.status == CompensationStatus::OutOfTravel || c.status == CompensationStatus::NotConverged) {
      q = q0[i];
      fk.tipAndAxis(q, &p, &u);
    }
    out.ill_conditioned += c.status == CompensationStatus::IllConditioned;
    out.out_of_travel += c.status == CompensationStatus::OutOfTravel;
    out.not_converged += c.status == CompensationStatus::NotConverged;
    warm_ok = c.status == CompensationStatus::Compensated || c.status == CompensationStatus::IllConditioned;
    warm_axis = orientation && c.status == CompensationStatus::Compensated;
    warm_q0 = q0[i];
    warm_dq = q - q0[i];
    c.q = q;
    c.after_w = p - target.p_w;
    c.after_axis = angleBetween(u, u_t);
    nominal.tipAndAxis(q, &c.nominal_p_w, &c.nominal_u_w);
  }
  return out;
}

std::vector<AxisTable> linearAxisTables(const MachineModel& model, const Eigen::VectorXd& params,
                                        const JointVector& q_ref, double step) {
  std::vector<int> prismatic;
  for (int a = 0; a < static_cast<int>(model.axes.size()); ++a)
    if (!model.axes[a].isRotary()) prismatic.push_back(a);
  const ForwardKinematics nominal(model, Eigen::VectorXd::Zero(params.size()));
  std::vector<AxisTable> out;
  for (int a : prismatic) {
    const Axis& ax = model.axes[a];
    AxisTable t;
    t.axis = a;
    t.step = step;
    t.prismatic = prismatic;
    // A grid through the reference position, covering the travel.
    const double ref = std::clamp(q_ref[a], ax.travel_min, ax.travel_max);
    const int below = static_cast<int>(std::floor((ref - ax.travel_min) / step + 1e-9));
    const int above = static_cast<int>(std::floor((ax.travel_max - ref) / step + 1e-9));
    t.start = ref - below * step;
    std::vector<ClPoint> path;
    std::vector<JointVector> q0;
    for (int k = -below; k <= above; ++k) {
      JointVector q = q_ref;
      q[a] = ref + k * step;
      ClPoint c;
      nominal.tipAndAxis(q, &c.p_w, &c.u_w);
      path.push_back(c);
      q0.push_back(q);
      t.position.push_back(q[a]);
    }
    CompensationOptions co;
    const CompensationResult r = compensateToolPath(model, params, path, q0, false, co);
    const CompensatedPoint& zero = r.points[below];
    for (const CompensatedPoint& c : r.points) {
      Eigen::Vector3d d = Eigen::Vector3d::Zero();
      for (size_t k = 0; k < prismatic.size() && k < 3; ++k)
        d[k] = (c.q[prismatic[k]] - c.q0[prismatic[k]]) - (zero.q[prismatic[k]] - zero.q0[prismatic[k]]);
      t.correction.push_back(d);
    }
    out.push_back(t);
  }
  return out;
}

Eigen::Vector3d tableCorrection(const std::vector<AxisTable>& tables, const JointVector& q) {
  Eigen::Vector3d d = Eigen::Vector3d::Zero();
  for (const AxisTable& t : tables) {
    if (t.position.empty()) continue;
    const double x = (q[t.axis] - t.start) / t.step;
    const int last = static_cast<int>(t.position.size()) - 1;
    const int k = std::clamp(static_cast<int>(std::floor(x)), 0, std::max(0, last - 1));
    const double f = last == 0 ? 0.0 : std::clamp(x - k, 0.0, 1.0);
    d += (1.0 - f) * t.correction[k] + f * t.correction[std::min(k + 1, last)];
  }
  return d;
}

TableEffect tableEffect(const MachineModel& model, const Eigen::VectorXd& params,
                        const std::vector<AxisTable>& tables, const JointVector& q_ref,
                        bool rotaries_move, int samples, unsigned seed) {
  const ForwardKinematics fk(model, params), nominal(model, Eigen::VectorXd::Zero(params.size()));
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  TableEffect e;
  // The deviation at the reference pose is a constant the work offset takes up (touching off):
  // both figures are relative to it.
  Eigen::Vector3d d_ref;
  {
    Eigen::Vector3d pn, pe, uu;
    nominal.tipAndAxis(q_ref, &pn, &uu);
    fk.tipAndAxis(q_ref, &pe, &uu);
    d_ref = pe - pn;
  }
  for (int i = 0; i < samples; ++i) {
    JointVector q = q_ref;
    for (size_t a = 0; a < model.axes.size(); ++a) {
      const Axis& ax = model.axes[a];
      if (ax.isRotary() && !rotaries_move) continue;
      q[a] = ax.travel_min + uni(rng) * (ax.travel_max - ax.travel_min);
    }
    Eigen::Vector3d p_nom, p, u;
    nominal.tipAndAxis(q, &p_nom, &u);
    fk.tipAndAxis(q, &p, &u);
    e.before_rms += (p - p_nom - d_ref).squaredNorm();
    JointVector qc = q;
    const Eigen::Vector3d d = tableCorrection(tables, q);
    if (!tables.empty())
      for (size_t k = 0; k < tables[0].prismatic.size() && k < 3; ++k) qc[tables[0].prismatic[k]] += d[k];
    fk.tipAndAxis(qc, &p, &u);
    e.after_rms += (p - p_nom - d_ref).squaredNorm();
  }
  e.before_rms = std::sqrt(e.before_rms / samples);
  e.after_rms = std::sqrt(e.after_rms / samples);
  return e;
}

}  // namespace tolver
