#include "core/numerics/statistics.h"

#include <algorithm>
#include <boost/math/distributions/chi_squared.hpp>
#include <boost/math/distributions/fisher_f.hpp>
#include <boost/math/special_functions/beta.hpp>
#include <cmath>
#include <cstring>
#include <limits>

namespace tolver {

StreamQuantiles::StreamQuantiles() : exponent_(2048) {}
StreamQuantiles::~StreamQuantiles() = default;
StreamQuantiles::StreamQuantiles(StreamQuantiles&&) noexcept = default;
StreamQuantiles& StreamQuantiles::operator=(StreamQuantiles&&) noexcept = default;

void StreamQuantiles::add(double v) {
  ++count_;
  if (!(v > 0.0)) {  // zero, negative, NaN
    ++zeros_;
    return;
  }
  if (std::isinf(v)) v = std::numeric_limits<double>::max();
  std::uint64_t bits;
  std::memcpy(&bits, &v, sizeof bits);
  const size_t e = static_cast<size_t>(bits >> 52) & 2047;
  const size_t bin = static_cast<size_t>(bits >> 36) & 0xFFFF;
  std::unique_ptr<std::uint32_t[]>& bins = exponent_[e];
  if (!bins) bins = std::make_unique<std::uint32_t[]>(65536);  // zeroed
  ++bins[bin];
}

double StreamQuantiles::ranked(size_t k) const {
  if (k < zeros_) return 0.0;
  size_t seen = zeros_;
  for (size_t e = 0; e < exponent_.size(); ++e) {
    if (!exponent_[e]) continue;
    for (size_t b = 0; b < 65536; ++b) {
      seen += exponent_[e][b];
      if (seen <= k) continue;
      // The bin's midpoint: its lower edge with the next mantissa bit set.
      const std::uint64_t bits = (static_cast<std::uint64_t>(e) << 52) |
                                 (static_cast<std::uint64_t>(b) << 36) | (std::uint64_t{1} << 35);
      double v;
      std::memcpy(&v, &bits, sizeof v);
      return v;
    }
  }
  return 0.0;
}

namespace {

// Domain and overflow errors give NaN or infinity instead of exceptions; the callers decide.
using QuietPolicy = boost::math::policies::policy<
    boost::math::policies::domain_error<boost::math::policies::ignore_error>,
    boost::math::policies::overflow_error<boost::math::policies::ignore_error>,
    boost::math::policies::evaluation_error<boost::math::policies::ignore_error>>;

}  // namespace

double incompleteBeta(double a, double b, double x) {
  if (x <= 0.0) return 0.0;
  if (x >= 1.0) return 1.0;
  return boost::math::ibeta(a, b, x, QuietPolicy());
}

double fSurvival(double f, double d1, double d2) {
  if (!(f > 0.0) || !(d1 > 0.0) || !(d2 > 0.0)) return 1.0;
  if (std::isinf(f)) return 0.0;
  const boost::math::fisher_f_distribution<double, QuietPolicy> dist(d1, d2);
  return boost::math::cdf(boost::math::complement(dist, f));
}

double normalSurvival(double z) { return 0.5 * std::erfc(z / std::sqrt(2.0)); }

double chiSquareQuantile(double p, double dof) {
  const boost::math::chi_squared_distribution<double, QuietPolicy> dist(dof);
  return boost::math::quantile(dist, p);
}

double gaussianRadiusQuantile(const double* eigenvalues, int n, double p) {
  double s1 = 0.0, s2 = 0.0;
  for (int k = 0; k < n; ++k) {
    const double l = std::max(0.0, eigenvalues[k]);
    s1 += l;
    s2 += l * l;
  }
  if (!(s1 > 0.0)) return 0.0;
  return std::sqrt(s2 / s1 * chiSquareQuantile(p, s1 * s1 / s2));
}

double blockMean(const std::vector<double>& x, const std::vector<int>& block, int blocks,
                 double* standard_error) {
  std::vector<double> sum(std::max(0, blocks), 0.0);
  std::vector<int> count(sum.size(), 0);
  double total = 0.0;
  int n = 0;
  for (size_t i = 0; i < x.size() && i < block.size(); ++i) {
    if (block[i] < 0 || block[i] >= blocks) continue;
    sum[block[i]] += x[i];
    ++count[block[i]];
    total += x[i];
    ++n;
  }
  const double mean = n ? total / n : 0.0;
  int used = 0;
  double ss = 0.0;
  for (size_t b = 0; b < sum.size(); ++b)
    if (count[b] > 0) {
      ++used;
      ss += (sum[b] - mean * count[b]) * (sum[b] - mean * count[b]);
    }
  if (standard_error)
    *standard_error = used > 1 ? std::sqrt(used / (used - 1.0) * ss) / n : INFINITY;
  return mean;
}

std::vector<double> lombScargle(const std::vector<double>& t, const std::vector<double>& y,
                                const std::vector<double>& omega) {
  const size_t n = std::min(t.size(), y.size());
  std::vector<double> power(omega.size(), 0.0);
  if (n < 3) return power;
  double mean = 0.0;
  for (size_t i = 0; i < n; ++i) mean += y[i];
  mean /= static_cast<double>(n);
  double var = 0.0;
  for (size_t i = 0; i < n; ++i) var += (y[i] - mean) * (y[i] - mean);
  var /= static_cast<double>(n - 1);
  if (!(var > 0.0)) return power;
  // c_i = cos(w t_i), s_i = sin(w t_i) at each frequency: exactly every kSeed frequencies, and
  // between, where the grid's step repeats (to 1e-9 of itself: a grid made by adding a step), by
  // the rotation through that step (one complex product per sample instead of four
  // trigonometric calls). From them, one pass gives the sums the formula needs: with
  // C = cos(w tau), S = sin(w tau), cos(w (t - tau)) = c C + s S, sin(w (t - tau)) = s C - c S,
  // and tan(2 w tau) = 2 sum(cs) / sum(c^2 - s^2).
  constexpr size_t kSeed = 32;
  std::vector<double> c(n), sn(n), rc(n), rs(n);
  double rotation = 0.0;  // the step rc, rs turn by
  auto near = [](double a, double b) { return std::abs(a - b) <= 1e-9 * std::abs(b); };
  for (size_t f = 0; f < omega.size(); ++f) {
    const double w = omega[f];
    if (f % kSeed != 0 && rotation != 0.0 && near(w - omega[f - 1], rotation)) {
      for (size_t i = 0; i < n; ++i) {
        const double ci = c[i] * rc[i] - sn[i] * rs[i];
        sn[i] = sn[i] * rc[i] + c[i] * rs[i];
        c[i] = ci;
      }
    } else {
      for (size_t i = 0; i < n; ++i) {
        c[i] = std::cos(w * t[i]);
        sn[i] = std::sin(w * t[i]);
      }
      const double next = f + 1 < omega.size() ? omega[f + 1] - w : 0.0;
      if (next != 0.0 && !near(next, rotation)) {
        rotation = next;
        for (size_t i = 0; i < n; ++i) {
          rc[i] = std::cos(rotation * t[i]);
          rs[i] = std::sin(rotation * t[i]);
        }
      }
    }
    double dc = 0.0, ds = 0.0, scc = 0.0, sss = 0.0, scs = 0.0;
    for (size_t i = 0; i < n; ++i) {
      const double d = y[i] - mean;
      dc += d * c[i];
      ds += d * sn[i];
      scc += c[i] * c[i];
      sss += sn[i] * sn[i];
      scs += c[i] * sn[i];
    }
    const double two_wtau = std::atan2(2.0 * scs, scc - sss);
    const double C = std::cos(0.5 * two_wtau), S = std::sin(0.5 * two_wtau);
    const double yc = C * dc + S * ds, ys = C * ds - S * dc;
    const double cc = C * C * scc + 2.0 * C * S * scs + S * S * sss;
    const double ss = S * S * scc - 2.0 * C * S * scs + C * C * sss;
    double p = 0.0;
    if (cc > 1e-12 * static_cast<double>(n)) p += yc * yc / cc;
    if (ss > 1e-12 * static_cast<double>(n)) p += ys * ys / ss;
    power[f] = 0.5 * p / var;
  }
  return power;
}

double periodogramFalseAlarm(double power, double independent) {
  // 1 - (1 - e^-P)^M, computed without cancellation for small e^-P.
  const double e = std::exp(-power);
  return -std::expm1(std::max(1.0, independent) * std::log1p(-std::min(e, 1.0 - 1e-16)));
}

RunsTest runsTest(const std::vector<double>& x) {
  RunsTest r;
  int last = 0;
  for (double v : x) {
    const int s = v > 0 ? 1 : (v < 0 ? -1 : 0);
    if (s == 0) continue;
    (s > 0 ? r.positive : r.negative)++;
    if (s != last) ++r.runs;
    last = s;
  }
  const double n1 = r.positive, n2 = r.negative, n = n1 + n2;
  if (n1 < 1 || n2 < 1) return r;
  const double mu = 2.0 * n1 * n2 / n + 1.0;
  const double var = 2.0 * n1 * n2 * (2.0 * n1 * n2 - n) / (n * n * (n - 1.0));
  if (!(var > 0.0)) return r;
  r.z = (r.runs - mu) / std::sqrt(var);
  r.p_value = std::min(1.0, 2.0 * normalSurvival(std::abs(r.z)));
  return r;
}

double lagOneAutocorrelation(const std::vector<double>& x, const std::vector<bool>& same_run) {
  double num = 0.0, den = 0.0, mean = 0.0;
  for (double v : x) mean += v;
  if (x.empty()) return 0.0;
  mean /= static_cast<double>(x.size());
  for (double v : x) den += (v - mean) * (v - mean);
  for (size_t i = 1; i < x.size(); ++i)
    if (same_run[i]) num += (x[i] - mean) * (x[i - 1] - mean);
  return den > 0.0 ? num / den : 0.0;
}

}  // namespace tolver
