#include "core/diagnosis/diagnosis.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/QR>
#include <Eigen/SVD>
#include <algorithm>
#include <boost/math/tools/minima.hpp>
#include <chrono>
#include <cmath>
#include <complex>
#include <cstdio>
#include <limits>
#include <optional>

#include "core/model/effects.h"
#include "core/numerics/chebyshev.h"
#include "core/numerics/statistics.h"
#include "core/numerics/units.h"

namespace tolver {

const char* verdictName(CandidateVerdict v) {
  switch (v) {
    case CandidateVerdict::Added:
      return "added";
    case CandidateVerdict::Outscored:
      return "significant, outscored";
    case CandidateVerdict::NotSignificant:
      return "not significant";
    case CandidateVerdict::NoPredictiveGain:
      return "no cross-validated gain";
    case CandidateVerdict::Confounded:
      return "confounded";
    case CandidateVerdict::NotIdentifiable:
      return "not identifiable";
    case CandidateVerdict::RefitFailed:
      return "refit failed";
    case CandidateVerdict::Implausible:
      return "implausible value";
  }
  return "";
}

std::vector<int> contiguousFolds(const BallbarTest& test, int blocks_per_setup, int* folds) {
  const int ns = static_cast<int>(test.setups.size());
  std::vector<int> count(ns, 0), seen(ns, 0);
  for (const BallbarReading& r : test.readings) ++count[r.setup];
  std::vector<int> fold(test.readings.size());
  const int b = std::max(1, blocks_per_setup);
  for (size_t i = 0; i < test.readings.size(); ++i) {
    const int s = test.readings[i].setup;
    fold[i] = s * b + std::min(b - 1, seen[s]++ * b / std::max(1, count[s]));
  }
  *folds = ns * b;
  return fold;
}

namespace {

// Thin orthonormal basis of the column space of A (rank-revealing QR).
Eigen::MatrixXd orthonormalBasis(const Eigen::ColPivHouseholderQR<Eigen::MatrixXd>& qr) {
  const Eigen::Index rank = qr.rank();
  Eigen::MatrixXd Q = Eigen::MatrixXd::Identity(qr.rows(), rank);
  Q.applyOnTheLeft(qr.householderQ());
  return Q;
}

// A - Q Q^T A, Q the orthonormal basis of the QR's first rank() columns, by its reflectors
// (H^T A with its first rank() rows zeroed, turned back by H): 4 m n k operations for k columns,
// where forming Q would take 2 m n^2.
Eigen::MatrixXd outsideColumns(const Eigen::ColPivHouseholderQR<Eigen::MatrixXd>& qr,
                               const Eigen::MatrixXd& A) {
  Eigen::MatrixXd W = A;
  W.applyOnTheLeft(qr.householderQ().adjoint());
  W.topRows(qr.rank()).setZero();
  W.applyOnTheLeft(qr.householderQ());
  return W;
}

Eigen::MatrixXd rowsOf(const Eigen::MatrixXd& A, const std::vector<int>& rows) {
  Eigen::MatrixXd out(rows.size(), A.cols());
  for (size_t i = 0; i < rows.size(); ++i) out.row(i) = A.row(rows[i]);
  return out;
}

Eigen::VectorXd rowsOf(const Eigen::VectorXd& v, const std::vector<int>& rows) {
  Eigen::VectorXd out(rows.size());
  for (size_t i = 0; i < rows.size(); ++i) out[i] = v[rows[i]];
  return out;
}

// The linearised fit at a solution, and everything a candidate is scored against.
class Scorer {
 public:
  Scorer(const Machine& machine, const BallbarTest& test, const CalibrationResult& fit,
         const std::vector<int>& fold_of, int folds)
      : model_(machine.model), test_(test) {
    const ForwardKinematics fk(model_, fit.params);
    J_ = identificationJacobian(fk, test, fit.ball_errors, fit.identified, &r_);
    m_ = static_cast<int>(r_.size());
    J_ = scaleColumns(J_, &scale_);
    const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(J_);
    Q_ = orthonormalBasis(qr);
    n_ = static_cast<int>(qr.rank());
    r_perp_ = r_ - Q_ * (Q_.transpose() * r_);
    rss0_ = r_perp_.squaredNorm();
    // Derivatives of each reading with respect to each axis's motion-error components.
    const int na = static_cast<int>(model_.axes.size());
    Gc_.resize(m_, 6 * na);
    Eigen::MatrixXd scratch;
    Eigen::RowVectorXd row(6 * na);
    for (int i = 0; i < m_; ++i) {
      const BallbarReading& rd = test.readings[i];
      ballbarComponentGradient(fk, rd.q, test.setups[rd.setup], fit.ball_errors[rd.setup], row,
                               scratch, &rd.context);
      Gc_.row(i) = row;
    }
    same_run_.assign(m_, false);
    for (int i = 1; i < m_; ++i)
      same_run_[i] = test.readings[i].setup == test.readings[i - 1].setup;
    // Folds: the base fit without each block.
    folds_.resize(folds);
    // Each fold's fit by downdating the normal equations, N - J_H^T J_H (n^3 / 3 and |H| n^2
    // operations, where a fold's QR takes 2 m n^2), when J has full rank and is well conditioned
    // (the scaled columns' condition below 1e5: the normal equations keep ten digits); else by
    // the QR of the fold's rows.
    const Eigen::MatrixXd::Index cols = J_.cols();
    const auto& R = qr.matrixR();
    const double r_max = cols > 0 ? std::abs(R(0, 0)) : 0.0;
    const double r_min = cols > 0 ? std::abs(R(cols - 1, cols - 1)) : 0.0;
    normal_ = n_ == cols && cols > 0 && r_min > 1e-5 * r_max;
    if (normal_) {
      N_ = J_.transpose() * J_;
      Jtr_ = J_.transpose() * r_;
    }
    for (int f = 0; f < folds; ++f) {
      Fold& F = folds_[f];
      for (int i = 0; i < m_; ++i) (fold_of[i] == f ? F.held : F.train).push_back(i);
      if (F.held.empty() || F.train.empty()) continue;
      F.JH = rowsOf(J_, F.held);
      F.rT = rowsOf(r_, F.train);
      F.rH = rowsOf(r_, F.held);
      if (normal_) {
        F.llt.compute(N_ - F.JH.transpose() * F.JH);
        F.normal = F.llt.info() == Eigen::Success;
        F.c = Jtr_ - F.JH.transpose() * F.rH;
      }
      if (!F.normal) {
        F.JT = rowsOf(J_, F.train);
        F.qr.compute(F.JT);
        F.JT.resize(0, 0);
      }
    }
  }

