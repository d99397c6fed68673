#include "core/path/tool_path_prediction.h"

#include "core/model/effects.h"

#include <array>
#include <cmath>
#include <cstdio>
#include <limits>

#include "core/kinematics/forward_kinematics.h"
#include "core/model/rigid_transform.h"
#include "core/numerics/units.h"

namespace tolver {

std::string describeIkFailure(const MachineModel& model, const IkSolution& sol) {
  char buf[256];
  switch (sol.status) {
    case IkStatus::Ok:
      return "ok";
    case IkStatus::UnreachableOrientation:
      return "tool axis cannot be reached by the rotary axes of this machine";
    case IkStatus::UnsupportedTopology:
      return "inverse kinematics needs three prismatic and at most two rotary axes";
    case IkStatus::OutOfTravel: {
      if (sol.violated_axis < 0 || sol.violated_axis >= static_cast<int>(model.axes.size()))
        return "the prismatic axes cannot place the tool tip (their directions are dependent)";
      const Axis& ax = model.axes[sol.violated_axis];
      const bool rot = ax.isRotary();
      const double k = rot ? radToDeg(1.0) : 1.0;
      const double over = sol.violated_value > ax.travel_max ? sol.violated_value - ax.travel_max
                                                             : ax.travel_min - sol.violated_value;
      std::snprintf(buf, sizeof buf,
                    "axis %s would need %.4f %s, %.4f %s beyond its travel [%.4f, %.4f]",
                    ax.name.c_str(), sol.violated_value * k, rot ? "deg" : "mm", over * k,
                    rot ? "deg" : "mm", ax.travel_min * k, ax.travel_max * k);
      return buf;
    }
  }
  return "unknown";
}

namespace {

// Angle between two unit vectors. Prediction errors are micro-radians, where atan's series of
// t = |u x v| / (u . v) is exact to rounding and several times cheaper than atan2.
double angleBetween(const Eigen::Vector3d& u, const Eigen::Vector3d& v) {
  const double sn = u.cross(v).norm(), cs = u.dot(v);
  if (cs > 0.0 && sn <= kAtanSeriesMax * cs) return atanOfSmall(sn / cs);
  return std::atan2(sn, cs);
}

}  // namespace

PredictionResult predictToolPath(const MachineModel& model, const Eigen::VectorXd& params,
                                 const std::vector<ClPoint>& path, int max_failures,
                                 const std::vector<JointVector>* commanded) {
  PredictionResult result;
  predictToolPath(model, params, path, result, max_failures, commanded);
  return result;
}

void predictToolPath(const MachineModel& model, const Eigen::VectorXd& params,
                     const std::vector<ClPoint>& path, PredictionResult& result, int max_failures,
                     const std::vector<JointVector>* commanded) {
  result.failures.clear();
  result.failed_points = 0;
  result.failures_per_axis.assign(model.axes.size() + 1, 0);
  if (commanded && commanded->size() != path.size()) commanded = nullptr;
  result.summary = PredictionSummary{};
  const InverseKinematics ik(model);
  const ForwardKinematics actual(model, params);
  result.points.resize(path.size());
  PredictionSummary& s = result.summary;
  s.points = static_cast<int>(path.size());
  double sum2 = 0.0, sum2_angle = 0.0;
  const JointVector* previous = nullptr;
  std::array<double, kMaxAxes> previous_cos, previous_sin;  // of previous's rotary values
  // Effects that depend on the approach direction (reversal) see it from the joint sequence;
  // time-dependent ones (thermal) see an unknown time and add nothing.
  MotionContext ctx;
  const MotionContext* ctx_ptr = model.effects.empty() ? nullptr : &ctx;
  for (size_t i = 0; i < path.size(); ++i) {
    const ClPoint& cl = path[i];
    const IkSolution sol =
        commanded ? ik.solve(cl.p_w, cl.u_w, &(*commanded)[i])
                  : ik.solve(cl.p_w, cl.u_w, previous, previous_cos.data(), previous_sin.data());
    if (sol.status != IkStatus::Ok) {
      PredictedPoint& bad = result.points[i];
      const double nan = std::numeric_limits<double>::quiet_NaN();
      bad.q = JointVector::Constant(sol.q.size(), nan);
      bad.p_pred_w = bad.u_pred_w = bad.deviation_w = Eigen::Vector3d::Constant(nan);
      bad.along_axis = bad.across_axis = bad.axis_angle = nan;
      bad.singular = false;
      const int axis = sol.status == IkStatus::OutOfTravel ? sol.violated_axis : -1;
      ++result.failed_points;
      ++result.failures_per_axis[axis >= 0 ? axis : model.axes.size()];
      if (static_cast<int>(result.failures.size()) < max_failures)
        result.failures.push_back(
            {static_cast<int>(i), cl.line, sol.status, axis, describeIkFailure(model, sol)});
      previous = nullptr;
      continue;
    }
    PredictedPoint& out = result.points[i];
    out.q = sol.q;
    out.singular = sol.singular;
    if (sol.singular) {
      if (s.singular_points == 0) s.first_singular_line = cl.line;
      ++s.singular_points;
    }
    if (ctx_ptr && previous) updateDirections(ctx, *previous, sol.q);
    actual.tipAndAxis(sol.q, &out.p_pred_w, &out.u_pred_w, sol.cos_q.data(), sol.sin_q.data(),
                      ctx_ptr);
    const Eigen::Vector3d u = cl.u_w.normalized();
    out.deviation_w = out.p_pred_w - cl.p_w;
    out.along_axis = out.deviation_w.dot(u);
    out.across_axis = (out.deviation_w - out.along_axis * u).norm();
    out.axis_angle = angleBetween(u, out.u_pred_w);
    const double d = out.deviation_w.norm();
    sum2 += d * d;
    sum2_angle += out.axis_angle * out.axis_angle;
    if (d > s.max_deviation || s.max_index < 0) {
      s.max_deviation = d;
      s.max_index = static_cast<int>(i);
    }
    if (out.axis_angle > s.max_axis_angle) s.max_axis_angle = out.axis_angle;
    previous = &out.q;
    previous_cos = sol.cos_q;
    previous_sin = sol.sin_q;
  }
  if (!path.empty()) {
    s.rms_deviation = std::sqrt(sum2 / path.size());
    s.rms_axis_angle = std::sqrt(sum2_angle / path.size());
  }
}

std::vector<RotaryJump> findRotaryJumps(const MachineModel& model, const std::vector<ClPoint>& path,
                                        const PredictionResult& result, double threshold) {
  std::vector<RotaryJump> jumps;
  for (size_t i = 1; i < path.size() && i < result.points.size(); ++i) {
    if (path[i].rapid || path[i - 1].rapid) continue;
    const JointVector& a = result.points[i - 1].q;
    const JointVector& b = result.points[i].q;
    for (int k = 0; k < static_cast<int>(model.axes.size()) && k < a.size() && k < b.size(); ++k) {
      if (!model.axes[k].isRotary()) continue;
      const double step = b[k] - a[k];
      if (std::isfinite(step) && std::abs(step) > threshold)
        jumps.push_back({static_cast<int>(i), path[i].line, k, step});
    }
  }
  return jumps;
}

}  // namespace tolver
