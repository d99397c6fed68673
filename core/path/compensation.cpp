#include "core/path/compensation.h"

#include <Eigen/LU>
#include <Eigen/QR>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <memory>
#include <random>

#include "core/kinematics/forward_kinematics.h"

namespace tolver {
namespace {

constexpr double kLever = 100.0;  // mm: orientation rows scaled to tip-like units
constexpr int kMaxRows = 5;

using Residual = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxRows, 1>;
using Jac = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxRows, kMaxAxes>;

double angleOf(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b));
}

// Compensation point by point along a path. The Jacobian of the residual is taken by forward
// differences and kept from point to point while it still converges (a chord method: a path's
// poses change slowly), with its LU, the joints it was taken at and which unknowns it is for. The
// orientation rows use a basis across the tool axis carried along the path (parallel transport),
// so that the kept Jacobian stays valid. Each point starts from the previous point's correction
// (corrections vary slowly along a path).
class PathCompensator {
 public:
  PathCompensator(const MachineModel& model, const Eigen::VectorXd& params,
                  const CompensationOptions& opt)
      : model_(model),
        opt_(opt),
        fk_(model, params),
        nominal_(model, Eigen::VectorXd::Zero(params.size())),
        n_(static_cast<int>(model.axes.size())),
        r_(5),
        r_new_(5),
        J_(5, n_) {
    for (int a = 0; a < n_; ++a) {
      all_.push_back(a);
      if (!model.axes[a].isRotary()) prismatic_.push_back(a);
    }
  }

  // One point: the joints from q0 (where the machine is at p0, u0) that put the tip (and the axis
  // when `orientation`) on the target.
  void compensate(const ClPoint& target, const JointVector& q0, const Eigen::Vector3d& p0,
                  const Eigen::Vector3d& u0, bool orientation, CompensatedPoint& c) {
    target_ = &target;
    u_t_ = target.u_w.normalized();
    const Eigen::Vector3d t = e1_ - e1_.dot(u_t_) * u_t_;
    e1_ = t.norm() > 0.5 ? t.normalized() : u_t_.unitOrthogonal();
    e2_ = u_t_.cross(e1_);
    c.q0 = q0;
    JointVector q;
    Eigen::Vector3d p, u;
    c.before_w = p0 - target.p_w;
    c.before_axis = angleOf(u0, u_t_);
    double cond = 1;
    bool converged = solve(orientation, q0, p0, u0, q, p, u, &cond, &c.iterations);
    c.condition = cond;
    if (orientation && !converged && cond > opt_.max_condition) {
      // Near a singular pose: correcting the tool axis would swing a rotary axis. The axis is
      // left as programmed, the tip compensated by the linear joints.
      c.status = CompensationStatus::IllConditioned;
      double cond3 = 1;
      converged = solve(false, q0, p0, u0, q, p, u, &cond3, &c.iterations);
      if (!converged) c.status = CompensationStatus::NotConverged;
    } else {
      c.status = converged ? CompensationStatus::Compensated : CompensationStatus::NotConverged;
    }
    if (c.status != CompensationStatus::NotConverged) c.axis_out = axisOutOfTravel(q);
    if (c.axis_out >= 0) c.status = CompensationStatus::OutOfTravel;
    if (c.status == CompensationStatus::OutOfTravel ||
        c.status == CompensationStatus::NotConverged) {
      q = q0;
      fk_.tipAndAxis(q, &p, &u);
    }
    warm_ok_ = c.status == CompensationStatus::Compensated ||
               c.status == CompensationStatus::IllConditioned;
    warm_axis_ = orientation && c.status == CompensationStatus::Compensated;
    warm_q0_ = q0;
    warm_dq_ = q - q0;
    c.q = q;
    c.after_w = p - target.p_w;
    c.after_axis = angleOf(u, u_t_);
    nominal_.tipAndAxis(q, &c.nominal_p_w, &c.nominal_u_w);
  }

  const ForwardKinematics& fk() const { return fk_; }

 private:
  using Lu = Eigen::PartialPivLU<
      Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxRows, kMaxRows>>;

  // The first axis beyond its travel (endless axes excepted), -1 when none.
  int axisOutOfTravel(const JointVector& q) const {
    for (int a = 0; a < n_; ++a) {
      const Axis& ax = model_.axes[a];
      if (ax.endless) continue;
      const double slack = ax.isRotary() ? 1e-9 : 1e-7;
      if (q[a] < ax.travel_min - slack || q[a] > ax.travel_max + slack) return a;
    }
    return -1;
  }

