#include "core/path/tool_path_prediction.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>

#include "core/kinematics/forward_kinematics.h"
#include "core/model/effects.h"
#include "core/model/rigid_transform.h"
#include "core/numerics/lanes.h"
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

PredictedPoint PredictedPoints::operator[](size_t i) const {
  PredictedPoint p;
  p.q.resize(axes_);
  for (int a = 0; a < axes_; ++a) p.q[a] = q(a)[i];
  p.p_pred_w = Eigen::Vector3d(field(kTipX)[i], field(kTipY)[i], field(kTipZ)[i]);
  p.u_pred_w = Eigen::Vector3d(field(kAxisX)[i], field(kAxisY)[i], field(kAxisZ)[i]);
  p.deviation_w = Eigen::Vector3d(field(kDevX)[i], field(kDevY)[i], field(kDevZ)[i]);
  p.along_axis = field(kAlong)[i];
  p.across_axis = field(kAcross)[i];
  p.axis_angle = field(kAngle)[i];
  p.singular = singular_[i] != 0;
  return p;
}

void PredictedPoints::set(size_t i, const PredictedPoint& p) {
  for (int a = 0; a < axes_; ++a) q(a)[i] = p.q[a];
  for (int k = 0; k < 3; ++k) {
    field(kTipX + k)[i] = p.p_pred_w[k];
    field(kAxisX + k)[i] = p.u_pred_w[k];
    field(kDevX + k)[i] = p.deviation_w[k];
  }
  field(kAlong)[i] = p.along_axis;
  field(kAcross)[i] = p.across_axis;
  field(kAngle)[i] = p.axis_angle;
  singular_[i] = p.singular ? 1 : 0;
}

void PredictedPoints::setFailed(size_t i) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (int a = 0; a < axes_ + kFields; ++a) q(a)[i] = nan;
  singular_[i] = 0;
}

void PredictedPoints::copyFrom(const PredictedPoints& other, size_t from, size_t count, size_t to) {
  if (count == 0) return;
  for (int a = 0; a < axes_ + kFields; ++a)
    std::memcpy(q(a) + to, other.q(a) + from, count * sizeof(double));
  std::memcpy(singular_.data() + to, other.singular_.data() + from, count);
}

void PredictedPoints::resize(size_t n, int axes) {
  n_ = n;
  axes_ = axes;
  stride_ = (n + 63) / 64 * 64;
  numbers_.resize(stride_ * (axes + kFields));
  singular_.resize(stride_);
}

