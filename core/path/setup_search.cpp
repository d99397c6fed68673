#include "core/path/setup_search.h"

#include <Eigen/LU>
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>

#include "core/kinematics/forward_kinematics.h"
#include "core/kinematics/inverse_kinematics.h"
#include "core/numerics/max_min_affine.h"
#include "core/numerics/units.h"

namespace tolver {
namespace {

// The model with prismatic travel unbounded: the inverse kinematics then always places the tip
// and only the rotary travel can fail.
MachineModel relaxed(const MachineModel& model) {
  MachineModel m = model;
  for (Axis& a : m.axes)
    if (!a.isRotary()) {
      a.travel_min = -1e9;
      a.travel_max = 1e9;
    }
  return m;
}

// Joints of every point for the model's set-up (relaxed model), NaN rows where the rotary
// axes cannot give the tool axis.
std::vector<JointVector> solveAll(const MachineModel& relaxed_model,
                                  const std::vector<ClPoint>& path,
                                  const std::vector<JointVector>* commanded,
                                  const std::vector<int>& subset) {
  const InverseKinematics ik(relaxed_model);
  std::vector<JointVector> q(subset.size());
  const JointVector* previous = nullptr;
  for (size_t k = 0; k < subset.size(); ++k) {
    const int i = subset[k];
    const JointVector* ref = commanded ? &(*commanded)[i] : previous;
    const IkSolution s = ik.solve(path[i].p_w, path[i].u_w, ref);
    if (s.status == IkStatus::Ok) {
      q[k] = s.q;
      previous = &q[k];
    } else {
      q[k] = JointVector::Constant(relaxed_model.axes.size(),
                                   std::numeric_limits<double>::quiet_NaN());
      previous = nullptr;
    }
  }
  return q;
}

std::vector<int> subsetOf(size_t n, int max_points) {
  std::vector<int> s;
  const size_t step = std::max<size_t>(1, (n + max_points - 1) / std::max(1, max_points));
  for (size_t i = 0; i < n; i += step) s.push_back(static_cast<int>(i));
  if (!s.empty() && s.back() != static_cast<int>(n) - 1) s.push_back(static_cast<int>(n) - 1);
  return s;
}

// Nelder-Mead maximisation of f over R^3.
template <class F>
Eigen::Vector3d maximise(const F& f, const Eigen::Vector3d& start, double size, double* best) {
  std::array<Eigen::Vector3d, 4> x;
  std::array<double, 4> v;
  x[0] = start;
  for (int k = 0; k < 3; ++k) {
    x[k + 1] = start;
    x[k + 1][k] += size;
  }
  for (int k = 0; k < 4; ++k) v[k] = f(x[k]);
  for (int it = 0; it < 600; ++it) {
    std::array<int, 4> o = {0, 1, 2, 3};
    std::sort(o.begin(), o.end(), [&](int a, int b) { return v[a] > v[b]; });
    if (std::abs(v[o[0]] - v[o[3]]) < 1e-7 && (x[o[0]] - x[o[3]]).norm() < 1e-6) break;
    const Eigen::Vector3d c = (x[o[0]] + x[o[1]] + x[o[2]]) / 3.0;
    const int w = o[3];
    const Eigen::Vector3d r = c + (c - x[w]);
    const double fr = f(r);
    if (fr > v[o[0]]) {
      const Eigen::Vector3d e = c + 2.0 * (c - x[w]);
      const double fe = f(e);
      if (fe > fr)
        x[w] = e, v[w] = fe;
      else
        x[w] = r, v[w] = fr;
    } else if (fr > v[o[2]]) {
      x[w] = r, v[w] = fr;
    } else {
      const Eigen::Vector3d k = c + 0.5 * (x[w] - c);
      const double fk = f(k);
      if (fk > v[w]) {
        x[w] = k, v[w] = fk;
      } else {
        for (int j = 1; j < 4; ++j) {
          x[o[j]] = x[o[0]] + 0.5 * (x[o[j]] - x[o[0]]);
          v[o[j]] = f(x[o[j]]);
        }
      }
    }
  }
  int b = 0;
  for (int k = 1; k < 4; ++k)
    if (v[k] > v[b]) b = k;
  *best = v[b];
  return x[b];
}

}  // namespace

std::vector<AxisRange> jointRanges(const MachineModel& model, const std::vector<ClPoint>& path,
                                   const std::vector<JointVector>* commanded, int* failed,
                                   int* first_failed_index) {
  const MachineModel m = relaxed(model);
  std::vector<int> all(path.size());
  for (size_t i = 0; i < path.size(); ++i) all[i] = static_cast<int>(i);
  const std::vector<JointVector> q = solveAll(m, path, commanded, all);
  std::vector<AxisRange> r(model.axes.size());
  *failed = 0;
  *first_failed_index = -1;
  for (size_t i = 0; i < q.size(); ++i) {
    if (q[i].size() == 0 || std::isnan(q[i][0])) {
      if ((*failed)++ == 0) *first_failed_index = static_cast<int>(i);
      continue;
    }
    for (size_t a = 0; a < r.size(); ++a) {
      AxisRange& x = r[a];
      if (!x.known || q[i][a] < x.min) x.min = q[i][a], x.min_index = static_cast<int>(i);
      if (!x.known || q[i][a] > x.max) x.max = q[i][a], x.max_index = static_cast<int>(i);
      x.known = true;
    }
  }
  return r;
}

// The part zero with the largest travel margin at one part rotation and gauge length. For
// fixed rotary angles each point's prismatic joints are affine in the part zero x: q = a + B (x
// - x0), one affine map per orientation solution of the point (the one the path's continuity
// takes and, for CL data, the other, which the inverse kinematics falls back to when the first
// leaves travel).
class ZeroSearch {
 public:
  ZeroSearch(const MachineModel& model, const std::vector<ClPoint>& path,
             const std::vector<JointVector>* commanded, const std::vector<int>& subset,
             const std::vector<int>& prismatic, double rot, double L)
      : model_(model), prismatic_(prismatic), x0(model.setup.part_zero_table) {
    MachineModel m = relaxed(model);
    m.setup.part_rotation = rot;
    m.setup.gauge_length = L;
    m.setup.part_zero_table = x0;
    const std::vector<JointVector> q0 = solveAll(m, path, commanded, subset);
    for (const JointVector& q : q0)
      if (std::isnan(q[0])) return;  // the rotary travel cannot give every point's tool axis
    // Each point's orientation solutions (the one the path's continuity takes and, for CL
    // data, the other, which the inverse kinematics falls back to when the first leaves
    // travel), and for each its affine prismatic joints: a at x0 and B by unit steps with
    // the rotaries kept.
    const InverseKinematics base(m);
    first.assign(q0.size() + 1, 0);
    for (size_t i = 0; i < q0.size(); ++i) {
      first[i] = static_cast<int>(cand.size());
      cand.push_back({q0[i], Eigen::Vector3d::Zero(), Eigen::Matrix3d::Zero()});
      if (commanded) continue;  // a posted program's rotary words are given
      InverseKinematics::RotaryCandidate rc[2];
      bool singular = false;
      const int nc = base.rotaryCandidates(path[subset[i]].u_w, rc, &singular);
      for (int c = 0; c < nc && !singular; ++c) {
        JointVector ref = q0[i];
        for (size_t r = 0; r < base.rotaryAxes().size(); ++r)
          ref[base.rotaryAxes()[r]] = rc[c].angleOf(static_cast<int>(r));
        const IkSolution s = base.solve(path[subset[i]].p_w, path[subset[i]].u_w, &ref);
        if (s.status != IkStatus::Ok) continue;
        bool same = true;
        for (int r : base.rotaryAxes()) same = same && std::abs(s.q[r] - q0[i][r]) < 1e-9;
        if (!same) {
          cand.push_back({s.q, Eigen::Vector3d::Zero(), Eigen::Matrix3d::Zero()});
          break;
        }
      }
    }
    first[q0.size()] = static_cast<int>(cand.size());
    n = q0.size();
    for (Affine& c : cand)
      for (int j = 0; j < 3; ++j) c.a[j] = c.ref[prismatic_[j]];
    for (int k = 0; k < 3; ++k) {
      MachineModel mk = m;
      mk.setup.part_zero_table = x0 + Eigen::Vector3d::Unit(k);
      const InverseKinematics ik(mk);
      for (size_t i = 0; i < n; ++i)
        for (int c = first[i]; c < first[i + 1]; ++c) {
          const IkSolution s = ik.solve(path[subset[i]].p_w, path[subset[i]].u_w, &cand[c].ref);
          for (int j = 0; j < 3; ++j)
            cand[c].B(j, k) =
                (s.status == IkStatus::Ok ? s.q[prismatic_[j]] : cand[c].a[j]) - cand[c].a[j];
        }
    }
    feasible_ = true;
  }