  // Tip error (mm), and the axis across the target axis scaled to tip-like units.
  void toResidual(bool with_axis, const Eigen::Vector3d& pp, const Eigen::Vector3d& uu,
                  Residual& res) const {
    res.head<3>() = pp - target_->p_w;
    if (with_axis) {
      res[3] = kLever * e1_.dot(uu);
      res[4] = kLever * e2_.dot(uu);
    }
  }

  void freshJacobian(bool with_axis, const JointVector& at) {
    const std::vector<int>& vars = with_axis ? all_ : prismatic_;
    const int rows = with_axis ? 5 : 3, nv = static_cast<int>(vars.size());
    J_.resize(rows, nv);
    Residual r0(rows), rh(rows);
    Eigen::Vector3d pa, ua;
    fk_.tipAndAxis(at, &pa, &ua);
    toResidual(with_axis, pa, ua, r0);
    for (int k = 0; k < nv; ++k) {
      const double h = 1e-6;
      JointVector qh = at;
      qh[vars[k]] += h;
      Eigen::Vector3d ph, uh;
      fk_.tipAndAxis(qh, &ph, &uh);
      toResidual(with_axis, ph, uh, rh);
      J_.col(k) = (rh - r0) / h;
    }
    if (rows == nv) {
      lu_.compute(J_);
      J_cond_ = 1.0 / std::max(lu_.rcond(), 1e-300);
    } else {
      const Eigen::JacobiSVD<Jac> svd(J_);
      const auto sv = svd.singularValues();
      J_cond_ = sv[sv.size() - 1] > 0 ? sv[0] / sv[sv.size() - 1] : INFINITY;
    }
    have_J_ = true;
    J_axis_ = with_axis;
    J_q_ = at;
  }

  // Whether the kept Jacobian may serve a point: nearby joints.
  bool near(const JointVector& a, const JointVector& b) const {
    for (int k = 0; k < n_; ++k)
      if (std::abs(a[k] - b[k]) > (model_.axes[k].isRotary() ? 0.05 : 50.0)) return false;
    return true;
  }

  // Newton from q0 (warm-started) on the chosen joints and rows; returns whether it converged.
  bool solve(bool with_axis, const JointVector& q0, const Eigen::Vector3d& p0,
             const Eigen::Vector3d& u0, JointVector& q, Eigen::Vector3d& p, Eigen::Vector3d& u,
             double* cond, int* iterations) {
    const std::vector<int>& vars = with_axis ? all_ : prismatic_;
    const int rows = with_axis ? 5 : 3, nv = static_cast<int>(vars.size());
    r_.resize(rows);
    r_new_.resize(rows);
    q = q0;
    p = p0;
    u = u0;
    toResidual(with_axis, p, u, r_);
    if (warm_ok_ && warm_axis_ == with_axis && near(warm_q0_, q0)) {
      JointVector qs = q0 + warm_dq_;
      Eigen::Vector3d ps, us;
      Residual rs(rows);
      fk_.tipAndAxis(qs, &ps, &us);
      toResidual(with_axis, ps, us, rs);
      if (rs.norm() < r_.norm()) {
        q = qs;
        p = ps;
        u = us;
        r_ = rs;
      }
    }
    bool fresh = false;
    if (!(have_J_ && J_axis_ == with_axis && J_q_.size() == q.size() && near(J_q_, q))) {
      freshJacobian(with_axis, q);
      fresh = true;
    }
    *cond = J_cond_;
    for (int it = 0; it <= opt_.max_iterations; ++it) {
      // |u x u_t| is the angle to 1e-18 here (and u . u_t > 0: the axis is never reversed).
      const double ang_err = with_axis ? u.cross(u_t_).norm() : 0.0;
      if (r_.head<3>().norm() <= opt_.tolerance && ang_err <= opt_.angle_tolerance &&
          u.dot(u_t_) > 0)
        return true;
      if (it == opt_.max_iterations) return false;
      *iterations = it + 1;
      if (J_cond_ > opt_.max_condition) {
        if (fresh) return false;
        freshJacobian(with_axis,
                      q);  // the kept one may be the ill-conditioned one: look again here
        fresh = true;
        *cond = J_cond_;
        --it;
        continue;
      }
      Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxAxes, 1> dq;
      if (rows == nv)
        dq = lu_.solve(r_);
      else
        dq = J_.completeOrthogonalDecomposition().solve(r_);
      JointVector q_new = q;
      for (int k = 0; k < nv; ++k) q_new[vars[k]] -= dq[k];
      Eigen::Vector3d p_new, u_new;
      fk_.tipAndAxis(q_new, &p_new, &u_new);
      toResidual(with_axis, p_new, u_new, r_new_);
      if (r_new_.norm() > 0.1 * r_.norm() && !fresh) {
        // The kept Jacobian no longer converges fast: a fresh one where the step landed (or
        // here, when the step did not help).
        const bool better = r_new_.norm() < r_.norm();
        freshJacobian(with_axis, better ? q_new : q);
        fresh = true;
        *cond = J_cond_;
        if (!better) continue;
      }
      q = q_new;
      p = p_new;
      u = u_new;
      r_ = r_new_;
    }
    return false;
  }