  // Unknowns of the fit whose (unit) columns have |cosine| >= min_cosine with one of G's, by
  // column index of the identification Jacobian, largest first.
  std::vector<std::pair<int, double>> similarColumns(const Eigen::MatrixXd& G,
                                                     double min_cosine) const {
    std::vector<std::pair<int, double>> out;
    const Eigen::MatrixXd C = J_.transpose() * scaleColumns(G);  // J_ columns are unit (scaled)
    for (Eigen::Index j = 0; j < C.rows(); ++j) {
      const double cj = C.row(j).cwiseAbs().maxCoeff();
      if (cj >= min_cosine) out.emplace_back(static_cast<int>(j), cj);
    }
    std::sort(out.begin(), out.end(),
              [](const auto& a, const auto& b) { return a.second > b.second; });
    return out;
  }

  // The periodic effect's columns, g sin(2 pi f s) and g cos(2 pi f s) (its basis), along the
  // uniform grid f = f0 + k df, k = 0, 1, ...: each reading's phase e^(i 2 pi f s) is advanced by
  // one complex multiplication a step and set afresh by sin and cos every kAnchor steps (the
  // rounding it gathers stays near 1e-14). Evaluating the basis at every reading for every grid
  // value was a fifth of a diagnosis.
  class FrequencyGrid {
   public:
    FrequencyGrid(const Scorer& sc, const EffectSpec& spec, double f0, double df)
        : f0_(f0), df_(df), G_(sc.m_, 2), s_(sc.m_), g_(sc.m_), z_(sc.m_), step_(sc.m_) {
      for (int i = 0; i < sc.m_; ++i) {
        s_[i] = sc.test_.readings[i].q[spec.axis];
        g_[i] = sc.Gc_(i, 6 * spec.axis + spec.component);
        step_[i] = std::polar(1.0, 2 * kPi * df * s_[i]);
      }
      anchor();
    }
    double frequency() const { return f0_ + k_ * df_; }
    const Eigen::MatrixXd& columns() {
      for (Eigen::Index i = 0; i < G_.rows(); ++i) {
        G_(i, 0) = g_[i] * z_[i].imag();
        G_(i, 1) = g_[i] * z_[i].real();
      }
      return G_;
    }
    void advance() {
      if (++k_ % kAnchor == 0)
        anchor();
      else
        z_ *= step_;
    }

   private:
    void anchor() {
      const double f = frequency();
      for (Eigen::Index i = 0; i < z_.size(); ++i) z_[i] = std::polar(1.0, 2 * kPi * f * s_[i]);
    }
    static constexpr int kAnchor = 32;
    double f0_, df_;
    int k_ = 0;
    Eigen::MatrixXd G_;
    Eigen::ArrayXd s_, g_;
    Eigen::ArrayXcd z_, step_;
  };

  int readings() const { return m_; }
  int unknowns() const { return n_; }
  double rss() const { return rss0_; }

  // The readings' derivatives with respect to the effect's coefficients (m x k).
  Eigen::MatrixXd columns(const EffectSpec& spec) const {
    const EffectTraits& t = traitsOf(spec.type);
    const int k = t.size(spec);
    Eigen::MatrixXd G(m_, k);
    if (spec.axis < 0) {
      G.setOnes();
      return G;
    }
    const Axis& ax = model_.axes[spec.axis];
    double phi[8];
    for (int i = 0; i < m_; ++i) {
      const BallbarReading& rd = test_.readings[i];
      const double s = rd.q[spec.axis];
      t.basis(spec, s, normalisedCoordinate(s, ax.travel_min, ax.travel_max), &rd.context, phi);
      const double g = Gc_(i, 6 * spec.axis + spec.component);
      for (int j = 0; j < k; ++j) G(i, j) = g * phi[j];
    }
    return G;
  }

  // RSS after adding the columns G (the projection fit); rss() when G is empty or null.
  double rssWith(const Eigen::MatrixXd& G, Eigen::VectorXd* residual = nullptr,
                 double* new_information = nullptr) const {
    const Eigen::MatrixXd Gs = scaleColumns(G);
    const Eigen::MatrixXd Gp = Gs - Q_ * (Q_.transpose() * Gs);
    if (new_information) {
      const Eigen::JacobiSVD<Eigen::MatrixXd> svd(Gp);
      *new_information = svd.singularValues().minCoeff();
    }
    const Eigen::VectorXd beta = Gp.colPivHouseholderQr().solve(r_perp_);
    const Eigen::VectorXd e = r_perp_ - Gp * beta;
    if (residual) *residual = e;
    return e.squaredNorm();
  }

  // rssWith(G) by the k x k normal equations of G's part outside the fit's columns:
  // Gp^T Gp = Gs^T Gs - (Q^T Gs)^T (Q^T Gs) and Gp^T r_perp = Gs^T r_perp (r_perp is outside them
  // already), so one m n k product where rssWith makes two and factors Gp. For the searches of a
  // period or a time constant, which evaluate it hundreds of times; directions of Gp whose
  // squared singular value is below 1e-9 of the largest (nearly inside the fit's columns, where
  // the normal equations lose their digits) explain nothing here.
  double rssSearch(const Eigen::MatrixXd& G) const {
    if (G.cols() == 0) return rss0_;
    double out = 0.0;
    rssSearchBatch(G, static_cast<int>(G.cols()), &out);
    return out;
  }

  // rssSearch of several column sets at once: G holds groups of k columns side by side, out[b]
  // receives group b's. Q^T Gs for all groups is one blocked product, which reads Q (m x p,
  // beyond the cache for ten thousand readings) once, where a group at a time streamed it from
  // memory for each: the searches' grids go through it a block of values at a time. Each group
  // is scaled on its own, as rssSearch scales its G.
  void rssSearchBatch(const Eigen::MatrixXd& G, int k, double* out) const {
    const Eigen::Index groups = k > 0 ? G.cols() / k : 0;
    Eigen::MatrixXd Gs(G.rows(), G.cols());
    for (Eigen::Index b = 0; b < groups; ++b)
      Gs.middleCols(b * k, k) = scaleColumns(G.middleCols(b * k, k));
    Eigen::MatrixXd QtG(Q_.cols(), Gs.cols());
    QtG.noalias() = Q_.transpose() * Gs;
    Eigen::VectorXd Gtr(Gs.cols());
    Gtr.noalias() = Gs.transpose() * r_perp_;
    Eigen::MatrixXd gram(k, k);
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(k);
    for (Eigen::Index b = 0; b < groups; ++b) {
      const auto Gb = Gs.middleCols(b * k, k);
      const auto Qb = QtG.middleCols(b * k, k);
      gram.noalias() = Gb.transpose() * Gb;
      gram.noalias() -= Qb.transpose() * Qb;
      eig.compute(gram);
      const Eigen::VectorXd& lambda = eig.eigenvalues();
      const double floor = 1e-9 * std::max(lambda.maxCoeff(), 1e-300);
      const Eigen::VectorXd vb = eig.eigenvectors().transpose() * Gtr.segment(b * k, k);
      double explained = 0.0;
      for (Eigen::Index j = 0; j < lambda.size(); ++j)
        if (lambda[j] > floor) explained += vb[j] * vb[j] / lambda[j];
      out[b] = std::max(0.0, rss0_ - explained);
    }
  }

