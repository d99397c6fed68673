#include "core/calibration/identifiability.h"

#include <Eigen/QR>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <random>

#include "core/kinematics/sensitivity_jacobian.h"

namespace tolver {
namespace {

Eigen::MatrixXd selectCols(const Eigen::MatrixXd& R, const std::vector<int>& idx) {
  Eigen::MatrixXd out(R.rows(), idx.size());
  for (size_t i = 0; i < idx.size(); ++i) out.col(i) = R.col(idx[i]);
  return out;
}

}  // namespace

Eigen::MatrixXd stackedJacobian(const ForwardKinematics& fk, const std::vector<JointVector>& poses,
                                const std::vector<int>& columns) {
  const int np = fk.model().parameterCount();
  Eigen::MatrixXd Jp(6, np);
  Eigen::MatrixXd out(6 * poses.size(), columns.size());
  for (size_t k = 0; k < poses.size(); ++k) {
    sensitivityJacobian(fk, poses[k], Jp);
    for (size_t c = 0; c < columns.size(); ++c) out.block<6, 1>(6 * k, c) = Jp.col(columns[c]);
  }
  return out;
}

std::vector<int> modelColumns(const MachineModel& m, const std::string& model) {
  std::vector<int> cols;
  for (const ParameterBlock& b : m.blocks) {
    const bool setup = b.kind == BlockKind::WorkpieceSetup || b.kind == BlockKind::ToolSetup;
    const bool take = model == "all" || setup ||
                      (model == "link" && b.kind == BlockKind::LinkError) ||
                      (model == "motion" && b.kind == BlockKind::MotionError);
    if (take)
      for (int i = 0; i < b.size; ++i) cols.push_back(b.offset + i);
  }
  return cols;
}

MachineModel withMotionDegree(const MachineModel& m, int degree) {
  MachineModel out = m;
  std::vector<std::array<int, 6>> d(m.axes.size());
  for (auto& x : d) x.fill(degree);
  std::vector<std::pair<std::string, std::string>> aliases;
  for (const ParameterAlias& a : m.aliases)
    aliases.emplace_back(a.name, m.parameters[a.parameter].iso_code);
  out.aliases.clear();
  out.buildParameterLayout(d);
  for (const auto& [name, code] : aliases) {
    const int p = out.findParameter(code);
    if (p >= 0) out.aliases.push_back({name, p, ""});
  }
  return out;
}

MinimalSet selectMinimalSet(const Eigen::MatrixXd& J, const std::vector<int>& columns,
                            const std::vector<bool>& setup, const std::vector<int>& preferred,
                            bool unscaled_condition) {
  MinimalSet out;
  const Eigen::MatrixXd R = compressRows(scaleColumns(J));
  out.initial = summariseScaled(R, static_cast<int>(J.rows()));
  if (unscaled_condition) out.initial.condition_unscaled = unscaledCondition(J);
  std::vector<int> live(columns.size());  // positions into columns / R
  for (size_t i = 0; i < live.size(); ++i) live[i] = static_cast<int>(i);
  auto isPreferred = [&](int pos) {
    return std::find(preferred.begin(), preferred.end(), columns[pos]) != preferred.end();
  };
  SvdSummary cur = out.initial;
  while (cur.rank < static_cast<int>(live.size())) {
    ReductionStep step;
    std::vector<int> group;  // positions into live
    // A column with no effect at all goes first.
    for (size_t i = 0; i < live.size(); ++i)
      if (R.col(live[i]).norm() == 0.0) group.push_back(static_cast<int>(i));
    if (!group.empty()) {
      group.resize(1);
      step.strategy = "no effect";
    } else {
      Eigen::JacobiSVD<Eigen::MatrixXd> svd(selectCols(R, live), Eigen::ComputeFullV);
      const Eigen::VectorXd v = svd.matrixV().col(live.size() - 1);
      const double vmax = v.cwiseAbs().maxCoeff();
      for (int i = 0; i < v.size(); ++i)
        if (std::abs(v[i]) >= 0.1 * vmax) group.push_back(i);
      std::sort(group.begin(), group.end(),
                [&](int a, int b) { return std::abs(v[a]) > std::abs(v[b]); });
    }
    for (int g : group) step.group.push_back(columns[live[g]]);
    std::vector<int> candidates = group;
    // I, then II: take protected parameters out of the candidates while some remain.
    auto protect = [&](auto is_protected, const char* name) {
      std::vector<int> rest;
      for (int g : candidates)
        if (!is_protected(live[g])) rest.push_back(g);
      if (!rest.empty() && rest.size() < candidates.size()) {
        candidates = rest;
        step.strategy += step.strategy.empty() ? name : std::string("+") + name;
      }
    };
    if (step.strategy.empty()) {
      protect([&](int pos) { return static_cast<bool>(setup[pos]); }, "I");
      protect(isPreferred, "II");
    }
    // III: among what is left, the removal that leaves the smallest condition number (and
    // never one that loses rank).
    int best = candidates.front();
    std::optional<SvdSummary> best_summary;  // the trials' summary of the removal chosen
    if (candidates.size() > 1) {
      double best_key = std::numeric_limits<double>::infinity();
      for (int g : candidates) {
        std::vector<int> trial = live;
        trial.erase(trial.begin() + g);
        SvdSummary s = summariseScaled(selectCols(R, trial), static_cast<int>(J.rows()));
        if (s.rank < cur.rank) continue;
        const double key = s.singular_values[0] / s.singular_values[s.rank - 1];
        if (key < best_key) {
          best_key = key;
          best = g;
          best_summary = std::move(s);
        }
      }
      step.strategy += step.strategy.empty() ? "III" : "+III";
    }
    std::vector<int> next = live;
    next.erase(next.begin() + best);
    cur = best_summary ? std::move(*best_summary)
                       : summariseScaled(selectCols(R, next), static_cast<int>(J.rows()));
    step.removed = columns[live[best]];
    step.size_after = static_cast<int>(next.size());
    step.rank_after = cur.rank;
    step.condition_after = cur.condition;
    out.steps.push_back(step);
    out.removed.push_back(step.removed);
    live = next;
  }
  for (int pos : live) out.kept.push_back(columns[pos]);
  out.reduced = cur;
  if (!unscaled_condition) {
    out.reduced.condition_unscaled = 0.0;
  } else if (out.removed.empty()) {  // nothing removed: the same matrix
    out.reduced.condition_unscaled = out.initial.condition_unscaled;
  } else {
    Eigen::MatrixXd Jk(J.rows(), live.size());
    for (size_t i = 0; i < live.size(); ++i) Jk.col(i) = J.col(live[i]);
    out.reduced.condition_unscaled = unscaledCondition(Jk);
  }
  return out;
}

MinimalSet minimalSetForModel(const MachineModel& m, const std::vector<JointVector>& poses,
                              const std::vector<int>& columns, const std::vector<int>& preferred) {
  const ForwardKinematics fk(m, Eigen::VectorXd::Zero(m.parameterCount()));
  const Eigen::MatrixXd J = stackedJacobian(fk, poses, columns);
  std::vector<bool> setup(columns.size());
  for (size_t i = 0; i < columns.size(); ++i) {
    const BlockKind k = m.blocks[m.parameters[columns[i]].block].kind;
    setup[i] = k == BlockKind::WorkpieceSetup || k == BlockKind::ToolSetup;
  }
  return selectMinimalSet(J, columns, setup, preferred);
}

std::vector<std::vector<AbsorbedTerm>> absorbedParameters(const MachineModel& m,
                                                          const std::vector<JointVector>& poses,
                                                          const std::vector<int>& kept,
                                                          const std::vector<int>& removed,
                                                          double min_share) {
  std::vector<std::vector<AbsorbedTerm>> out(kept.size());
  if (kept.empty() || removed.empty()) return out;
  std::vector<int> basis = kept;
  for (int p = 0; p < m.parameterCount(); ++p) {
    const BlockKind k = m.blocks[m.parameters[p].block].kind;
    if ((k == BlockKind::WorkpieceSetup || k == BlockKind::ToolSetup) &&
        std::find(kept.begin(), kept.end(), p) == kept.end())
      basis.push_back(p);
  }
  const ForwardKinematics fk(m, Eigen::VectorXd::Zero(m.parameterCount()));
  const Eigen::MatrixXd B = stackedJacobian(fk, poses, basis);
  const Eigen::MatrixXd R = stackedJacobian(fk, poses, removed);
  const Eigen::VectorXd nb = B.colwise().norm().transpose();
  Eigen::VectorXd sb = nb;
  for (Eigen::Index c = 0; c < sb.size(); ++c)
    if (sb[c] == 0) sb[c] = 1;
  const Eigen::MatrixXd Bs = B * sb.cwiseInverse().asDiagonal();
  const Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd> cod(Bs);
  for (Eigen::Index j = 0; j < R.cols(); ++j) {
    const double nr = R.col(j).norm();
    if (!(nr > 0)) continue;
    const Eigen::VectorXd a = cod.solve(R.col(j)).cwiseQuotient(sb);
    // Only a removed column the kept ones (and the set-up) reproduce is folded in.
    if ((B * a - R.col(j)).norm() > 1e-6 * nr) continue;
    for (size_t k = 0; k < kept.size(); ++k) {
      const double share = std::abs(a[k]) * nb[k] / nr;
      if (share >= min_share) out[k].push_back({removed[j], a[k], share});
    }
  }
  for (auto& v : out)
    std::sort(v.begin(), v.end(),
              [](const AbsorbedTerm& x, const AbsorbedTerm& y) { return x.share > y.share; });
  return out;
}

std::vector<JointVector> randomPoses(const MachineModel& m, int count, unsigned seed) {
  std::mt19937 rng(seed);
  std::vector<JointVector> poses;
  for (int k = 0; k < count; ++k) {
    JointVector q(m.axes.size());
    for (size_t a = 0; a < m.axes.size(); ++a) {
      std::uniform_real_distribution<double> u(m.axes[a].travel_min, m.axes[a].travel_max);
      q[a] = u(rng);
    }
    poses.push_back(q);
  }
  return poses;
}

}  // namespace tolver
