#include "core/path/tool_motion.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/model/effects.h"

namespace tolver {
namespace {

// Length of the path of the point `reach` up the axis, estimated by a two-chord polyline
// through the joint-space midpoint (the tip of a rotary move follows an arc).
double moveLength(const Eigen::Vector3d& p0, const Eigen::Vector3d& u0, const Eigen::Vector3d& pm,
                  const Eigen::Vector3d& um, const Eigen::Vector3d& p1, const Eigen::Vector3d& u1,
                  double reach) {
  const double tip = (pm - p0).norm() + (p1 - pm).norm();
  const Eigen::Vector3d r0 = p0 + reach * u0, rm = pm + reach * um, r1 = p1 + reach * u1;
  const double top = (rm - r0).norm() + (r1 - rm).norm();
  return std::max(tip, top);
}

}  // namespace

void samplePlacements(const ForwardKinematics& nominal, const ForwardKinematics& actual,
                      const std::vector<ClPoint>& path, const std::vector<JointVector>& q,
                      const MotionSampling& sampling, std::vector<ToolPlacement>* nominal_out,
                      std::vector<ToolPlacement>* actual_out) {
  samplePlacements(nominal, actual, path, q, q, sampling, nominal_out, actual_out);
}

namespace {

// CL points [first, last) of samplePlacements, appended; ctx (or null) carries the approach
// directions from point first - 1 on.
void sampleRange(const ForwardKinematics& nominal, const ForwardKinematics& actual,
                 const std::vector<ClPoint>& path, const std::vector<JointVector>& q,
                 const std::vector<JointVector>& qa, const MotionSampling& sampling, size_t first,
                 size_t last, MotionContext* ctx_ptr, std::vector<ToolPlacement>* nominal_out,
                 std::vector<ToolPlacement>* actual_out) {
  auto emit = [&](const JointVector& qk, const JointVector& qak, int index) {
    ToolPlacement a, b;
    nominal.tipAndAxis(qk, &a.tip_w, &a.axis_w);
    actual.tipAndAxis(qak, &b.tip_w, &b.axis_w, nullptr, nullptr, ctx_ptr);
    a.cl_index = b.cl_index = index;
    nominal_out->push_back(a);
    actual_out->push_back(b);
  };
  JointVector qm, qam;
  Eigen::Vector3d p0, u0, pm, um, p1, u1;
  for (size_t i = first; i < last; ++i) {
    if (i == 0 || path[i].rapid) {
      if (ctx_ptr && i > 0) updateDirections(*ctx_ptr, qa[i - 1], qa[i]);
      emit(q[i], qa[i], static_cast<int>(i));
      continue;
    }
    if (ctx_ptr) updateDirections(*ctx_ptr, qa[i - 1], qa[i]);
    nominal.tipAndAxis(q[i - 1], &p0, &u0);
    qm = 0.5 * (q[i - 1] + q[i]);
    nominal.tipAndAxis(qm, &pm, &um);
    nominal.tipAndAxis(q[i], &p1, &u1);
    const double len = moveLength(p0, u0, pm, um, p1, u1, sampling.reach);
    const int m =
        std::clamp(static_cast<int>(std::ceil(len / sampling.step)), 1, sampling.max_substeps);
    for (int k = 1; k <= m; ++k) {
      const double f = static_cast<double>(k) / m;
      qm = (1.0 - f) * q[i - 1] + f * q[i];
      qam = (1.0 - f) * qa[i - 1] + f * qa[i];
      emit(k == m ? q[i] : qm, k == m ? qa[i] : qam, static_cast<int>(i));
    }
  }
}

}  // namespace

void samplePlacements(const ForwardKinematics& nominal, const ForwardKinematics& actual,
                      const std::vector<ClPoint>& path, const std::vector<JointVector>& q,
                      const std::vector<JointVector>& qa, const MotionSampling& sampling,
                      std::vector<ToolPlacement>* nominal_out,
                      std::vector<ToolPlacement>* actual_out) {
  nominal_out->clear();
  actual_out->clear();
  const size_t n = std::min({path.size(), q.size(), qa.size()});
  // Direction-dependent effects (reversal) see the approach directions of the joint moves.
  MotionContext ctx;
  MotionContext* ctx_ptr = actual.model().effects.empty() ? nullptr : &ctx;
  sampleRange(nominal, actual, path, q, qa, sampling, 0, n, ctx_ptr, nominal_out, actual_out);
}

void samplePlacementsOf(const ForwardKinematics& nominal, const ForwardKinematics& actual,
                        const std::vector<ClPoint>& path, const std::vector<JointVector>& q,
                        const std::vector<JointVector>& qa, const MotionSampling& sampling,
                        size_t first, size_t last, std::vector<ToolPlacement>* nominal_out,
                        std::vector<ToolPlacement>* actual_out) {
  if (!actual.model().effects.empty())
    throw std::invalid_argument("samplePlacementsOf: a machine with effects is sampled whole");
  last = std::min({last, path.size(), q.size(), qa.size()});
  sampleRange(nominal, actual, path, q, qa, sampling, first, last, nullptr, nominal_out,
              actual_out);
}

std::vector<double> programTimes(const std::vector<ClPoint>& path, double rapid_mm_min) {
  std::vector<double> t(path.size(), 0.0);
  for (size_t i = 1; i < path.size(); ++i) {
    const double len = (path[i].p_w - path[i - 1].p_w).norm();
    const double feed = path[i].rapid ? rapid_mm_min : static_cast<double>(path[i].feed_mm_min);
    if (!(feed > 0)) {
      if (len > 0) return {};
      t[i] = t[i - 1];
      continue;
    }
    t[i] = t[i - 1] + len / feed;
  }
  return t;
}

}  // namespace tolver