  // The largest margin (part zero in *x_best); -inf when the rotary travel cannot give every
  // point's tool axis at this rotation.
  double best(Eigen::Vector3d* x_best) const {
    if (!feasible_) return -std::numeric_limits<double>::infinity();
    std::vector<int> continuity(n);
    for (size_t i = 0; i < n; ++i) continuity[i] = first[i];
    Eigen::Vector3d x = x0;
    double best1 = exactFrom(continuity, &x);
    if (!std::isfinite(best1)) {
      best1 = margin(x0);
      x = x0;
    }
    // Nelder-Mead on the margin with every solution allowed finds other choices; it stalls at
    // the kinks of a piecewise-linear function, so it restarts from the best point with
    // shrinking simplices, and the exact step then polishes the choice it ends on.
    // One solution per point (a three-axis machine, a posted program's rotary words): the
    // margin is concave and the linear programme's optimum is the maximum; nothing to search.
    bool single = true;
    for (size_t i = 0; i < n && single; ++i) single = first[i + 1] - first[i] == 1;
    if (single && std::isfinite(best1)) {
      *x_best = x;
      return best1;
    }
    Eigen::Vector3d y_best = x;
    double v_best = best1;
    // The search runs on the points that bind (an active set: the smallest margins where it
    // starts), each result checked on every point and the points that bind there added, until
    // none is missing: the value it returns is always the margin over all points.
    std::vector<int> active = smallestMargins(x, kActive);
    for (int round = 0; round < 6; ++round) {
      Eigen::Vector3d y_round = y_best;
      double v_round = -std::numeric_limits<double>::infinity();
      for (double size : {200.0, 50.0, 100.0, 10.0, 30.0, 2.0, 0.5}) {
        double v = 0.0;
        const Eigen::Vector3d y =
            maximise([this, &active](const Eigen::Vector3d& p) { return marginOn(p, active); },
                     y_round, size, &v);
        if (v > v_round) v_round = v, y_round = y;
      }
      const double v_all = margin(y_round);
      if (v_all > v_best) v_best = v_all, y_best = y_round;
      if (v_all >= v_round - 1e-9 || active.size() >= n) break;
      // Points outside the set bind at the result: add the smallest.
      std::vector<char> in(n, 0);
      for (int i : active) in[i] = 1;
      for (int i : smallestMargins(y_round, kActive))
        if (!in[i]) active.push_back(i);
    }
    if (v_best > best1) {
      std::vector<int> choice(n);
      const Eigen::Vector3d d = y_best - x0;
      for (size_t i = 0; i < n; ++i) {
        choice[i] = first[i];
        for (int k = first[i]; k < first[i + 1]; ++k)
          if (candMargin(k, d) > candMargin(choice[i], d)) choice[i] = k;
      }
      Eigen::Vector3d z = y_best;
      const double vz = exactFrom(choice, &z);
      if (vz > v_best) v_best = vz, y_best = z;
      best1 = v_best;
      x = y_best;
    }
    *x_best = x;
    return best1;
  }

