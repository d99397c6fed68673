#include "core/diagnosis/part_trace.h"

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>

#include "core/numerics/statistics.h"

namespace tolver {
namespace {

template <typename... A>
std::string formatReason(const char* f, A... a) {
  char buf[200];
  std::snprintf(buf, sizeof buf, f, a...);
  return buf;
}

struct Group {
  std::string name;
  std::vector<std::string> value_names;
  Eigen::MatrixXd X;               // points x values
  Eigen::MatrixXd prior_root_inv;  // values x values, L^-1 of the prior (empty: none)
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();  // set-up: the rotations' centre while fitting
  double plausible_abs = INFINITY;                   // the largest |value| that is physical
};

// The least squares fit of y by the columns of the groups in `set` on the rows in `rows`, with
// each group's prior (if any) as extra rows sigma L^-1 beta = 0. Returns beta (stacked) and sets
// *rss.
struct Fit {
  Eigen::VectorXd beta;
  Eigen::MatrixXd covariance;  // of beta, sigma^2 (A^T A)^-1
  double rss = 0;
  int columns = 0;
};

Fit fitGroups(const std::vector<Group>& groups, const std::vector<int>& set,
              const std::vector<int>& rows, const Eigen::VectorXd& y, double sigma) {
  Fit f;
  int cols = 0, prior_rows = 0;
  for (int g : set) {
    cols += static_cast<int>(groups[g].X.cols());
    if (groups[g].prior_root_inv.size()) prior_rows += static_cast<int>(groups[g].X.cols());
  }
  f.columns = cols;
  const int m = static_cast<int>(rows.size());
  Eigen::VectorXd b(m + prior_rows);
  for (int i = 0; i < m; ++i) b[i] = y[rows[i]];
  b.tail(prior_rows).setZero();
  if (cols == 0) {
    f.rss = b.head(m).squaredNorm();
    return f;
  }
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(m + prior_rows, cols);
  int c = 0, pr = m;
  for (int g : set) {
    const Group& G = groups[g];
    const int k = static_cast<int>(G.X.cols());
    for (int i = 0; i < m; ++i) A.block(i, c, 1, k) = G.X.row(rows[i]);
    if (G.prior_root_inv.size()) {
      A.block(pr, c, k, k) = sigma * G.prior_root_inv;
      pr += k;
    }
    c += k;
  }
  // Column scaling: lengths (mm) and angles (rad) at once.
  Eigen::VectorXd scale = A.colwise().norm().transpose();
  for (Eigen::Index j = 0; j < scale.size(); ++j) scale[j] = scale[j] > 0 ? 1.0 / scale[j] : 0.0;
  const Eigen::MatrixXd As = A * scale.asDiagonal();
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(As);
  f.beta = scale.asDiagonal() * qr.solve(b);
  f.rss = (b.head(m) - A.topRows(m) * f.beta).squaredNorm();
  const Eigen::MatrixXd N = As.transpose() * As;
  f.covariance =
      scale.asDiagonal() * N.completeOrthogonalDecomposition().pseudoInverse() * scale.asDiagonal();
  return f;
}

Eigen::VectorXd predictGroups(const std::vector<Group>& groups, const std::vector<int>& set,
                              const Fit& f) {
  const Eigen::Index n = groups.front().X.rows();
  Eigen::VectorXd out = Eigen::VectorXd::Zero(n);
  int c = 0;
  for (int g : set) {
    const int k = static_cast<int>(groups[g].X.cols());
    out += groups[g].X * f.beta.segment(c, k);
    c += k;
  }
  return out;
}

double rmsOf(const Eigen::VectorXd& r, const std::vector<int>& rows, double* max_abs = nullptr) {
  double s = 0, mx = 0;
  for (int i : rows) {
    s += r[i] * r[i];
    mx = std::max(mx, std::abs(r[i]));
  }
  if (max_abs) *max_abs = mx;
  return rows.empty() ? 0.0 : std::sqrt(s / rows.size());
}

std::vector<Group> candidateGroups(const std::vector<TracePoint>& pts, const TraceOptions& o) {
  const Eigen::Index n = static_cast<Eigen::Index>(pts.size());
  std::vector<Group> groups;
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (const TracePoint& p : pts) c += p.p_w;
  c /= std::max<Eigen::Index>(1, n);
  {
    Group g;
    g.name = "set-up";
    g.value_names = {"x mm", "y mm", "z mm", "about x rad", "about y rad", "about z rad"};
    g.X.resize(n, 6);
    g.centre = c;
    // The part off by (t, w) on the table (about the points' centroid c while fitting, for
    // conditioning): the path the machine runs, seen from the part, moves by -(t + w x (p - c)).
    for (Eigen::Index i = 0; i < n; ++i) {
      g.X.block<1, 3>(i, 0) = -pts[i].n_w.transpose();
      g.X.block<1, 3>(i, 3) = -(pts[i].p_w - c).cross(pts[i].n_w).transpose();
    }
    groups.push_back(std::move(g));
  }
  for (int k = 0; k < std::max(1, o.tools); ++k) {
    const std::string t = o.tools > 1 ? " T" + std::to_string(k + 1) : "";
    Group r, l, d;
    r.name = "cutter radius" + t;
    r.value_names = {"dR mm"};
    r.X = Eigen::MatrixXd::Zero(n, 1);
    l.name = "tool length" + t;
    l.value_names = {"dL mm"};
    l.X = Eigen::MatrixXd::Zero(n, 1);
    d.name = "tool offset" + t;
    d.value_names = {"x mm", "y mm", "z mm"};
    d.X = Eigen::MatrixXd::Zero(n, 3);
    for (Eigen::Index i = 0; i < n; ++i) {
      if (pts[i].tool != k) continue;
      r.X(i, 0) = pts[i].radius_sensitivity;
      l.X(i, 0) = -pts[i].n_w.dot(pts[i].axis_w);
      d.X.row(i) = pts[i].n_w.transpose();
    }
    for (Group* g : {&r, &l})
      if (g->X.cwiseAbs().maxCoeff() > 1e-6) groups.push_back(std::move(*g));
    if (o.tools > 1 && d.X.cwiseAbs().maxCoeff() > 1e-6) groups.push_back(std::move(d));
  }
  bool timed = n > 0;
  for (const TracePoint& p : pts) timed = timed && std::isfinite(p.time_h);
  if (timed) {
    Group g;
    g.name = "thermal drift";
    g.value_names = {"spindle growth mm/h"};
    g.X.resize(n, 1);
    for (Eigen::Index i = 0; i < n; ++i) g.X(i, 0) = -pts[i].n_w.dot(pts[i].axis_w) * pts[i].time_h;
    g.plausible_abs = o.plausible.drift_mm_per_h;
    if (g.X.cwiseAbs().maxCoeff() > 1e-9) groups.push_back(std::move(g));
  }
  for (int k = 0; k < std::max(1, o.tools); ++k) {
    Group g;
    g.name = "tool deflection" + (o.tools > 1 ? " T" + std::to_string(k + 1) : std::string());
    g.value_names = {"off the surface mm", "across the feed mm"};
    g.X = Eigen::MatrixXd::Zero(n, 2);
    for (Eigen::Index i = 0; i < n; ++i) {
      const TracePoint& p = pts[i];
      if (p.tool != k) continue;
      g.X(i, 0) = (p.n_w - p.n_w.dot(p.axis_w) * p.axis_w).norm();
      g.X(i, 1) = p.n_w.dot(p.axis_w.cross(p.feed_w));
    }
    g.plausible_abs = o.plausible.deflection_mm;
    // Both directions must vary, or the group is another's (a flat floor: nothing to see).
    if (g.X.col(0).cwiseAbs().maxCoeff() > 1e-6 && g.X.col(1).cwiseAbs().maxCoeff() > 1e-6)
      groups.push_back(std::move(g));
  }
  {
    Group g;
    g.name = "stock";
    g.value_names = {"offset mm"};
    g.X = Eigen::MatrixXd::Ones(n, 1);
    groups.push_back(std::move(g));
  }
  if (o.machine_rows.rows() == n && o.machine_rows.cols() > 0 &&
      o.machine_covariance.rows() == o.machine_rows.cols()) {
    Group g;
    g.name = "machine";
    g.value_names = o.machine_names;
    g.value_names.resize(o.machine_rows.cols(), "parameter");
    g.X = o.machine_rows;
    Eigen::MatrixXd C = o.machine_covariance;
    C.diagonal().array() += 1e-30 + 1e-12 * C.diagonal().maxCoeff();
    const Eigen::LLT<Eigen::MatrixXd> llt(C);
    if (llt.info() == Eigen::Success) {
      const Eigen::MatrixXd L = llt.matrixL();
      g.prior_root_inv =
          L.triangularView<Eigen::Lower>().solve(Eigen::MatrixXd::Identity(C.rows(), C.cols()));
      groups.push_back(std::move(g));
    }
  }
  return groups;
}

}  // namespace

PartTrace tracePart(const std::vector<TracePoint>& pts, const TraceOptions& o) {
  PartTrace out;
  const Eigen::Index n = static_cast<Eigen::Index>(pts.size());
  out.residual_after = Eigen::VectorXd::Zero(n);
  if (n == 0) {
    out.verdict = "nothing added";
    out.verdict_text = "no measured points";
    return out;
  }
  Eigen::VectorXd y(n);
  std::vector<int> fit_rows, held_rows;
  for (Eigen::Index i = 0; i < n; ++i) {
    y[i] = pts[i].residual;
    (pts[i].held_out ? held_rows : fit_rows).push_back(static_cast<int>(i));
  }
  out.fit_points = static_cast<int>(fit_rows.size());
  out.heldout_points = static_cast<int>(held_rows.size());
  const std::vector<Group> groups = candidateGroups(pts, o);
  out.groups.resize(groups.size());
  for (size_t g = 0; g < groups.size(); ++g) {
    out.groups[g].name = groups[g].name;
    out.groups[g].value_names = groups[g].value_names;
  }
  out.fit_rms_before = rmsOf(y, fit_rows);
  out.heldout_rms_before = rmsOf(y, held_rows, &out.heldout_max_before);
  // The prior's noise scale: the residual before any effect (a strong prior: the part moves the
  // calibrated machine only where it is sure).
  const double sigma = std::max(out.fit_rms_before, 1e-9);
  // Held-out blocks: consecutive held-out points in 20 blocks (neighbours share slow errors).
  std::vector<int> block(held_rows.size());
  const int blocks = std::min<int>(20, static_cast<int>(held_rows.size()));
  for (size_t i = 0; i < held_rows.size(); ++i)
    block[i] = static_cast<int>(i * blocks / std::max<size_t>(1, held_rows.size()));

  std::vector<int> current, implausible;
  Fit base = fitGroups(groups, current, fit_rows, y, sigma);
  Eigen::VectorXd r_base = y;
  for (;;) {
    int best = -1;
    double best_f = 0, best_p = 1, best_bic = 0;
    std::vector<Fit> trial(groups.size());
    for (size_t g = 0; g < groups.size(); ++g) {
      if (std::find(current.begin(), current.end(), static_cast<int>(g)) != current.end()) continue;
      if (std::find(implausible.begin(), implausible.end(), static_cast<int>(g)) !=
          implausible.end())
        continue;
      std::vector<int> set = current;
      set.push_back(static_cast<int>(g));
      trial[g] = fitGroups(groups, set, fit_rows, y, sigma);
      const double q = static_cast<double>(groups[g].X.cols());
      const double dof = static_cast<double>(fit_rows.size()) - trial[g].columns;
      TraceGroup& tg = out.groups[g];
      tg.rss_fit = trial[g].rss;
      if (dof < 1 || !(trial[g].rss > 0)) continue;
      tg.f = std::max(0.0, (base.rss - trial[g].rss) / q) / (trial[g].rss / dof);
      tg.p_value = fSurvival(tg.f, q, dof);
      // Ranked by BIC (a group of six values must buy more than a group of one): the F test
      // then decides whether the best is real.
      const double m = static_cast<double>(fit_rows.size());
      const double bic = m * std::log(trial[g].rss / base.rss) + q * std::log(m);
      if (best < 0 || bic < best_bic) {
        best_bic = bic;
        best_f = tg.f;
        best_p = tg.p_value;
        best = static_cast<int>(g);
      }
    }
    if (best < 0) break;
    TraceGroup& tb = out.groups[best];
    if (!(best_p < o.alpha)) {
      tb.reason = formatReason("F %.3g, p %.2g: not significant", best_f, best_p);
      break;
    }
    std::vector<int> set = current;
    set.push_back(best);
    {
      const Eigen::Index k = groups[best].X.cols();
      const Eigen::VectorXd v = trial[best].beta.tail(k);
      if (v.cwiseAbs().maxCoeff() > groups[best].plausible_abs) {
        tb.reason =
            formatReason("implausible: %.3g beyond the physical range +-%.3g (%s); not added",
                         v.cwiseAbs().maxCoeff(), groups[best].plausible_abs,
                         groups[best].value_names[0].c_str());
        tb.values = v;
        tb.sd = Eigen::VectorXd::Constant(k, NAN);
        implausible.push_back(best);
        continue;
      }
    }
    const Eigen::VectorXd r_new = y - predictGroups(groups, set, trial[best]);
    if (!held_rows.empty()) {
      std::vector<double> gain(held_rows.size());
      for (size_t i = 0; i < held_rows.size(); ++i) {
        const int k = held_rows[i];
        gain[i] = 1e6 * (r_base[k] * r_base[k] - r_new[k] * r_new[k]);
      }
      double se = 0;
      tb.heldout_gain_um2 = blockMean(gain, block, blocks, &se);
      tb.heldout_gain_se_um2 = se;
      if (!(tb.heldout_gain_um2 > 2.0 * se)) {
        tb.reason =
            formatReason("held-out gain %.3g +- %.2g um2: not confirmed", tb.heldout_gain_um2, se);
        break;
      }
    }
    // Groups that fit these points as well: confounded with it.
    const double gain_best = base.rss - trial[best].rss;
    for (size_t g = 0; g < groups.size(); ++g) {
      if (static_cast<int>(g) == best || trial[g].columns == 0) continue;
      if (std::find(current.begin(), current.end(), static_cast<int>(g)) != current.end()) continue;
      if (base.rss - trial[g].rss >= 0.98 * gain_best) {
        tb.confounded.push_back(groups[g].name);
        out.groups[g].confounded.push_back(groups[best].name);
        out.groups[g].reason =
            "confounded with " + groups[best].name + ": these points cannot tell them apart";
      }
    }
    tb.added = true;
    tb.reason = formatReason("F %.3g, p %.2g", best_f, best_p);
    current = set;
    out.added.push_back(best);
    base = trial[best];
    r_base = r_new;
  }
  // The values of the final model, each group's from the joint fit.
  int c = 0;
  for (int g : current) {
    const int k = static_cast<int>(groups[g].X.cols());
    const double dof = std::max(1.0, static_cast<double>(fit_rows.size()) - base.columns);
    const double s2 = base.rss / dof;
    Eigen::VectorXd v = base.beta.segment(c, k);
    Eigen::MatrixXd C = s2 * base.covariance.block(c, c, k, k);
    if (groups[g].name == "set-up") {  // the translation at the part's origin: t - w x centre
      Eigen::MatrixXd G = Eigen::MatrixXd::Identity(6, 6);
      const Eigen::Vector3d& x = groups[g].centre;
      G.block<3, 3>(0, 3) << 0, -x.z(), x.y(), x.z(), 0, -x.x(), -x.y(), x.x(), 0;
      v = G * v;
      C = G * C * G.transpose();
    }
    out.groups[g].values = v;
    out.groups[g].sd = C.diagonal().cwiseMax(0.0).cwiseSqrt();
    out.groups[g].covariance = C;
    c += k;
  }
  out.residual_after = r_base;
  out.fit_rms_after = rmsOf(r_base, fit_rows);
  out.heldout_rms_after = rmsOf(r_base, held_rows, &out.heldout_max_after);
  out.sigma_after =
      std::sqrt(base.rss / std::max(1.0, static_cast<double>(fit_rows.size()) - base.columns));
  // Ranked: the added groups in order, then the others by F.
  std::vector<int> order(out.groups.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int>(i);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
    const auto pa = std::find(current.begin(), current.end(), a);
    const auto pb = std::find(current.begin(), current.end(), b);
    if (pa != current.end() || pb != current.end()) return pa < pb;
    return out.groups[a].f > out.groups[b].f;
  });
  std::vector<TraceGroup> ranked;
  for (int i : order) ranked.push_back(out.groups[i]);
  out.groups = std::move(ranked);
  for (size_t i = 0; i < out.added.size(); ++i) out.added[i] = static_cast<int>(i);
  // Lack of fit against the points measured more than once.
  {
    std::map<int, std::vector<int>> places;
    for (int i : fit_rows)
      if (pts[i].repeat >= 0) places[pts[i].repeat].push_back(i);
    double ss_pe = 0;
    PartTrace::LackOfFit& l = out.lack_of_fit;
    for (const auto& [id, rows] : places) {
      if (rows.size() < 2) continue;
      ++l.places;
      double mean = 0;
      for (int i : rows) mean += r_base[i];
      mean /= static_cast<double>(rows.size());
      for (int i : rows) ss_pe += (r_base[i] - mean) * (r_base[i] - mean);
      l.df_pure += static_cast<double>(rows.size()) - 1.0;
    }
    const double df_resid = static_cast<double>(fit_rows.size()) - base.columns;
    l.df_lack = df_resid - l.df_pure;
    if (l.df_pure >= 2 && l.df_lack >= 1 && ss_pe > 0) {
      l.tested = true;
      l.s_pure = std::sqrt(ss_pe / l.df_pure);
      const double ss_lof = std::max(0.0, base.rss - ss_pe);
      l.f = (ss_lof / l.df_lack) / (ss_pe / l.df_pure);
      l.p_value = fSurvival(l.f, l.df_lack, l.df_pure);
      l.missing_rms =
          std::sqrt(std::max(0.0, out.sigma_after * out.sigma_after - l.s_pure * l.s_pure));
    }
  }
  const PartTrace::LackOfFit& lof = out.lack_of_fit;
  if (lof.tested && lof.p_value < o.alpha) {
    out.verdict = "unexplained";
    out.verdict_text = formatReason(
        "unexplained: the model misses %.2f um RMS beyond the points' repeatability (%.2f um, "
        "%d places measured twice or more; F %.3g, p %.2g)",
        1e3 * lof.missing_rms, 1e3 * lof.s_pure, lof.places, lof.f, lof.p_value);
    if (!current.empty()) {
      out.verdict_text += "; added:";
      for (size_t i = 0; i < current.size(); ++i)
        out.verdict_text += (i ? ", " : " ") + out.groups[i].name;
    }
  } else if (!current.empty()) {
    out.verdict = "effects added";
    out.verdict_text = "effects added:";
    for (size_t i = 0; i < current.size(); ++i)
      out.verdict_text += (i ? ", " : " ") + out.groups[i].name;
  } else {
    out.verdict = "nothing added";
    out.verdict_text =
        "nothing added: no candidate explains the residual beyond the points' own scatter";
  }
  if (out.verdict != "unexplained")
    out.verdict_text += lof.tested
                            ? formatReason(
                                  " (the residual is the repeatability: %.2f um over %d places "
                                  "measured twice or more, F %.3g, p %.2g)",
                                  1e3 * lof.s_pure, lof.places, lof.f, lof.p_value)
                            : std::string(" (adequacy not tested: no place measured twice)");
  return out;
}

}  // namespace tolver