  // Cross-validated RMS of the base model (G empty) or the model with the columns G, mm; with
  // held, each reading's residual predicted by the fit without its fold (0 when its fold is
  // empty or all).
  double crossValidatedRms(const Eigen::MatrixXd* G, Eigen::VectorXd* held = nullptr) const {
    double sum = 0.0;
    int count = 0;
    if (held) held->setZero(m_);
    // The whole data's products with G, downdated per fold (normal equations).
    Eigen::MatrixXd JtG, GtG;
    Eigen::VectorXd Gtr;
    if (G && normal_) {
      JtG = J_.transpose() * *G;
      GtG = G->transpose() * *G;
      Gtr = G->transpose() * r_;
    }
    for (const Fold& F : folds_) {
      if (F.held.empty() || F.train.empty()) continue;
      Eigen::VectorXd eH;
      if (F.normal) {
        // [J G] fitted on the fold's training rows by the normal equations' Schur complement:
        // A = J_T^T G_T, c = J_T^T r_T, (G_T^T G_T - A^T N_T^-1 A) beta = G_T^T r_T - A^T N_T^-1 c,
        // N_T alpha = c - A beta.
        if (!G) {
          eH = F.rH - F.JH * F.llt.solve(F.c);
        } else {
          const Eigen::MatrixXd GH = rowsOf(*G, F.held);
          const Eigen::MatrixXd A = JtG - F.JH.transpose() * GH;
          const Eigen::MatrixXd NiA = F.llt.solve(A);
          const Eigen::VectorXd Nic = F.llt.solve(F.c);
          const Eigen::MatrixXd S = GtG - GH.transpose() * GH - A.transpose() * NiA;
          const Eigen::VectorXd t = Gtr - GH.transpose() * F.rH - A.transpose() * Nic;
          const Eigen::VectorXd beta = S.colPivHouseholderQr().solve(t);
          eH = F.rH - F.JH * (Nic - NiA * beta) - GH * beta;
        }
      } else if (!G) {
        eH = F.rH - F.JH * F.qr.solve(F.rT);
      } else {
        const Eigen::MatrixXd GT = rowsOf(*G, F.train), GH = rowsOf(*G, F.held);
        const Eigen::MatrixXd GTp = outsideColumns(F.qr, GT);
        const Eigen::VectorXd rTp = outsideColumns(F.qr, F.rT);
        const Eigen::VectorXd beta = GTp.colPivHouseholderQr().solve(rTp);
        const Eigen::VectorXd alpha = F.qr.solve(F.rT - GT * beta);
        eH = F.rH - F.JH * alpha - GH * beta;
      }
      sum += eH.squaredNorm();
      count += static_cast<int>(eH.size());
      if (held)
        for (size_t k = 0; k < F.held.size(); ++k) (*held)[F.held[k]] = eH[k];
    }
    return count ? std::sqrt(sum / count) : 0.0;
  }

  // Condition number of the column-scaled [J G].
  double condition(const Eigen::MatrixXd& G) const {
    Eigen::MatrixXd A(m_, J_.cols() + G.cols());
    A << J_, G;
    return scaledCondition(A);
  }

  // Lag-1 autocorrelation of a residual vector within set-ups.
  double autocorrelation(const Eigen::VectorXd& e) const {
    return lagOneAutocorrelation(std::vector<double>(e.data(), e.data() + e.size()), same_run_);
  }

  // Range of an axis coordinate over the readings.
  double span(int axis) const {
    double lo = INFINITY, hi = -INFINITY;
    for (const BallbarReading& rd : test_.readings) {
      lo = std::min(lo, rd.q[axis]);
      hi = std::max(hi, rd.q[axis]);
    }
    return hi - lo;
  }