 private:
  struct Affine {
    JointVector ref;
    Eigen::Vector3d a;
    Eigen::Matrix3d B;
  };

  double candMargin(int c, const Eigen::Vector3d& d) const {
    const Eigen::Vector3d q = cand[c].a + cand[c].B * d;
    double tc = std::numeric_limits<double>::infinity();
    for (int j = 0; j < 3; ++j) {
      const Axis& ax = model_.axes[prismatic_[j]];
      tc = std::min(tc, std::min(q[j] - ax.travel_min, ax.travel_max - q[j]));
    }
    return tc;
  }

  static constexpr size_t kActive = 256;

  double pointMargin(size_t i, const Eigen::Vector3d& d) const {
    double best_c = -std::numeric_limits<double>::infinity();
    for (int c = first[i]; c < first[i + 1]; ++c) best_c = std::max(best_c, candMargin(c, d));
    return best_c;
  }

  double marginOn(const Eigen::Vector3d& x, const std::vector<int>& points) const {
    double t = std::numeric_limits<double>::infinity();
    const Eigen::Vector3d d = x - x0;
    for (int i : points) t = std::min(t, pointMargin(i, d));
    return t;
  }

  // The k points with the smallest margin at x.
  std::vector<int> smallestMargins(const Eigen::Vector3d& x, size_t k) const {
    std::vector<std::pair<double, int>> m(n);
    const Eigen::Vector3d d = x - x0;
    for (size_t i = 0; i < n; ++i) m[i] = {pointMargin(i, d), static_cast<int>(i)};
    k = std::min(k, n);
    std::partial_sort(m.begin(), m.begin() + k, m.end());
    std::vector<int> out(k);
    for (size_t j = 0; j < k; ++j) out[j] = m[j].second;
    return out;
  }

