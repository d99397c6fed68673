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
  std::vector<int> vars;  // the joints Newton moves
  for (int a = 0; a < n; ++a)
    if (orientation || !model.axes[a].isRotary()) vars.push_back(a);
  const int rows = orientation ? 5 : 3;
  const int nv = static_cast<int>(vars.size());
  CompensationResult out;
  out.points.resize(path.size());
  Residual r(rows), r_h(rows);
  Jac J(rows, nv);
  for (size_t i = 0; i < path.size(); ++i) {
    CompensatedPoint& c = out.points[i];
    const ClPoint& target = path[i];
    const Eigen::Vector3d u_t = target.u_w.normalized();
    const Eigen::Vector3d e1 = u_t.unitOrthogonal(), e2 = u_t.cross(e1);
    auto residual = [&](const JointVector& q, Residual& res, Eigen::Vector3d* p, Eigen::Vector3d* u) {
      fk.tipAndAxis(q, p, u);
      res.head<3>() = *p - target.p_w;
      if (orientation) {
        res[3] = kLever * e1.dot(*u);
        res[4] = kLever * e2.dot(*u);
      }
    };
    c.q0 = q0[i];
    JointVector q = q0[i];
    Eigen::Vector3d p, u;
    residual(q, r, &p, &u);
    c.before_w = p - target.p_w;
    c.before_axis = angleBetween(u, u_t);
    double cond = 1;
    bool converged = false;
    for (int it = 0; it <= opt.max_iterations; ++it) {
      const double tip_err = r.head<3>().norm();
      const double ang_err = orientation ? angleBetween(u, u_t) : 0.0;
      if (tip_err <= opt.tolerance && ang_err <= opt.angle_tolerance) {
        converged = true;
        break;
      }
      if (it == opt.max_iterations) break;
      c.iterations = it + 1;
      for (int k = 0; k < nv; ++k) {
        const int a = vars[k];
        const double h = 1e-6;
        JointVector qh = q;
        qh[a] += h;
        Eigen::Vector3d ph, uh;
        residual(qh, r_h, &ph, &uh);
        J.col(k) = (r_h - r) / h;
      }
      const Eigen::JacobiSVD<Jac> svd(J, Eigen::ComputeFullU | Eigen::ComputeFullV);
      const auto s = svd.singularValues();
      cond = s[s.size() - 1] > 0 ? s[0] / s[s.size() - 1] : INFINITY;
      // Truncated pseudo-inverse step.
      Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxAxes, 1> dq = Eigen::VectorXd::Zero(nv);
      const Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxRows, 1> ur = svd.matrixU().transpose() * r;
      for (int k = 0; k < s.size(); ++k)
        if (s[k] > s[0] / opt.max_condition) dq += svd.matrixV().col(k) * (ur[k] / s[k]);
      for (int k = 0; k < nv; ++k) q[vars[k]] -= dq[k];
      residual(q, r, &p, &u);
      // Ill-conditioned points converge only in the directions they can be moved: stop when
      // the step stops changing anything.
      if (cond > opt.max_condition && dq.norm() < 1e-12) break;
    }
    c.condition = cond;
    c.status = cond > opt.max_condition ? CompensationStatus::IllConditioned
               : converged              ? CompensationStatus::Compensated
                                        : CompensationStatus::NotConverged;
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
      residual(q, r, &p, &u);
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
