#include "core/compensation.h"

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>

#include "core/forward_kinematics.h"

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
                                      const CompensationOptions& opt) {
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
  Residual r(5), r_h(5);
  Jac J(5, n);
  for (size_t i = 0; i < path.size(); ++i) {
    CompensatedPoint& c = out.points[i];
    const ClPoint& target = path[i];
    const Eigen::Vector3d u_t = target.u_w.normalized();
    const Eigen::Vector3d e1 = u_t.unitOrthogonal(), e2 = u_t.cross(e1);
    c.q0 = q0[i];
    // Newton from q0 on the chosen joints and rows; returns whether it converged.
    auto solve = [&](bool with_axis, JointVector& q, Eigen::Vector3d& p, Eigen::Vector3d& u, double* cond) {
      const std::vector<int>& vars = with_axis ? all : prismatic;
      const int rows = with_axis ? 5 : 3, nv = static_cast<int>(vars.size());
      r.resize(rows);
      r_h.resize(rows);
      J.resize(rows, nv);
      auto residual = [&](const JointVector& qq, Residual& res, Eigen::Vector3d* pp, Eigen::Vector3d* uu) {
        fk.tipAndAxis(qq, pp, uu);
        res.head<3>() = *pp - target.p_w;
        if (with_axis) {
          res[3] = kLever * e1.dot(*uu);
          res[4] = kLever * e2.dot(*uu);
        }
      };
      q = q0[i];
      residual(q, r, &p, &u);
      *cond = 1;
      for (int it = 0; it <= opt.max_iterations; ++it) {
        const double ang_err = with_axis ? angleBetween(u, u_t) : 0.0;
        if (r.head<3>().norm() <= opt.tolerance && ang_err <= opt.angle_tolerance) return true;
        if (it == opt.max_iterations) return false;
        c.iterations = it + 1;
        for (int k = 0; k < nv; ++k) {
          const double h = 1e-6;
          JointVector qh = q;
          qh[vars[k]] += h;
          Eigen::Vector3d ph, uh;
          residual(qh, r_h, &ph, &uh);
          J.col(k) = (r_h - r) / h;
        }
        const Eigen::JacobiSVD<Jac> svd(J, Eigen::ComputeFullU | Eigen::ComputeFullV);
        const auto s = svd.singularValues();
        *cond = s[s.size() - 1] > 0 ? s[0] / s[s.size() - 1] : INFINITY;
        if (*cond > opt.max_condition) return false;
        const Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxAxes, 1> dq = svd.solve(r);
        for (int k = 0; k < nv; ++k) q[vars[k]] -= dq[k];
        residual(q, r, &p, &u);
      }
      return false;
    };
    JointVector q;
    Eigen::Vector3d p, u;
    {
      fk.tipAndAxis(q0[i], &p, &u);
      c.before_w = p - target.p_w;
      c.before_axis = angleBetween(u, u_t);
    }
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
    c.q = q;
    c.after_w = p - target.p_w;
    c.after_axis = angleBetween(u, u_t);
    nominal.tipAndAxis(q, &c.nominal_p_w, &c.nominal_u_w);
  }
  return out;
}

}  // namespace tolver