  // The margin of a part zero: over the points, the best of their solutions' margins.
  double margin(const Eigen::Vector3d& x) const {
    double t = std::numeric_limits<double>::infinity();
    const Eigen::Vector3d d = x - x0;
    for (size_t i = 0; i < n; ++i) {
      double best_c = -std::numeric_limits<double>::infinity();
      for (int c = first[i]; c < first[i + 1]; ++c) best_c = std::max(best_c, candMargin(c, d));
      t = std::min(t, best_c);
    }
    return t;
  }

  // With one solution chosen per point the margin is concave and piecewise linear: its maximum
  // is a linear programme, solved exactly. The choice is then revised to each point's best
  // solution at that optimum, until it no longer changes (the margin never decreases from one
  // round to the next).
  double exactFrom(std::vector<int> choice, Eigen::Vector3d* x_out) const {
    double best = -std::numeric_limits<double>::infinity();
    Eigen::MatrixXd g(6 * n, 3);
    Eigen::VectorXd c(6 * n);
    for (int round = 0; round < 10; ++round) {
      for (size_t i = 0; i < n; ++i) {
        const Affine& a = cand[choice[i]];
        for (int j = 0; j < 3; ++j) {
          const Axis& ax = model_.axes[prismatic_[j]];
          const size_t r = 6 * i + 2 * j;
          g.row(r) = a.B.row(j);
          c[r] = a.a[j] - ax.travel_min;
          g.row(r + 1) = -a.B.row(j);
          c[r + 1] = ax.travel_max - a.a[j];
        }
      }
      // Rows with the same gradient (points the part zero moves alike: all of a three-axis
      // program's) bind only at their smallest constant: one row each.
      const auto [gu, cu] = uniqueRows(g, c);
      const MaxMinResult lp = maximiseMinOfAffine(gu, cu);
      if (lp.status != MaxMinStatus::Optimal) break;
      const Eigen::Vector3d d = lp.x;
      const double v = margin(x0 + d);
      if (v > best) {
        best = v;
        *x_out = x0 + d;
      }
      bool changed = false;
      for (size_t i = 0; i < n; ++i) {
        int bc = choice[i];
        for (int k = first[i]; k < first[i + 1]; ++k)
          if (candMargin(k, d) > candMargin(bc, d) + 1e-9) bc = k;
        changed = changed || bc != choice[i];
        choice[i] = bc;
      }
      if (!changed) break;
    }
    return best;
  }

  static std::pair<Eigen::MatrixXd, Eigen::VectorXd> uniqueRows(const Eigen::MatrixXd& g,
                                                                const Eigen::VectorXd& c) {
    std::map<std::array<double, 3>, double> rows;
    for (Eigen::Index r = 0; r < g.rows(); ++r) {
      const std::array<double, 3> key = {g(r, 0), g(r, 1), g(r, 2)};
      auto [it, inserted] = rows.emplace(key, c[r]);
      if (!inserted) it->second = std::min(it->second, c[r]);
    }
    Eigen::MatrixXd gu(rows.size(), 3);
    Eigen::VectorXd cu(rows.size());
    Eigen::Index r = 0;
    for (const auto& [key, value] : rows) {
      gu.row(r) << key[0], key[1], key[2];
      cu[r++] = value;
    }
    return {gu, cu};
  }