  const MachineModel& model_;
  const CompensationOptions& opt_;
  const ForwardKinematics fk_, nominal_;
  const int n_;
  std::vector<int> all_, prismatic_;  // the joints Newton moves: all of them, or the linear ones
  // The point being compensated: its target and the basis across its axis.
  const ClPoint* target_ = nullptr;
  Eigen::Vector3d u_t_, e1_ = Eigen::Vector3d::Zero(), e2_;
  Residual r_, r_new_;
  // The kept Jacobian.
  Jac J_;
  Lu lu_;
  bool have_J_ = false, J_axis_ = false;
  JointVector J_q_;
  double J_cond_ = 1;
  // The previous point's correction, for a warm start.
  bool warm_ok_ = false, warm_axis_ = false;
  JointVector warm_q0_, warm_dq_;
};

}  // namespace

struct StreamCompensator::State {
  State(const MachineModel& model, const Eigen::VectorXd& params, const CompensationOptions& o)
      : opt(o), pc(model, params, opt) {}
  CompensationOptions opt;
  PathCompensator pc;
};

StreamCompensator::StreamCompensator(const MachineModel& model, const Eigen::VectorXd& params,
                                     const CompensationOptions& options)
    : state_(std::make_unique<State>(model, params, options)) {}

StreamCompensator::~StreamCompensator() = default;

CompensationResult StreamCompensator::compensate(const std::vector<ClPoint>& path,
                                                 const std::vector<JointVector>& q0,
                                                 bool orientation, const PredictedPoints* predicted,
                                                 const std::vector<char>* tip_only) {
  PathCompensator& pc = state_->pc;
  CompensationResult out;
  out.points.resize(path.size());
  for (size_t i = 0; i < path.size(); ++i) {
    Eigen::Vector3d p0, u0;  // the machine's pose at q0
    if (predicted) {
      p0 = (*predicted)[i].p_pred_w;
      u0 = (*predicted)[i].u_pred_w;
    } else {
      pc.fk().tipAndAxis(q0[i], &p0, &u0);
    }
    CompensatedPoint& c = out.points[i];
    const bool tip = tip_only && i < tip_only->size() && (*tip_only)[i];
    pc.compensate(path[i], q0[i], p0, u0, orientation && !tip, c);
    out.ill_conditioned += c.status == CompensationStatus::IllConditioned;
    out.out_of_travel += c.status == CompensationStatus::OutOfTravel;
    out.not_converged += c.status == CompensationStatus::NotConverged;
  }
  return out;
}

CompensationResult compensateToolPath(const MachineModel& model, const Eigen::VectorXd& params,
                                      const std::vector<ClPoint>& path,
                                      const std::vector<JointVector>& q0, bool orientation,
                                      const CompensationOptions& opt,
                                      const PredictedPoints* predicted) {
  StreamCompensator stream(model, params, opt);
  return stream.compensate(path, q0, orientation, predicted, opt.tip_only);
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
        d[k] = (c.q[prismatic[k]] - c.q0[prismatic[k]]) -
               (zero.q[prismatic[k]] - zero.q0[prismatic[k]]);
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
      for (size_t k = 0; k < tables[0].prismatic.size() && k < 3; ++k)
        qc[tables[0].prismatic[k]] += d[k];
    fk.tipAndAxis(qc, &p, &u);
    e.after_rms += (p - p_nom - d_ref).squaredNorm();
  }
  e.before_rms = std::sqrt(e.before_rms / samples);
  e.after_rms = std::sqrt(e.after_rms / samples);
  return e;
}

}  // namespace tolver