 private:
  struct Fold {
    std::vector<int> train, held;
    Eigen::MatrixXd JT, JH;
    Eigen::VectorXd rT, rH;
    bool normal = false;                             // fitted by the downdated normal equations
    Eigen::LLT<Eigen::MatrixXd> llt;                 // of N - J_H^T J_H
    Eigen::VectorXd c;                               // J_T^T r_T
    Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr;  // else
  };
  bool normal_ = false;
  Eigen::MatrixXd N_;  // J^T J
  Eigen::VectorXd Jtr_;
  const MachineModel& model_;
  const BallbarTest& test_;
  Eigen::MatrixXd J_, Q_, Gc_;
  Eigen::VectorXd r_, scale_, r_perp_;
  std::vector<bool> same_run_;
  std::vector<Fold> folds_;
  int m_ = 0, n_ = 0;
  double rss0_ = 0.0;
};

// Minimises f on [a, b] (Brent's method, to half the double's digits: the precision a minimum
// can be located to).
template <class F>
double minimiseOn(F f, double a, double b) {
  std::uintmax_t iterations = 100;
  return boost::math::tools::brent_find_minima(f, a, b, std::numeric_limits<double>::digits / 2,
                                               iterations)
      .first;
}

// Finds the hyperparameter of spec (period or time constant) that minimises the RSS; returns the
// number of independent trials the search made.
int searchHyperparameter(const Scorer& sc, const BallbarTest& test, EffectSpec& spec) {
  double* h = hyperparameter(spec);
  if (!h) return 1;
  const HyperparameterRange range = traitsOf(spec.type).hyper;
  auto rssAt = [&](double value) {
    *h = value;
    return sc.rssSearch(sc.columns(spec));
  };
  // The grid's RSS values, a block of grid values at a time (Scorer::rssSearchBatch); columns(i,
  // G) writes the columns of grid value i (in order) into G.
  const int k = traitsOf(spec.type).size(spec);
  auto gridRss = [&](int count, const auto& columns) {
    constexpr int kBlock = 32;
    std::vector<double> v(static_cast<size_t>(count));
    Eigen::MatrixXd G(sc.readings(), static_cast<Eigen::Index>(kBlock) * k);
    for (int first = 0; first < count; first += kBlock) {
      const int n = std::min(kBlock, count - first);
      for (int b = 0; b < n; ++b) G.middleCols(b * k, k) = columns(first + b);
      sc.rssSearchBatch(G.leftCols(static_cast<Eigen::Index>(n) * k), k, v.data() + first);
    }
    return v;
  };
  if (range.frequency_grid) {
    // Uniform in frequency, five samples per cycle of phase change across the data's span.
    const double span = std::max(sc.span(spec.axis), range.min);
    const double f0 = 1.0 / range.max, f1 = 1.0 / range.min, df = 1.0 / (5.0 * span);
    double best_f = f0, best = INFINITY;
    const bool periodic = spec.type == EffectType::Periodic;
    std::optional<Scorer::FrequencyGrid> grid;
    if (periodic) grid.emplace(sc, spec, f0, df);
    int count = 0;
    while (f0 + count * df <= f1 + 1e-12) ++count;
    const std::vector<double> v = gridRss(count, [&](int i) -> Eigen::MatrixXd {
      if (!periodic) {
        *h = 1.0 / (f0 + i * df);
        return sc.columns(spec);
      }
      Eigen::MatrixXd c = grid->columns();  // grid values come in order: i = 0, 1, ...
      grid->advance();
      return c;
    });
    for (int i = 0; i < count; ++i)
      if (v[static_cast<size_t>(i)] < best) {
        best = v[static_cast<size_t>(i)];
        best_f = f0 + i * df;
      }
    const double f = minimiseOn([&](double x) { return rssAt(1.0 / x); }, std::max(f0, best_f - df),
                                std::min(f1, best_f + df));
    *h = 1.0 / f;
    // Independent trials: one per cycle of phase change, twice over for the refined peak.
    return std::max(1, static_cast<int>(std::lround(2.0 * (f1 - f0) * span)));
  }
  // Time constants: log-spaced grid, only where the test lasts long enough to see them.
  double t_end = 0;
  for (const BallbarReading& r : test.readings)
    if (std::isfinite(r.context.time_s)) t_end = std::max(t_end, r.context.time_s);
  const double lo = std::log(range.min),
               hi = std::log(std::max(range.min * 2, std::min(range.max, 2 * t_end)));
  const int n = 24;
  double best = INFINITY, best_x = lo;
  const std::vector<double> v = gridRss(n + 1, [&](int i) {
    *h = std::exp(lo + (hi - lo) * i / n);
    return sc.columns(spec);
  });
  for (int i = 0; i <= n; ++i)
    if (v[static_cast<size_t>(i)] < best) {
      best = v[static_cast<size_t>(i)];
      best_x = lo + (hi - lo) * i / n;
    }
  const double step = (hi - lo) / n;
  *h = std::exp(minimiseOn([&](double x) { return rssAt(std::exp(x)); },
                           std::max(lo, best_x - step), std::min(hi, best_x + step)));
  return 3;
}

// Standard uncertainty of a searched hyperparameter from the curvature of the RSS profile:
// u^2 = 2 s^2 / RSS''.
double hyperparameterUncertainty(const Scorer& sc, EffectSpec spec, double sigma2) {
  double* h = hyperparameter(spec);
  if (!h) return NAN;
  const double h0 = *h, dh = 1e-3 * h0;
  auto rssAt = [&](double v) {
    *h = v;
    return sc.rssWith(sc.columns(spec));
  };
  const double curvature = (rssAt(h0 + dh) - 2 * rssAt(h0) + rssAt(h0 - dh)) / (dh * dh);
  return curvature > 0 ? std::sqrt(2.0 * sigma2 / curvature) : INFINITY;
}

// Re-searches the hyperparameter (period, time constant) of each added effect with every other
// effect in the model: an effect added early was searched while later ones were still missing,
// and a time constant found beside an unexplained cyclic error is biased. For each, the model
// without that effect's contribution is linearised at the current solution, the search run
// again, and the nonlinear refit with the new value kept when it lowers the residual.
void refineHyperparameters(DiagnosisResult& res, const BallbarTest& test,
                           const std::vector<int>& unknowns, const std::vector<int>& fold_of) {
  for (AddedEffect& a : res.added) {
    if (!hyperparameter(a.spec) || a.parameters.empty()) continue;
    Machine without = res.machine;
    for (int p : a.parameters) without.params[p] = 0.0;
    CalibrationResult f0 = res.final_fit;
    f0.params = without.params;
    f0.identified.erase(std::remove_if(f0.identified.begin(), f0.identified.end(),
                                       [&](int p) {
                                         return std::find(a.parameters.begin(), a.parameters.end(),
                                                          p) != a.parameters.end();
                                       }),
                        f0.identified.end());
    const Scorer sc(without, test, f0, fold_of, res.folds);
    EffectSpec spec = a.spec;
    searchHyperparameter(sc, test, spec);
    const double h_old = hyperparameterValue(a.spec), h_new = hyperparameterValue(spec);
    if (!(std::abs(h_new - h_old) > 1e-3 * h_old)) continue;
    Machine trial = res.machine;
    const int effect = trial.model.blocks[trial.model.parameters[a.parameters[0]].block].effect;
    *hyperparameter(trial.model.effects[effect]) = h_new;
    const CalibrationResult fit = calibrate(trial.model, res.machine.params, test, unknowns);
    if (fit.status != CalibrationStatus::Converged || !fit.held.empty() ||
        !(fit.rms_residual < res.final_fit.rms_residual))
      continue;
    trial.params = fit.params;
    res.machine = trial;
    res.final_fit = fit;
    a.spec = spec;
    a.label = describeEffect(res.machine.model, spec);
    a.hyperparameter = h_new;
    a.hyperparameter_uncertainty =
        hyperparameterUncertainty(sc, spec, fit.residual_sigma * fit.residual_sigma);
  }
}

bool sameEffect(const EffectSpec& a, const EffectSpec& b) {
  return a.type == b.type && a.axis == b.axis && a.component == b.component &&
         a.varying == b.varying;
}

// The candidates of a round: every effect of the types asked for that the model lacks.
std::vector<CandidateScore> candidatesOf(const MachineModel& model, const DiagnosisOptions& opt,
                                         int round) {
  std::vector<CandidateScore> scores;
  for (const EffectTraits& t : effectTypes()) {
    if (!opt.types.empty() &&
        std::find(opt.types.begin(), opt.types.end(), t.type) == opt.types.end())
      continue;
    for (const EffectSpec& spec : t.candidates(model)) {
      auto present = [&](const EffectSpec& e) {
        return spec.type != EffectType::Chebyshev && sameEffect(e, spec);
      };
      if (std::any_of(model.effects.begin(), model.effects.end(), present)) continue;
      CandidateScore c;
      c.spec = spec;
      c.round = round;
      scores.push_back(c);
    }
  }
  return scores;
}

// Scores each candidate (hyperparameter search, RSS with and without it, F test on the
// effective readings, information criterion, cross-validated RMS); returns the number of
// independent tests made (for the Bonferroni factor).
int scoreCandidates(const Scorer& sc, const BallbarTest& test, const MachineModel& model,
                    double cv_base, std::vector<CandidateScore>& scores,
                    const std::function<void(int, int)>& progress) {
  int tests = 0;
  const int m = sc.readings(), n = sc.unknowns();
  for (size_t i = 0; i < scores.size(); ++i) {
    if (progress) progress(static_cast<int>(i), static_cast<int>(scores.size()));
    CandidateScore& c = scores[i];
    c.trials = searchHyperparameter(sc, test, c.spec);
    tests += c.trials;
    c.label = describeEffect(model, c.spec);
    const Eigen::MatrixXd G = sc.columns(c.spec);
    c.coefficients = static_cast<int>(G.cols());
    c.rss_before = sc.rss();
    if ((G.colwise().norm().array() < 1e-12).any()) {  // the readings do not see it at all
      c.rss_after = c.rss_before;
      c.verdict = CandidateVerdict::NotIdentifiable;
      continue;
    }
    Eigen::VectorXd e;
    c.rss_after = sc.rssWith(G, &e, &c.new_information);
    const double rho = std::clamp(sc.autocorrelation(e), 0.0, 0.95);
    c.effective_readings = m * (1.0 - rho) / (1.0 + rho);
    const int k = c.coefficients + (hyperparameter(c.spec) ? 1 : 0);
    const double dof = c.effective_readings - n - c.coefficients;
    // The cross-validated RMS only of the candidates it decides (qualify): O(folds m n k) each,
    // half of a whole diagnosis when every candidate had it. NaN: not computed.
    c.cv_rms_before = cv_base;
    c.cv_rms_after = std::numeric_limits<double>::quiet_NaN();
    if (dof <= 1 || !(c.rss_after > 0)) {
      c.verdict = CandidateVerdict::NotIdentifiable;
      continue;
    }
    c.f_statistic = ((c.rss_before - c.rss_after) / c.coefficients) / (c.rss_after / dof);
    c.p_value = fSurvival(c.f_statistic, c.coefficients, dof);
    c.delta_ic = c.effective_readings * std::log(c.rss_before / c.rss_after) -
                 k * std::log(c.effective_readings);
  }
  if (progress) progress(static_cast<int>(scores.size()), static_cast<int>(scores.size()));
  return tests;
}

// The verdict of each scored candidate; returns the qualified ones, best (largest information
// gain) first.
std::vector<size_t> qualify(const Scorer& sc, const DiagnosisOptions& opt,
                            const std::vector<EffectSpec>& rejected, int tests,
                            std::vector<CandidateScore>& scores) {
  std::vector<size_t> qualified;
  for (size_t i = 0; i < scores.size(); ++i) {
    CandidateScore& c = scores[i];
    if (c.verdict == CandidateVerdict::NotIdentifiable) continue;
    c.p_value = std::min(1.0, c.p_value * std::max(1, tests));
    if (c.new_information < opt.min_new_information) {
      c.verdict = CandidateVerdict::Confounded;
    } else if (c.p_value >= opt.alpha || c.delta_ic <= 0) {
      c.verdict = CandidateVerdict::NotSignificant;
    } else if (const Eigen::MatrixXd G = sc.columns(c.spec);
               !((c.cv_rms_after = sc.crossValidatedRms(&G)) < c.cv_rms_before)) {
      c.verdict = CandidateVerdict::NoPredictiveGain;
    } else {
      c.condition = sc.condition(G);
      if (c.condition > opt.max_condition ||
          std::any_of(rejected.begin(), rejected.end(),
                      [&](const EffectSpec& r) { return sameEffect(r, c.spec); })) {
        c.verdict = CandidateVerdict::NotIdentifiable;
      } else {
        c.verdict = CandidateVerdict::Outscored;
        qualified.push_back(i);
      }
    }
  }
  std::sort(qualified.begin(), qualified.end(),
            [&](size_t a, size_t b) { return scores[a].delta_ic > scores[b].delta_ic; });
  return qualified;
}

// Candidates the readings cannot tell from scores[i]: same type and size, columns (at its
// hyperparameter) spanning the same space to 0.1 % (the machine's own errors tilt the frames by
// micro-radians, so exact equivalents differ at that level).
std::vector<size_t> equivalentsOf(const Scorer& sc, const std::vector<CandidateScore>& scores,
                                  size_t i) {
  std::vector<size_t> out;
  const CandidateScore& c = scores[i];
  const Eigen::MatrixXd G = sc.columns(c.spec);
  const Eigen::HouseholderQR<Eigen::MatrixXd> qa(G);
  const Eigen::MatrixXd Qa = qa.householderQ() * Eigen::MatrixXd::Identity(G.rows(), G.cols());
  for (size_t j = 0; j < scores.size(); ++j) {
    const CandidateScore& o = scores[j];
    if (j == i || o.spec.type != c.spec.type || o.coefficients != c.coefficients) continue;
    EffectSpec os = o.spec;
    if (double* h = hyperparameter(os)) *h = hyperparameterValue(c.spec);
    const Eigen::MatrixXd G2 = sc.columns(os);
    if (G2.cols() != G.cols() || (G2.colwise().norm().array() < 1e-12).any()) continue;
    bool same = true;
    for (Eigen::Index k = 0; k < G2.cols() && same; ++k) {
      const Eigen::VectorXd g = G2.col(k) / G2.col(k).norm();
      same = (g - Qa * (Qa.transpose() * g)).norm() < 1e-3;
    }
    if (same) out.push_back(j);
  }
  return out;
}

// The parameters of the fit (or ball coordinates) whose columns the added effect's resemble
// (|cosine| >= 0.5), at most 4, with their values before and after the refit.
std::vector<AddedEffect::Confounding> confoundings(const Scorer& sc, const MachineModel& aug_model,
                                                   const BallbarTest& test, const EffectSpec& spec,
                                                   const CalibrationResult& before,
                                                   const CalibrationResult& fit) {
  std::vector<AddedEffect::Confounding> out;
  const int np = static_cast<int>(before.identified.size());
  const auto similar = sc.similarColumns(sc.columns(spec), 0.5);
  for (size_t k = 0; k < similar.size() && k < 4; ++k) {
    AddedEffect::Confounding cf;
    cf.cosine = similar[k].second;
    const int j = similar[k].first;
    if (j < np) {
      const int p = before.identified[j];
      cf.name = aug_model.parameters[p].iso_code;
      cf.angular = aug_model.parameters[p].angular;
      cf.before = before.params[p];
      cf.after = fit.params[p];
    } else {
      const int b = (j - np) / 6, k3 = (j - np) % 6;
      cf.name = "ball " + std::to_string(test.setups[b].id) + (k3 < 3 ? " table " : " tool ") +
                "xyz"[k3 % 3];
      const BallErrors& e0 = before.ball_errors[b];
      const BallErrors& e1 = fit.ball_errors[b];
      cf.before = (k3 < 3 ? e0.table_w : e0.tool_t)[k3 % 3];
      cf.after = (k3 < 3 ? e1.table_w : e1.tool_t)[k3 % 3];
    }
    out.push_back(cf);
  }
  return out;
}

// Adds the qualified candidate scores[qi] (or an equivalent along an axis's own motion) when
// the nonlinear refit sees it, converges and lowers the residual; otherwise records why not.
bool tryToAdd(const Scorer& sc, const BallbarTest& test, std::vector<CandidateScore>& scores,
              size_t qi, std::vector<int>& unknowns, std::vector<EffectSpec>& rejected,
              DiagnosisResult& res) {
  auto principal = [&](const EffectSpec& e) {
    return e.axis >= 0 && e.component == principalComponent(res.machine.model.axes[e.axis]);
  };
  // Among equivalent names, the one along an axis's own motion (the drift of Z along z
  // rather than the table's along z): the same fit, the likelier cause.
  size_t pick = qi;
  std::vector<size_t> equivalent = equivalentsOf(sc, scores, qi);
  if (!principal(scores[qi].spec))
    for (size_t e : equivalent)
      if (principal(scores[e].spec) && scores[e].verdict == CandidateVerdict::Outscored) {
        pick = e;
        break;
      }
  if (pick != qi) equivalent.push_back(qi);
  CandidateScore& c = scores[pick];
  Machine aug = res.machine;
  const int first = aug.model.parameterCount();
  aug.model.addEffect(c.spec);
  aug.params.conservativeResize(aug.model.parameterCount());
  aug.params.tail(aug.model.parameterCount() - first).setZero();
  std::vector<int> aug_unknowns = unknowns;
  AddedEffect a;
  a.spec = c.spec;
  a.label = c.label;
  for (int p = first; p < aug.model.parameterCount(); ++p) {
    aug_unknowns.push_back(p);
    a.parameters.push_back(p);
  }
  const CalibrationResult fit = calibrate(aug.model, aug.params, test, aug_unknowns);
  const bool seen = fit.status != CalibrationStatus::Unobservable &&
                    fit.status != CalibrationStatus::NoData &&
                    std::none_of(a.parameters.begin(), a.parameters.end(), [&](int p) {
                      return std::find(fit.held.begin(), fit.held.end(), p) != fit.held.end();
                    });
  if (!seen) {
    c.verdict = CandidateVerdict::NotIdentifiable;
    c.reason = "the refit cannot see its coefficients";
    rejected.push_back(c.spec);
    return false;
  }
  if (fit.status != CalibrationStatus::Converged || !fit.held.empty()) {
    c.verdict = CandidateVerdict::RefitFailed;
    c.reason =
        fit.status != CalibrationStatus::Converged
            ? "the refit did not converge in " + std::to_string(fit.iterations) + " iterations"
            : "the refit could not see " + std::to_string(fit.held.size()) +
                  " parameter(s) the base fit identified";
    rejected.push_back(c.spec);
    return false;
  }
  if (!(fit.rms_residual < res.final_fit.rms_residual)) {
    c.verdict = CandidateVerdict::RefitFailed;
    c.reason = "the refit did not lower the residual";
    rejected.push_back(c.spec);
    return false;
  }
  c.verdict = CandidateVerdict::Added;
  a.values.resize(a.parameters.size());
  a.uncertainty.resize(a.parameters.size());
  for (size_t j = 0; j < a.parameters.size(); ++j) {
    const int p = a.parameters[j];
    a.values[j] = fit.params[p];
    const auto it = std::find(fit.identified.begin(), fit.identified.end(), p);
    a.uncertainty[j] = fit.uncertainty[it - fit.identified.begin()];
  }
  // A value no machine has (a drift of 100 urad/h): the effect stands in for something else.
  const double limit = plausibleCoefficientLimit(c.spec);
  for (size_t j = 0; j < a.parameters.size(); ++j)
    if (std::abs(a.values[j]) - 2.0 * a.uncertainty[j] > limit) {
      const bool angular = c.spec.component >= 3;
      const double k = angular ? 1e6 : 1e3;
      char why[200];
      std::snprintf(why, sizeof why, "fitted %.3g +- %.2g %s%s, beyond the plausible %.3g",
                    a.values[j] * k, a.uncertainty[j] * k, angular ? "urad" : "um",
                    c.spec.type == EffectType::Drift ? "/h" : "", limit * k);
      c.verdict = CandidateVerdict::Implausible;
      c.reason = why;
      rejected.push_back(c.spec);
      return false;
    }
  a.hyperparameter = hyperparameterValue(c.spec);
  a.hyperparameter_uncertainty =
      hyperparameterUncertainty(sc, c.spec, fit.residual_sigma * fit.residual_sigma);
  a.new_information = c.new_information;
  for (size_t e : equivalent)
    if (e != pick) a.equivalent.push_back(describeEffect(res.machine.model, scores[e].spec));
  a.confounded_with = confoundings(sc, aug.model, test, c.spec, res.final_fit, fit);
  aug.params = fit.params;
  res.machine = aug;
  res.final_fit = fit;
  unknowns = aug_unknowns;
  res.added.push_back(a);
  return true;
}

// Values and uncertainties of the added effects from the final fit (later rounds refit the
// earlier effects).
void finalValues(DiagnosisResult& res) {
  for (AddedEffect& a : res.added) {
    const CalibrationResult& fit = res.final_fit;
    for (size_t j = 0; j < a.parameters.size(); ++j) {
      const int p = a.parameters[j];
      a.values[j] = fit.params[p];
      const auto it = std::find(fit.identified.begin(), fit.identified.end(), p);
      a.uncertainty[j] =
          it == fit.identified.end() ? NAN : fit.uncertainty[it - fit.identified.begin()];
    }
  }
}

// The final check: the augmented model must predict readings it was not fitted to at least as
// well as the base model (the held-out readings when given, else cross-validation); otherwise
// the effects are withdrawn.
void finalCheck(const Machine& machine, const DiagnosisOptions& opt, DiagnosisResult& res) {
  double gain = 0,
         gain_se = 0;  // held-out: mean of r_before^2 - r_after^2 and its standard error (mm^2)
  if (opt.heldout && !opt.heldout->readings.empty()) {
    const Eigen::VectorXd r0 =
        ballbarResiduals(ForwardKinematics(machine.model, res.base_fit.params), *opt.heldout,
                         res.base_fit.ball_errors);
    const Eigen::VectorXd r1 =
        ballbarResiduals(ForwardKinematics(res.machine.model, res.final_fit.params), *opt.heldout,
                         res.final_fit.ball_errors);
    res.heldout_before = residualStats(r0);
    res.heldout_after = residualStats(r1);
    const Eigen::ArrayXd d = r0.array().square() - r1.array().square();
    const double n = static_cast<double>(d.size());
    gain = d.mean();
    gain_se = n > 1 ? std::sqrt((d - gain).square().sum() / (n - 1) / n) : INFINITY;
    res.heldout_gain_mm2 = gain;
    res.heldout_gain_se_mm2 = gain_se;
  }
  if (!res.added.empty()) {
    const bool with_heldout = res.heldout_before.readings > 0;
    const double before = with_heldout ? res.heldout_before.rms : res.cv_rms_before;
    const double after = with_heldout ? res.heldout_after.rms : res.cv_rms_after;
    // The gain must exceed twice its standard error to count: on held-out readings, else over
    // the cross-validation's folds (each fold's fit refits the effects' own parameters).
    if (!with_heldout) {
      gain = res.cv_gain_mm2;
      gain_se = res.cv_gain_se_mm2;
    }
    const bool unconfirmed =
        after <= before && (with_heldout || std::isfinite(gain_se)) && !(gain > 2.0 * gain_se);
    if (after > before || unconfirmed) {
      char why[300];
      if (unconfirmed)
        std::snprintf(why, sizeof why,
                      "the %s gain (RMS %.3f -> %.3f um; mean squared gain %.3g +- %.2g "
                      "um^2) is within twice its uncertainty: not confirmed",
                      with_heldout ? "held-out" : "cross-validated", mmToUm(before), mmToUm(after),
                      gain * 1e6, gain_se * 1e6);
      else
        std::snprintf(why, sizeof why,
                      "the augmented model predicted the %s readings worse than the base model "
                      "(RMS %.3f um against %.3f um)",
                      with_heldout ? "held-out" : "cross-validated", mmToUm(after), mmToUm(before));
      res.withdrawn_reason = why;
      res.withdrawn = res.added;
      res.added.clear();
      for (CandidateScore& c : res.candidates)
        if (c.verdict == CandidateVerdict::Added) {
          c.verdict = CandidateVerdict::NoPredictiveGain;
          c.reason = "withdrawn by the final check";
        }
      res.machine = machine;
      res.machine.params = res.base_fit.params;
      res.final_fit = res.base_fit;
      res.cv_rms_after = res.cv_rms_before;
      res.heldout_after = res.heldout_before;
    }
  }
}

// The measurement that would separate what a finding points at.
std::string suggestionFor(const MachineModel& model, const std::string& variable) {
  if (variable.size() > 10 && variable.compare(variable.size() - 10, 10, " direction") == 0)
    return "measure the same poses approached from both directions of " +
           variable.substr(0, variable.size() - 10) + " (a bidirectional run)";
  if (variable == "time")
    return "return to the reference pose more often (every 4 readings) to map the change with time";
  if (variable == "set-up")
    return "a further set-up, or the balls' positions measured on a CMM, separates the balls from "
           "the machine";
  for (const Axis& ax : model.axes)
    if (ax.name == variable)
      return ax.isRotary() ? "a run turning " + ax.name +
                                 " alone, with the table ball at two radii and two "
                                 "heights, separates its tilts from its offsets"
                           : "a run along " + ax.name +
                                 " alone, with the tool ball at two lengths, separates "
                                 "its angular errors from its straightness";
  return "a set-up with another tool-ball length separates tilts from offsets";
}

// Where the final residual is largest: the reading, its set-up and pose, and the strongest
// structure the analysis found (significant or not).
std::string whereLargest(const MachineModel& model, const BallbarTest& test,
                         const DiagnosisResult& res) {
  const Eigen::VectorXd& r = res.final_fit.residuals;
  if (r.size() == 0 || r.size() != static_cast<Eigen::Index>(test.readings.size())) return "";
  Eigen::Index i = 0;
  r.cwiseAbs().maxCoeff(&i);
  const BallbarReading& rd = test.readings[i];
  std::string pose;
  char buf[160];
  for (size_t a = 0; a < model.axes.size(); ++a) {
    const Axis& ax = model.axes[a];
    std::snprintf(buf, sizeof buf, "%s%s %.1f%s", pose.empty() ? "" : ", ", ax.name.c_str(),
                  ax.isRotary() ? radToDeg(rd.q[a]) : rd.q[a], ax.isRotary() ? " deg" : "");
    pose += buf;
  }
  std::snprintf(buf, sizeof buf,
                "largest residual %+.3f um at reading %d (line %d, set-up %d: ", mmToUm(r[i]),
                static_cast<int>(i) + 1, rd.line, test.setups[rd.setup].id);
  std::string out = buf + pose + ")";
  const auto& f = res.analysis_after.findings;
  if (!f.empty()) {
    std::snprintf(buf, sizeof buf,
                  "; strongest structure: %s (%s, %.0f %% of the variance, p %.2g)",
                  f.front().variable.c_str(), f.front().test.c_str(), 100.0 * f.front().strength,
                  f.front().p_value);
    out += buf;
  }
  return out;
}

const CandidateScore* firstImplausible(const DiagnosisResult& res) {
  for (const CandidateScore& c : res.candidates)
    if (c.verdict == CandidateVerdict::Implausible) return &c;
  return nullptr;
}

// One verdict from the selection, the final check, the structure left and the lack of fit.
void decideVerdict(DiagnosisResult& res, const MachineModel& model, const BallbarTest& test,
                   double alpha) {
  const LackOfFit& l = res.lack_of_fit_after;
  const bool lacks = l.tested && l.p_value < alpha;
  char lof[300] = "";
  if (l.tested)
    std::snprintf(
        lof, sizeof lof,
        "the fit's residual sigma %.3f um against the repeatability %.3f um of %d repeated poses "
        "(F %.2f, p %.2g)",
        mmToUm(l.s_fit), mmToUm(l.s_pure), l.poses, l.f, l.p_value);
  char missing[200] = "";
  if (lacks)
    std::snprintf(missing, sizeof missing, "the model misses %.3f um RMS beyond the repeatability",
                  mmToUm(l.missing_rms));
  const std::string n_added =
      std::to_string(res.added.size()) + (res.added.size() == 1 ? " effect" : " effects");
  if (!res.withdrawn.empty()) {
    res.verdict =
        lacks || res.unexplained ? DiagnosisVerdict::Incomplete : DiagnosisVerdict::NothingAdded;
    res.verdict_text = "nothing added (" + res.withdrawn_reason + ")";
    if (lacks) res.verdict_text += "; " + std::string(missing) + ": " + lof;
  } else if (lacks || res.unexplained) {
    res.verdict = DiagnosisVerdict::Incomplete;
    res.verdict_text =
        (res.added.empty()
             ? std::string("incomplete: no effect of the library explains what is missing")
             : "incomplete: " + n_added + " added, and something still missing");
    if (lacks) res.verdict_text += "; " + std::string(missing) + ": " + lof;
    if (res.unexplained) {
      const ResidualFinding& u = res.unexplained_finding;
      char what[200];
      if (u.test == "periodogram" && u.order)
        std::snprintf(
            what, sizeof what,
            "; the residual still follows %s (harmonic order %.0f, %.0f %% of its variance)",
            u.variable.c_str(), u.period, 100.0 * u.strength);
      else if (u.test == "periodogram")
        std::snprintf(
            what, sizeof what,
            "; the residual still follows %s (period %.2f +- %.2f mm, %.0f %% of its variance)",
            u.variable.c_str(), u.period, u.period_uncertainty, 100.0 * u.strength);
      else
        std::snprintf(what, sizeof what,
                      "; the residual still follows %s (%s, %.0f %% of its variance)",
                      u.variable.c_str(), u.test.c_str(), 100.0 * u.strength);
      res.verdict_text += what;
    }
  } else if (const CandidateScore* odd = firstImplausible(res); odd && res.added.empty()) {
    // The best explanation has a value no machine has: it stands in for something else.
    res.verdict = DiagnosisVerdict::Incomplete;
    res.verdict_text = "incomplete: the residual is best explained by " + odd->label +
                       " with a value no machine has (" + odd->reason +
                       "): something the library lacks";
    if (l.tested) res.verdict_text += "; " + std::string(lof);
  } else if (!res.added.empty()) {
    res.verdict = DiagnosisVerdict::EffectsAdded;
    res.verdict_text = n_added + " added" +
                       (l.tested ? "; no significant lack of fit left: " + std::string(lof)
                                 : "; adequacy not tested: no pose is measured twice");
  } else {
    res.verdict = DiagnosisVerdict::NothingMissing;
    res.verdict_text =
        l.tested
            ? "nothing missing: no effect added, no structure left, no significant lack of fit: " +
                  std::string(lof)
            : "nothing found: no effect added and no structure left, but adequacy could not be "
              "tested (no pose is measured twice: plan-ballbar's plans return to a reference pose)";
  }
  if (res.verdict == DiagnosisVerdict::Incomplete) {
    res.where = whereLargest(model, test, res);
    const auto& f = res.analysis_after.findings;
    res.suggestion =
        suggestionFor(model, res.unexplained ? res.unexplained_finding.variable
                                             : (f.empty() ? std::string() : f.front().variable));
  }
  res.message = res.verdict_text;
}

}  // namespace

const char* verdictName(DiagnosisVerdict v) {
  switch (v) {
    case DiagnosisVerdict::EffectsAdded:
      return "effects added";
    case DiagnosisVerdict::NothingMissing:
      return "nothing missing";
    case DiagnosisVerdict::Incomplete:
      return "incomplete";
    case DiagnosisVerdict::NothingAdded:
      return "nothing added";
  }
  return "";
}

DiagnosisResult diagnose(const Machine& machine, const BallbarTest& test,
                         const DiagnosisOptions& opt,
                         const std::function<void(int, int)>& progress) {
  const auto start = std::chrono::steady_clock::now();
  DiagnosisResult res;
  res.machine = machine;
  std::vector<int> unknowns =
      opt.base_unknowns.empty() ? defaultCalibrationUnknowns(machine.model) : opt.base_unknowns;
  res.base_fit = calibrate(machine.model, machine.params, test, unknowns);
  if (res.base_fit.status == CalibrationStatus::Unobservable ||
      res.base_fit.status == CalibrationStatus::NoData) {
    res.message = res.base_fit.message;
    return res;
  }
  res.final_fit = res.base_fit;
  res.machine.params = res.base_fit.params;
  // Parameters the base fit could not see stay held at their prior values in every later fit:
  // the refits identify what the base fit identified, plus the effects.
  unknowns = res.base_fit.identified;
  const std::vector<int> fold_of = contiguousFolds(test, opt.blocks_per_setup, &res.folds);
  std::vector<EffectSpec> rejected;  // found not identifiable by the nonlinear refit
  // Each reading's cross-validated residual: the base model's, and the current model's.
  Eigen::VectorXd cv_before, cv_after;

  for (int round = 1; round <= opt.max_effects + 1; ++round) {
    const Scorer sc(res.machine, test, res.final_fit, fold_of, res.folds);
    const double cv_base = sc.crossValidatedRms(nullptr, &cv_after);
    if (round == 1) {
      res.cv_rms_before = cv_base;
      cv_before = cv_after;
    }
    res.cv_rms_after = cv_base;
    if (round > opt.max_effects) break;
    if (round > 1 && opt.max_seconds > 0.0 &&
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() >
            opt.max_seconds) {
      res.budget_spent = true;
      break;
    }
    res.rounds_done = round;
    std::vector<CandidateScore> scores = candidatesOf(res.machine.model, opt, round);
    const int tests = scoreCandidates(sc, test, res.machine.model, cv_base, scores, progress);
    bool added = false;
    for (size_t qi : qualify(sc, opt, rejected, tests, scores))
      if ((added = tryToAdd(sc, test, scores, qi, unknowns, rejected, res))) break;
    res.candidates.insert(res.candidates.end(), scores.begin(), scores.end());
    if (!added) break;
    if (res.added.size() >= 2) refineHyperparameters(res, test, unknowns, fold_of);
  }
  finalValues(res);
  {
    // The cross-validated gain per reading and its standard error over the folds (the blocks
    // are contiguous runs, so their readings share slow errors: the blocks' standard error).
    std::vector<double> d(cv_before.size());
    for (Eigen::Index i = 0; i < cv_before.size(); ++i)
      d[i] = cv_before[i] * cv_before[i] - cv_after[i] * cv_after[i];
    res.cv_gain_mm2 = blockMean(d, fold_of, res.folds, &res.cv_gain_se_mm2);
  }
  finalCheck(machine, opt, res);
  res.rms_before = res.base_fit.rms_residual;
  res.rms_after = res.final_fit.rms_residual;
  res.analysis_before = analyseResiduals(machine.model, test, res.base_fit.residuals);
  res.analysis_after = analyseResiduals(res.machine.model, test, res.final_fit.residuals);
  if (!res.analysis_after.follows.empty() && !res.analysis_after.findings.empty()) {
    res.unexplained = true;
    res.unexplained_finding = res.analysis_after.findings.front();
  }
  const int fitted_before = res.base_fit.unknowns, fitted_after = res.final_fit.unknowns;
  res.lack_of_fit_before = lackOfFit(test, res.base_fit.residuals, fitted_before);
  res.lack_of_fit_after = lackOfFit(test, res.final_fit.residuals, fitted_after);
  decideVerdict(res, machine.model, test, opt.alpha);
  res.ok = true;
  return res;
}

}  // namespace tolver