  const MachineModel& model_;
  const std::vector<int>& prismatic_;
  const Eigen::Vector3d x0;
  bool feasible_ = false;
  size_t n = 0;
  std::vector<Affine> cand;
  std::vector<int> first;
};

SetupSearchResult findSetup(const MachineModel& model, const std::vector<ClPoint>& path,
                            const std::vector<JointVector>* commanded,
                            const SetupSearchOptions& options) {
  SetupSearchResult out;
  out.setup = model.setup;
  out.margin = -std::numeric_limits<double>::infinity();
  const std::vector<int> subset = subsetOf(path.size(), options.max_points);
  std::vector<int> prismatic;
  for (size_t a = 0; a < model.axes.size(); ++a)
    if (!model.axes[a].isRotary()) prismatic.push_back(static_cast<int>(a));
  std::vector<double> rotations;
  if (options.rotation_step <= 0.0)
    rotations.push_back(model.setup.part_rotation);
  else
    for (double r = 0.0; r < 2.0 * kPi - 1e-9; r += options.rotation_step) rotations.push_back(r);
  std::vector<double> gauges = options.gauge_lengths;
  if (gauges.empty()) gauges.push_back(model.setup.gauge_length);

  auto consider = [&](double rot, double L) {
    Eigen::Vector3d x;
    const double v = ZeroSearch(model, path, commanded, subset, prismatic, rot, L).best(&x);
    if (v > out.margin) {
      out.margin = v;
      out.setup.part_zero_table = x;
      out.setup.part_rotation = rot;
      out.setup.gauge_length = L;
    }
    return v;
  };
  // The time budget: once spent (after one rotation at least), the best of those tried.
  const auto start = std::chrono::steady_clock::now();
  auto spent = [&] {
    if (!(options.max_seconds > 0.0) || out.rotations_tried == 0) return false;
    const std::chrono::duration<double> t = std::chrono::steady_clock::now() - start;
    if (t.count() > options.max_seconds) out.budget_spent = true;
    return out.budget_spent;
  };
  std::vector<std::pair<double, double>> coarse;  // margin, rotation
  const double total =
      static_cast<double>(rotations.size()) * (options.rotation_step > 0 ? 2.0 : 1.0);
  for (double rot : rotations) {
    if (options.stop_when_found && out.margin >= 0.0) break;
    if (spent()) break;
    if (options.progress) options.progress(out.rotations_tried / total);
    ++out.rotations_tried;
    double v = -std::numeric_limits<double>::infinity();
    for (double L : gauges) v = std::max(v, consider(rot, L));
    if (!std::isfinite(v))
      ++out.rotations_rejected;
    else
      coarse.push_back({v, rot});
  }
  // The margin changes with the rotation between the candidates: refine around the three best
  // by halving steps down to a tenth of a degree.
  if (options.rotation_step > 0.0) {
    std::sort(coarse.begin(), coarse.end(),
              [](const auto& a, const auto& b) { return a.first > b.first; });
    if (coarse.size() > 3) coarse.resize(3);
    int refined = 0;
    for (const auto& [v0, rot0] : coarse) {
      if (options.progress)
        options.progress(0.5 +
                         0.5 * refined++ / static_cast<double>(std::max<size_t>(1, coarse.size())));
      double rot = rot0, v = v0;
      for (double h = options.rotation_step / 2.0;
           h > degToRad(0.1) && !(options.stop_when_found && out.margin >= 0.0) && !spent();
           h /= 2.0)
        for (double r : {rot - h, rot + h}) {
          double vr = -std::numeric_limits<double>::infinity();
          const double rr = std::fmod(r + 2.0 * kPi, 2.0 * kPi);
          for (double L : gauges) vr = std::max(vr, consider(rr, L));
          if (vr > v) v = vr, rot = rr;
        }
    }
  }
  // The best set-up on every point.
  MachineModel best = model;
  best.setup.part_zero_table = out.setup.part_zero_table;
  best.setup.part_rotation = out.setup.part_rotation;
  best.setup.gauge_length = out.setup.gauge_length;
  int failed = 0, first = -1;
  out.ranges = jointRanges(best, path, commanded, &failed, &first);
  const InverseKinematics ik(best);
  const JointVector* previous = nullptr;
  JointVector prev;
  for (size_t i = 0; i < path.size(); ++i) {
    const JointVector* ref = commanded ? &(*commanded)[i] : previous;
    const IkSolution s = ik.solve(path[i].p_w, path[i].u_w, ref);
    if (s.status != IkStatus::Ok) {
      out.outside.push_back(static_cast<int>(i));
      previous = nullptr;
    } else {
      prev = s.q;
      previous = &prev;
    }
  }
  out.found = std::isfinite(out.margin) && out.outside.empty();
  return out;
}

std::vector<SetupPiece> splitIntoSetups(const MachineModel& model, const std::vector<ClPoint>& path,
                                        const std::vector<JointVector>* commanded,
                                        const SetupSearchOptions& options, int max_pieces,
                                        bool* budget_spent) {
  const auto start = std::chrono::steady_clock::now();
  bool spent = false;
  // What is left of the budget for the next search (0: none given); spent once it is gone.
  auto left = [&] {
    if (!(options.max_seconds > 0.0)) return 0.0;
    const std::chrono::duration<double> t = std::chrono::steady_clock::now() - start;
    const double l = options.max_seconds - t.count();
    if (l <= 0.0) spent = true;
    return l;
  };
  SetupSearchOptions quick = options;
  quick.stop_when_found = true;
  quick.progress = nullptr;
  // Whether one set-up reaches path[first, end); a search cut short by the budget counts as
  // neither (spent is set and the split stops).
  auto reach = [&](int first, int end, SetupSearchResult* r) {
    quick.max_seconds = left();
    if (spent) return false;
    const std::vector<ClPoint> piece(path.begin() + first, path.begin() + end);
    std::vector<JointVector> cmd;
    if (commanded) cmd.assign(commanded->begin() + first, commanded->begin() + end);
    *r = findSetup(model, piece, commanded ? &cmd : nullptr, quick);
    if (r->budget_spent && !r->found) spent = true;
    return r->found;
  };
  std::vector<SetupPiece> pieces;
  const int n = static_cast<int>(path.size());
  int first = 0;
  while (first < n && static_cast<int>(pieces.size()) < max_pieces && !spent) {
    if (options.progress) options.progress(static_cast<double>(first) / n);
    SetupPiece p;
    p.first = first;
    // Galloping from one point, then bisection: [first, lo) is reachable, [first, hi) not (hi
    // = n + 1: the rest is reachable). A piece is found in searches of its own length or twice
    // it, not of the whole rest: a program mostly outside travel, cut into short pieces, took
    // minutes when every piece began with a search of the rest and bisected from its middle.
    int lo = first, hi = n + 1;
    SetupSearchResult r;
    for (int len = 1; !spent; len *= 2) {
      const int end = std::min(first + len, n);
      if (!reach(first, end, &r)) {
        hi = end;
        break;
      }
      lo = end;
      p.result = r;
      if (end == n) break;
    }
    if (lo == first) {
      p.last = first;  // a point no set-up reaches on its own
      p.result = r;
    } else {
      while (!spent && hi - lo > 1) {
        const int mid = lo + (hi - lo) / 2;
        if (reach(first, mid, &r)) {
          lo = mid;
          p.result = r;
        } else {
          hi = mid;
        }
      }
      p.last = lo - 1;
    }
    if (spent) break;  // the piece is not known to be the longest: not given
    // The piece's set-up with the margin of the full search (not the first that reached); if
    // the budget runs out in it, the best of the rotations tried, which still reaches the piece.
    if (p.result.found) {
      std::vector<ClPoint> piece(path.begin() + p.first, path.begin() + p.last + 1);
      std::vector<JointVector> cmd;
      if (commanded) cmd.assign(commanded->begin() + p.first, commanded->begin() + p.last + 1);
      SetupSearchOptions full = options;
      full.progress = nullptr;
      full.max_seconds = left();
      if (!spent) {
        SetupSearchResult best = findSetup(model, piece, commanded ? &cmd : nullptr, full);
        if (best.found && best.margin >= p.result.margin) p.result = std::move(best);
      }
    }
    first = p.last + 1;
    pieces.push_back(std::move(p));
  }
  if (budget_spent) *budget_spent = spent;
  return pieces;
}

namespace {

// What the G-code reader derives from the model (io/program/gcode_reader.cpp,
// prepareMachineCoordinates): the gauge point at joints zero g0_w, and G_m, the prismatic
// joints' effect on the tip times nc_sign, both seen from w.
struct MachineFrame {
  Eigen::Vector3d g0 = Eigen::Vector3d::Zero();
  Eigen::Matrix3d Gm = Eigen::Matrix3d::Identity();
  std::array<int, 3> prismatic{};
  bool ok = false;
};

MachineFrame machineFrame(const MachineModel& model) {
  MachineFrame f;
  const ForwardKinematics fk(model, Eigen::VectorXd::Zero(model.parameterCount()));
  const JointVector q0 = JointVector::Zero(static_cast<int>(model.axes.size()));
  Eigen::Vector3d tip0, axis0;
  fk.tipAndAxis(q0, &tip0, &axis0);
  f.g0 = tip0 + model.setup.gauge_length * axis0;
  f.prismatic = prismaticWordOrder(model);
  if (f.prismatic[0] < 0) return f;
  for (int col = 0; col < 3; ++col) {
    JointVector q = q0;
    q[f.prismatic[col]] = 1.0;
    Eigen::Vector3d tip, axis;
    fk.tipAndAxis(q, &tip, &axis);
    f.Gm.col(col) = (tip - tip0) * model.axes[f.prismatic[col]].nc_sign;
  }
  f.ok = std::abs(f.Gm.determinant()) > 1e-9;
  return f;
}

}  // namespace

std::vector<AxisRange> commandedJointRanges(const MachineModel& model,
                                            const std::vector<JointVector>& joints, double* margin,
                                            int* limiting_axis) {
  std::vector<AxisRange> ranges(model.axes.size());
  for (size_t i = 0; i < joints.size(); ++i)
    for (size_t a = 0; a < model.axes.size(); ++a) {
      AxisRange& r = ranges[a];
      const double q = joints[i][static_cast<int>(a)];
      if (!r.known || q < r.min) r.min = q, r.min_index = static_cast<int>(i);
      if (!r.known || q > r.max) r.max = q, r.max_index = static_cast<int>(i);
      r.known = true;
    }
  *margin = std::numeric_limits<double>::infinity();
  *limiting_axis = -1;
  for (size_t a = 0; a < model.axes.size(); ++a) {
    const Axis& ax = model.axes[a];
    if (ax.endless || !ranges[a].known) continue;
    double m = std::min(ranges[a].min - ax.travel_min, ax.travel_max - ranges[a].max);
    if (ax.isRotary())
      m = m >= 0 ? std::numeric_limits<double>::infinity()
                 : m * 1000.0;  // rotary overrun dominates
    if (m < *margin) *margin = m, *limiting_axis = static_cast<int>(a);
  }
  return ranges;
}

Eigen::Vector3d workOffsetAtPartZero(const MachineModel& model) {
  const MachineFrame f = machineFrame(model);
  return f.ok ? Eigen::Vector3d(-f.Gm.inverse() * f.g0) : Eigen::Vector3d::Zero();
}

WorkOffsetSetup proposeWorkOffset(const MachineModel& model, const std::vector<JointVector>& joints,
                                  const std::vector<char>& kind,
                                  const std::vector<unsigned char>& fixed) {
  WorkOffsetSetup out;
  out.part_zero_table = model.setup.part_zero_table;
  const MachineFrame f = machineFrame(model);
  if (!f.ok || joints.empty()) return out;
  // How the prismatic joints of a work-offset point move with the part zero: q_j = nc_j (m_j +
  // ...), m = word + offset, offset = -G_m^-1 g0(part zero) (the reader's default offset).
  const Eigen::Vector3d off0 = workOffsetAtPartZero(model);
  Eigen::Matrix3d A;
  for (int k = 0; k < 3; ++k) {
    MachineModel mk = model;
    mk.setup.part_zero_table += Eigen::Vector3d::Unit(k);
    const Eigen::Vector3d dm = workOffsetAtPartZero(mk) - off0;
    for (int j = 0; j < 3; ++j) A(j, k) = model.axes[f.prismatic[j]].nc_sign * dm[j];
  }
  // Ranges of the moving (work offset) and fixed (machine coordinate) points.
  const double inf = std::numeric_limits<double>::infinity();
  Eigen::Vector3d lo_m = Eigen::Vector3d::Constant(inf), hi_m = -lo_m;
  Eigen::Vector3d lo_f = lo_m, hi_f = hi_m;
  std::array<bool, 3> moving = {false, false, false};
  auto isFixed = [&](size_t i, int j) {
    return i < fixed.size() ? ((fixed[i] >> j) & 1u) != 0 : (i < kind.size() && kind[i] == 2);
  };
  for (size_t i = 0; i < joints.size(); ++i) {
    const char k = i < kind.size() ? kind[i] : 0;
    if (k == 1) continue;
    for (int j = 0; j < 3; ++j) {
      const double q = joints[i][f.prismatic[j]];
      if (isFixed(i, j)) {
        lo_f[j] = std::min(lo_f[j], q), hi_f[j] = std::max(hi_f[j], q);
      } else {
        lo_m[j] = std::min(lo_m[j], q), hi_m[j] = std::max(hi_m[j], q);
        moving[j] = true;
      }
    }
  }
  if (!moving[0] && !moving[1] && !moving[2]) return out;
  out.placed = moving;
  // Centre each axis's range of the moving points in its travel; an axis no point moves in the
  // work offset stays (its range empty: a shift of it would be NaN).
  Eigen::Vector3d shift;
  out.margin = inf;
  out.work_offset_margin = inf;
  for (int j = 0; j < 3; ++j) {
    const Axis& ax = model.axes[f.prismatic[j]];
    shift[j] = moving[j] ? 0.5 * (ax.travel_min + ax.travel_max) - 0.5 * (lo_m[j] + hi_m[j]) : 0.0;
    const double m_moving =
        moving[j] ? 0.5 * ((ax.travel_max - ax.travel_min) - (hi_m[j] - lo_m[j])) : inf;
    out.work_offset_margin = std::min(out.work_offset_margin, m_moving);
    double m = m_moving;
    if (std::isfinite(lo_f[j])) m = std::min({m, lo_f[j] - ax.travel_min, ax.travel_max - hi_f[j]});
    if (m < out.margin) {
      out.margin = m;
      out.limiting_axis = f.prismatic[j];
      out.limited_by_machine_coordinates = m < m_moving;
    }
  }
  const Eigen::FullPivLU<Eigen::Matrix3d> lu(A);
  if (!lu.isInvertible()) return out;
  const Eigen::Vector3d delta = lu.solve(shift);
  out.part_zero_table = model.setup.part_zero_table + delta;
  MachineModel best = model;
  best.setup.part_zero_table = out.part_zero_table;
  out.work_offset_m = workOffsetAtPartZero(best);
  // The joint ranges with the proposal: the moving points shifted, the fixed ones as they are.
  out.ranges.assign(model.axes.size(), AxisRange{});
  for (size_t i = 0; i < joints.size(); ++i) {
    const char k = i < kind.size() ? kind[i] : 0;
    if (k == 1) continue;
    JointVector q = joints[i];
    for (int j = 0; j < 3; ++j)
      if (!isFixed(i, j)) q[f.prismatic[j]] += shift[j];
    for (size_t a = 0; a < model.axes.size(); ++a) {
      AxisRange& r = out.ranges[a];
      if (!r.known || q[a] < r.min) r.min = q[a], r.min_index = static_cast<int>(i);
      if (!r.known || q[a] > r.max) r.max = q[a], r.max_index = static_cast<int>(i);
      r.known = true;
    }
  }
  out.found = out.margin >= -1e-9;  // a home position at the end of travel is inside
  for (size_t a = 0; a < model.axes.size(); ++a) {
    const Axis& ax = model.axes[a];
    if (!ax.isRotary() || ax.endless || !out.ranges[a].known) continue;
    out.found = out.found && out.ranges[a].min >= ax.travel_min - 1e-9 &&
                out.ranges[a].max <= ax.travel_max + 1e-9;
  }
  return out;
}

}  // namespace tolver