namespace {

// The deviation of a predicted point, over L = double or four lanes (core/numerics/lanes.h):
// p, u_raw the CL point and its tool axis (not necessarily unit), pp, up the predicted tip and
// unit axis. The axis angle: prediction errors are micro-radians, where atan's series of
// t = |u x v| / (u . v) is exact to rounding and several times cheaper than atan2; a lane
// beyond the series is flagged (and recomputed by the double form, which takes atan2).
struct Deviation {
  double dev[3], along, across, angle, norm;
};
template <typename L>
TOLVER_LANE_INLINE auto deviationL(const L p[3], const L u_raw[3], const L pp[3], const L up[3],
                                   L dev[3], L* along, L* across, L* angle, L* norm) {
  using lanes::select;
  using lanes::sqrtL;
  const L n2 = u_raw[0] * u_raw[0] + u_raw[1] * u_raw[1] + u_raw[2] * u_raw[2];
  const L root = sqrtL(n2);
  const auto positive = n2 > 0.0;
  L u[3];
  for (int k = 0; k < 3; ++k) u[k] = select(positive, u_raw[k] / root, u_raw[k]);
  for (int k = 0; k < 3; ++k) dev[k] = pp[k] - p[k];
  *along = dev[0] * u[0] + dev[1] * u[1] + dev[2] * u[2];
  L w[3];
  for (int k = 0; k < 3; ++k) w[k] = dev[k] - *along * u[k];
  *across = sqrtL(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
  const L x = u[1] * up[2] - u[2] * up[1], y = u[2] * up[0] - u[0] * up[2],
          z = u[0] * up[1] - u[1] * up[0];
  const L sn = sqrtL(x * x + y * y + z * z), cs = u[0] * up[0] + u[1] * up[1] + u[2] * up[2];
  const auto series = lanes::maskOf(cs > 0.0) & lanes::maskOf(sn <= kAtanSeriesMax * cs);
  *angle = atanOfSmallL(sn / cs);
  *norm = sqrtL(dev[0] * dev[0] + dev[1] * dev[1] + dev[2] * dev[2]);
  if constexpr (sizeof(L) == sizeof(double)) {
    if (!series) *angle = std::atan2(sn, cs);
    return false;
  } else {
    return !series;
  }
}

Deviation deviationOf(const Eigen::Vector3d& p_w, const Eigen::Vector3d& u_w,
                      const Eigen::Vector3d& p_pred, const Eigen::Vector3d& u_pred) {
  const double p[3] = {p_w[0], p_w[1], p_w[2]}, u[3] = {u_w[0], u_w[1], u_w[2]};
  const double pp[3] = {p_pred[0], p_pred[1], p_pred[2]}, up[3] = {u_pred[0], u_pred[1], u_pred[2]};
  Deviation d;
  deviationL(p, u, pp, up, d.dev, &d.along, &d.across, &d.angle, &d.norm);
  return d;
}

// deviationL over a block: in[0..3] the CL tips, axes, predicted tips and axes (3 arrays of n
// each), out the deviations (dev x, y, z, along, across, angle, norm: 7 arrays of n).
template <typename V>
TOLVER_LANE_INLINE void deviationLanesOf(int n, const double* const in[4][3],
                                         double* const out[7]) {
  auto one = [&](int i) {  // the double form: the tail, and lanes beyond the series
    double v[4][3], d[7];
    for (int a = 0; a < 4; ++a)
      for (int k = 0; k < 3; ++k) v[a][k] = in[a][k][i];
    deviationL(v[0], v[1], v[2], v[3], d, &d[3], &d[4], &d[5], &d[6]);
    for (int k = 0; k < 7; ++k) out[k][i] = d[k];
  };
  constexpr int width = lanes::widthOf<V>();
  int i = 0;
  for (; i + width <= n; i += width) {
    V v[4][3], d[7];
    for (int a = 0; a < 4; ++a)
      for (int k = 0; k < 3; ++k) v[a][k] = lanes::loadL<V>(in[a][k] + i);
    const auto redo = deviationL(v[0], v[1], v[2], v[3], d, &d[3], &d[4], &d[5], &d[6]);
    for (int k = 0; k < 7; ++k) lanes::storeL<V>(out[k] + i, d[k]);
    if (lanes::any(redo))
      for (int l = 0; l < width; ++l)
        if (lanes::lane(redo, l)) one(i + l);
  }
  for (; i < n; ++i) one(i);
}

TOLVER_LANE_CLONES
void deviationLanes4(int n, const double* const in[4][3], double* const out[7]) {
  deviationLanesOf<lanes::Lane4>(n, in, out);
}

#if TOLVER_HAS_WIDE_LANES
TOLVER_LANE_WIDE
void deviationLanes8(int n, const double* const in[4][3], double* const out[7]) {
  deviationLanesOf<lanes::Lane8>(n, in, out);
}
#endif

void deviationLanes(int n, const double* const in[4][3], double* const out[7]) {
#if TOLVER_HAS_WIDE_LANES
  if (lanes::wideLanes()) return deviationLanes8(n, in, out);
#endif
  deviationLanes4(n, in, out);
}

}  // namespace

// The bookkeeping of one block of kBlock points (failures and the summary's figures), kept per
// block so that blocks may be accounted in any order, on any thread, and merged in path order
// (mergeTallies): the sums are block sums added block after block, the same on every path.
struct BlockSums {  // (a value apart from the failures: the loop keeps it in registers)
  double sum2 = 0.0, sum2_angle = 0.0;
  double max_deviation = 0.0, max_axis_angle = 0.0;
  int max_index = -1, max_line = 0;
  int singular_points = 0, first_singular_line = 0;
  // Rapids (positioning, home moves) are counted apart: the headline figures are the cut's.
  int rapid_points = 0, rapid_max_index = -1, rapid_max_line = 0;
  double rapid_max_deviation = 0.0;
  TOLVER_LANE_INLINE void add(size_t i, const ClPoint& cl, bool singular, double d, double angle) {
    if (singular) {
      if (singular_points == 0) first_singular_line = cl.line;
      ++singular_points;
    }
    if (cl.rapid) {
      ++rapid_points;
      if (d > rapid_max_deviation || rapid_max_index < 0) {
        rapid_max_deviation = d;
        rapid_max_index = static_cast<int>(i);
        rapid_max_line = cl.line;
      }
      return;
    }
    sum2 += d * d;
    sum2_angle += angle * angle;
    if (d > max_deviation || max_index < 0) {
      max_deviation = d;
      max_index = static_cast<int>(i);
      max_line = cl.line;
    }
    if (angle > max_axis_angle) max_axis_angle = angle;
  }
};
struct BlockTally {
  BlockSums sums;
  int failed = 0;
  std::array<int, kMaxAxes + 1> failed_per_axis{};  // by axis; the last: no axis to blame
  struct Failure {
    int index, line;
    IkStatus status;
    int axis;
    double value;
  };
  std::vector<Failure> failures;  // the block's first max_failures
  void fail(size_t i, const ClPoint& cl, IkStatus status, int violated_axis, double violated_value,
            int max_failures, int axes) {
    const int axis = status == IkStatus::OutOfTravel ? violated_axis : -1;
    ++failed;
    ++failed_per_axis[axis >= 0 ? axis : axes];
    if (static_cast<int>(failures.size()) < max_failures)
      failures.push_back({static_cast<int>(i), cl.line, status, axis, violated_value});
  }
};

namespace {

// A block's tally folded into the tally of the blocks before it on the path (in path order):
// sums added, maxima kept, the first max_failures failures.
void foldTally(BlockTally& into, const BlockTally& t, int max_failures, int axes) {
  BlockSums& s = into.sums;
  const BlockSums& b = t.sums;
  s.sum2 += b.sum2;
  s.sum2_angle += b.sum2_angle;
  if (b.max_index >= 0 && (b.max_deviation > s.max_deviation || s.max_index < 0)) {
    s.max_deviation = b.max_deviation;
    s.max_index = b.max_index;
    s.max_line = b.max_line;
  }
  if (b.max_axis_angle > s.max_axis_angle) s.max_axis_angle = b.max_axis_angle;
  s.rapid_points += b.rapid_points;
  if (b.rapid_max_index >= 0 &&
      (b.rapid_max_deviation > s.rapid_max_deviation || s.rapid_max_index < 0)) {
    s.rapid_max_deviation = b.rapid_max_deviation;
    s.rapid_max_index = b.rapid_max_index;
    s.rapid_max_line = b.rapid_max_line;
  }
  if (b.singular_points > 0 && s.singular_points == 0)
    s.first_singular_line = b.first_singular_line;
  s.singular_points += b.singular_points;
  into.failed += t.failed;
  for (int a = 0; a <= axes; ++a) into.failed_per_axis[a] += t.failed_per_axis[a];
  for (const BlockTally::Failure& f : t.failures) {
    if (static_cast<int>(into.failures.size()) >= max_failures) break;
    into.failures.push_back(f);
  }
}

// The tally of a path's `points` points into the result's failures and summary.
void summarise(const MachineModel& model, const BlockTally& total, size_t points,
               PredictionResult& result) {
  const int axes = static_cast<int>(model.axes.size());
  PredictionSummary& s = result.summary;
  const BlockSums& b = total.sums;
  s = PredictionSummary{};
  s.points = static_cast<int>(points);
  s.max_deviation = b.max_deviation;
  s.max_index = b.max_index;
  s.max_line = b.max_line;
  s.max_axis_angle = b.max_axis_angle;
  s.rapid_points = b.rapid_points;
  s.rapid_max_deviation = b.rapid_max_deviation;
  s.rapid_max_index = b.rapid_max_index;
  s.rapid_max_line = b.rapid_max_line;
  s.singular_points = b.singular_points;
  s.first_singular_line = b.first_singular_line;
  result.failed_points = total.failed;
  result.failures_per_axis.assign(model.axes.size() + 1, 0);
  for (int a = 0; a <= axes; ++a) result.failures_per_axis[a] = total.failed_per_axis[a];
  result.failures.clear();
  for (const BlockTally::Failure& f : total.failures) {
    IkSolution sol;
    sol.status = f.status;
    sol.violated_axis = f.axis;
    sol.violated_value = f.value;
    result.failures.push_back({f.index, f.line, f.status, f.axis, describeIkFailure(model, sol)});
  }
  // Over the cutting points that were predicted (failed points and rapids apart).
  const long cutting = static_cast<long>(points) - result.failed_points - s.rapid_points;
  if (cutting <= 0) {  // nothing but rapids: their figures are the only ones
    s.max_deviation = s.rapid_max_deviation;
    s.max_index = s.rapid_max_index;
    s.max_line = s.rapid_max_line;
    return;
  }
  s.rms_deviation = std::sqrt(b.sum2 / static_cast<double>(cutting));
  s.rms_axis_angle = std::sqrt(b.sum2_angle / static_cast<double>(cutting));
}

}  // namespace

// Each array of a block starts on a cache line and spans whole lines (kBlock doubles), so a
// block's points are streamed into PredictedPoints array by array.
struct BlockPrediction::Work {
  size_t start = 0;
  InverseKinematics::Block ik;
  // predicted tip and axis; deviation, along, across, angle (PredictedPoints::Field's order
  // from kTipX), then the deviation's norm
  alignas(64) double pred[6][InverseKinematics::kBlock];
  alignas(64) double dev[7][InverseKinematics::kBlock];
};
static_assert(InverseKinematics::kBlock % 64 == 0);

struct PredictionCarry::State {
  size_t points = 0;                     // in the stretches before
  bool has_before = false;               // a point precedes the next stretch,
  double u_before[3] = {0.0, 0.0, 1.0};  // with this tool axis
  InverseKinematics::Cursor cursor;      // the choice's (the one-point path's previous point)
  MotionContext ctx;                     // direction-dependent effects' approach directions
  BlockTally total;                      // the whole path's so far
};

PredictionCarry::PredictionCarry() : s_(std::make_unique<State>()) {}
PredictionCarry::~PredictionCarry() = default;
PredictionCarry::PredictionCarry(PredictionCarry&&) noexcept = default;
PredictionCarry& PredictionCarry::operator=(PredictionCarry&&) noexcept = default;
PredictionCarry::PredictionCarry(const PredictionCarry& other)
    : s_(std::make_unique<State>(*other.s_)) {}
size_t PredictionCarry::points() const { return s_->points; }

struct BlockPrediction::State {
  State(const MachineModel& m, const Eigen::VectorXd& params, const std::vector<ClPoint>& p,
        PredictionResult& r, int most_failures, PredictionCarry* c)
      : model(m),
        path(p),
        ik(m),
        actual(m, params),
        result(r),
        max_failures(most_failures),
        carry(c),
        base(c ? c->points() : 0) {}
  const MachineModel& model;
  const std::vector<ClPoint>& path;
  const InverseKinematics ik;
  const ForwardKinematics actual;
  PredictionResult& result;
  int max_failures;
  PredictionCarry* carry;
  size_t base;                      // index of path[0] in the whole path
  std::vector<BlockTally> tallies;  // one per block
  InverseKinematics::Cursor cursor;
};

namespace {

// The stretch's tallies, in path order, into the result's failures and summary; with a carry,
// folded into the whole path's so far, which the carry keeps with the stretch's last tool axis.
void finishTallies(const MachineModel& model, const std::vector<BlockTally>& tallies,
                   const std::vector<ClPoint>& path, int max_failures, PredictionResult& result,
                   PredictionCarry* carry) {
  BlockTally local;
  BlockTally& total = carry ? carry->state().total : local;
  for (const BlockTally& t : tallies)
    foldTally(total, t, max_failures, static_cast<int>(model.axes.size()));
  const size_t points = (carry ? carry->points() : 0) + path.size();
  summarise(model, total, points, result);
  if (!carry) return;
  PredictionCarry::State& c = carry->state();
  c.points = points;
  if (path.empty()) return;
  c.has_before = true;
  for (int k = 0; k < 3; ++k) c.u_before[k] = path.back().u_w[k];
}

size_t blockCount(size_t points) {
  return (points + InverseKinematics::kBlock - 1) / InverseKinematics::kBlock;
}

void prepare(const MachineModel& model, const std::vector<ClPoint>& path, PredictionResult& result,
             std::vector<BlockTally>& tallies) {
  result.failures.clear();
  result.failed_points = 0;
  result.failures_per_axis.assign(model.axes.size() + 1, 0);
  result.summary = PredictionSummary{};
  result.points.resize(path.size(), static_cast<int>(model.axes.size()));
  result.summary.points = static_cast<int>(path.size());
  tallies.assign(blockCount(path.size()), BlockTally{});
}

}  // namespace

BlockPrediction::BlockPrediction(const MachineModel& model, const Eigen::VectorXd& params,
                                 const std::vector<ClPoint>& path, PredictionResult& result,
                                 int max_failures, PredictionCarry* carry)
    : s_(std::make_unique<State>(model, params, path, result, max_failures, carry)) {
  prepare(model, path, result, s_->tallies);
  if (carry) s_->cursor = carry->state().cursor;
}

BlockPrediction::~BlockPrediction() = default;

bool BlockPrediction::batchable() const { return s_->ik.batchable() && s_->actual.batchable(); }

size_t BlockPrediction::blocks() const { return blockCount(s_->path.size()); }

std::shared_ptr<BlockPrediction::Work> BlockPrediction::newWork() const {
  return std::make_shared<Work>();
}

void BlockPrediction::lanes(size_t block, Work& w, int hint) const {
  const std::vector<ClPoint>& path = s_->path;
  w.start = block * InverseKinematics::kBlock;
  InverseKinematics::Block& b = w.ik;
  b.n = static_cast<int>(std::min<size_t>(InverseKinematics::kBlock, path.size() - w.start));
  // The next block's CL points, towards the caches while this one is copied and solved (the
  // copy otherwise waits on each line).
  const size_t next = w.start + InverseKinematics::kBlock;
  if (next < path.size()) {
    const char* from = reinterpret_cast<const char*>(&path[next]);
    const size_t bytes =
        std::min<size_t>(InverseKinematics::kBlock, path.size() - next) * sizeof(ClPoint);
    for (size_t at = 0; at < bytes; at += 64) __builtin_prefetch(from + at);
  }
  for (int i = 0; i < b.n; ++i) {
    const ClPoint& cl = path[w.start + i];
    for (int k = 0; k < 3; ++k) {
      b.p[k][i] = cl.p_w[k];
      b.u[k][i] = cl.u_w[k];
    }
  }
  b.exact_first = (s_->base + w.start) % kExactEvery == 0;
  b.prism_only = hint;
  if (w.start > 0) {
    b.has_before = true;
    for (int k = 0; k < 3; ++k) b.u_before[k] = path[w.start - 1].u_w[k];
  } else {  // the stretch before's last point, if any
    const PredictionCarry::State* c = s_->carry ? &s_->carry->state() : nullptr;
    b.has_before = c && c->has_before;
    if (b.has_before)
      for (int k = 0; k < 3; ++k) b.u_before[k] = c->u_before[k];
  }
  s_->ik.blockLanes(b);
}

void BlockPrediction::predict(size_t block, Work& w, Cursor& cursor) const {
  lanes(block, w, cursor.previous_candidate);
  s_->ik.blockChoice(w.ik, cursor);
  forward(w);
  account(w);
}

BlockPrediction::Cursor& BlockPrediction::cursor() { return s_->cursor; }

bool BlockPrediction::sameCursor(const Cursor& a, const Cursor& b) const {
  if (a.has_previous != b.has_previous || a.previous_candidate != b.previous_candidate)
    return false;
  if (!a.has_previous) return true;  // (the rest is not read)
  if (a.previous.size() != b.previous.size() ||
      std::memcmp(a.previous.data(), b.previous.data(), a.previous.size() * sizeof(double)) != 0)
    return false;
  for (int r : s_->ik.rotaryAxes())
    if (std::memcmp(&a.previous_cos[r], &b.previous_cos[r], sizeof(double)) != 0 ||
        std::memcmp(&a.previous_sin[r], &b.previous_sin[r], sizeof(double)) != 0)
      return false;
  return true;
}

void BlockPrediction::forward(Work& w) const {
  InverseKinematics::Block& b = w.ik;
  const int n = b.n;
  const int axes = static_cast<int>(s_->model.axes.size());
  const double* q[kMaxAxes];
  const double* c[kMaxAxes];
  const double* s[kMaxAxes];
  for (int a = 0; a < axes; ++a) {
    q[a] = b.q[a];
    c[a] = b.c[a];
    s[a] = b.s[a];
  }
  double* const p_pred[3] = {w.pred[0], w.pred[1], w.pred[2]};
  double* const u_pred[3] = {w.pred[3], w.pred[4], w.pred[5]};
  s_->actual.tipAndAxisBatch(n, q, c, s, p_pred, u_pred);
  const double* const in[4][3] = {{b.p[0], b.p[1], b.p[2]},
                                  {b.u[0], b.u[1], b.u[2]},
                                  {w.pred[0], w.pred[1], w.pred[2]},
                                  {w.pred[3], w.pred[4], w.pred[5]}};
  double* const out[7] = {w.dev[0], w.dev[1], w.dev[2], w.dev[3], w.dev[4], w.dev[5], w.dev[6]};
  deviationLanes(n, in, out);
  // The block into the result, whole lines per array (past n within the block's arrays and
  // the result's rounded length); account then writes NaN over the points that failed.
  PredictedPoints& points = s_->result.points;
  const size_t bytes = static_cast<size_t>((n + 7) / 8 * 8) * sizeof(double);
  lanes::StreamCopy copies[kMaxAxes + PredictedPoints::kFields + 1];
  int m = 0;
  for (int a = 0; a < axes; ++a) copies[m++] = {points.q(a) + w.start, b.q[a], bytes};
  for (int k = 0; k < 6; ++k)
    copies[m++] = {points.field(PredictedPoints::kTipX + k) + w.start, w.pred[k], bytes};
  for (int k = 0; k < 6; ++k)
    copies[m++] = {points.field(PredictedPoints::kDevX + k) + w.start, w.dev[k], bytes};
  static_assert(sizeof(b.singular[0]) == 1 && InverseKinematics::kBlock == 64);
  copies[m++] = {points.singular() + w.start, b.singular, 64};
  lanes::streamLines(copies, m);
}

void BlockPrediction::account(Work& w) const {
  const InverseKinematics::Block& b = w.ik;
  const int axes = static_cast<int>(s_->model.axes.size());
  BlockTally& t = s_->tallies[w.start / InverseKinematics::kBlock];
  t = BlockTally{};
  BlockSums sums;
  for (int i = 0; i < b.n; ++i) {
    const size_t at = w.start + i;
    if (b.status[i] != IkStatus::Ok) {
      s_->result.points.setFailed(at);
      t.fail(s_->base + at, s_->path[at], b.status[i], b.violated_axis[i], b.violated_value[i],
             s_->max_failures, axes);
    } else {
      sums.add(s_->base + at, s_->path[at], b.singular[i], w.dev[6][i], w.dev[5][i]);
    }
  }
  t.sums = sums;
}

void BlockPrediction::finish() {
  if (s_->carry) s_->carry->state().cursor = s_->cursor;
  finishTallies(s_->model, s_->tallies, s_->path, s_->max_failures, s_->result, s_->carry);
}

namespace {

// A posted program's rotary solution is the program's: the control runs the rotary words it was
// given. When the inverse kinematics took the other solution (the commanded one puts a prismatic
// axis out of travel), the commanded one is kept if it is inside travel after all, and otherwise
// the point fails naming the axis the commanded solution breaks and the value it would need.
void keepCommanded(const InverseKinematics& ik, const ClPoint& cl, const JointVector& cmd,
                   IkSolution& sol) {
  bool replaced = false;
  for (int r : ik.rotaryAxes()) replaced = replaced || std::abs(sol.q[r] - cmd[r]) > 1e-6;
  if (!replaced) return;
  JointVector q = sol.q;
  for (int r : ik.rotaryAxes()) q[r] = cmd[r];
  int violated = -1;
  if (ik.placeToolPoint(Eigen::Vector3d::Zero(), cl.p_w, q, &violated)) {
    sol.q = q;
    for (int r : ik.rotaryAxes()) {
      sol.cos_q[r] = std::cos(q[r]);
      sol.sin_q[r] = std::sin(q[r]);
    }
    return;
  }
  sol.status = IkStatus::OutOfTravel;
  sol.violated_axis = violated;
  sol.violated_value = violated >= 0 ? q[violated] : 0.0;
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
  predictToolPath(model, params, path, result, max_failures, commanded, true);
}

void predictToolPath(const MachineModel& model, const Eigen::VectorXd& params,
                     const std::vector<ClPoint>& path, PredictionResult& result, int max_failures,
                     const std::vector<JointVector>* commanded, bool batch,
                     PredictionCarry* carry) {
  if (commanded && commanded->size() != path.size()) commanded = nullptr;
  if (batch && !commanded) {
    BlockPrediction bp(model, params, path, result, max_failures, carry);
    if (bp.batchable()) {
      const std::shared_ptr<BlockPrediction::Work> w = bp.newWork();
      for (size_t k = 0; k < bp.blocks(); ++k) bp.predict(k, *w, bp.cursor());
      bp.finish();
      return;
    }
  }
  std::vector<BlockTally> tallies;
  prepare(model, path, result, tallies);
  const size_t base = carry ? carry->points() : 0;
  const InverseKinematics ik(model);
  const ForwardKinematics actual(model, params);
  const int axes = static_cast<int>(model.axes.size());
  // The previous point (the cursor's previous values; the stretch before's last with a carry).
  InverseKinematics::Cursor own;
  InverseKinematics::Cursor& prev = carry ? carry->state().cursor : own;
  // Effects that depend on the approach direction (reversal) see it from the joint sequence;
  // time-dependent ones (thermal) see an unknown time and add nothing.
  MotionContext own_ctx;
  MotionContext& ctx = carry ? carry->state().ctx : own_ctx;
  MotionContext* ctx_ptr = model.effects.empty() ? nullptr : &ctx;
  PredictedPoint out;
  for (size_t i = 0; i < path.size(); ++i) {
    const ClPoint& cl = path[i];
    const JointVector* previous = prev.has_previous ? &prev.previous : nullptr;
    IkSolution sol = commanded ? ik.solve(cl.p_w, cl.u_w, &(*commanded)[i])
                               : ik.solve(cl.p_w, cl.u_w, previous, prev.previous_cos.data(),
                                          prev.previous_sin.data(),
                                          (base + i) % BlockPrediction::kExactEvery == 0);
    if (commanded && sol.status == IkStatus::Ok) keepCommanded(ik, cl, (*commanded)[i], sol);
    if (sol.status != IkStatus::Ok) {
      result.points.setFailed(i);
      tallies[i / InverseKinematics::kBlock].fail(base + i, cl, sol.status, sol.violated_axis,
                                                  sol.violated_value, max_failures, axes);
      prev.has_previous = false;
      continue;
    }
    out.q = sol.q;
    out.singular = sol.singular;
    if (ctx_ptr && previous) updateDirections(ctx, *previous, sol.q);
    actual.tipAndAxis(sol.q, &out.p_pred_w, &out.u_pred_w, sol.cos_q.data(), sol.sin_q.data(),
                      ctx_ptr);
    const Deviation d = deviationOf(cl.p_w, cl.u_w, out.p_pred_w, out.u_pred_w);
    out.deviation_w = Eigen::Vector3d(d.dev[0], d.dev[1], d.dev[2]);
    out.along_axis = d.along;
    out.across_axis = d.across;
    out.axis_angle = d.angle;
    result.points.set(i, out);
    tallies[i / InverseKinematics::kBlock].sums.add(base + i, cl, sol.singular, d.norm, d.angle);
    prev.has_previous = true;
    prev.previous = sol.q;
    prev.previous_cos = sol.cos_q;
    prev.previous_sin = sol.sin_q;
  }
  finishTallies(model, tallies, path, max_failures, result, carry);
}

std::vector<RotaryJump> findRotaryJumps(const MachineModel& model, const std::vector<ClPoint>& path,
                                        const PredictionResult& result, double threshold) {
  RotaryJumpFinder finder(model, threshold);
  finder.add(path, result.points, 0);
  return std::move(finder.jumps);
}

RotaryJumpFinder::RotaryJumpFinder(const MachineModel& model, double threshold)
    : model_(model), threshold_(threshold) {}

void RotaryJumpFinder::add(const std::vector<ClPoint>& path, const PredictedPoints& points,
                           size_t first_index) {
  const int axes = std::min(static_cast<int>(model_.axes.size()), points.axes());
  for (size_t i = 0; i < path.size() && i < points.size(); ++i) {
    if (has_previous_ && !path[i].rapid && !previous_rapid_)
      for (int k = 0; k < axes; ++k) {
        if (!model_.axes[k].isRotary()) continue;
        const double step = points.q(k)[i] - previous_q_[k];
        if (std::isfinite(step) && std::abs(step) > threshold_)
          jumps.push_back({static_cast<int>(first_index + i), path[i].line, k, step});
      }
    has_previous_ = true;
    previous_rapid_ = path[i].rapid;
    for (int k = 0; k < axes; ++k) previous_q_[k] = points.q(k)[i];
  }
}

}  // namespace tolver
