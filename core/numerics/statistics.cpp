#include "core/numerics/statistics.h"

#include <algorithm>
#include <cmath>

namespace tolver {
namespace {

// Continued fraction of the incomplete beta (modified Lentz), valid for x < (a + 1) / (a + b + 2).
double betaFraction(double a, double b, double x) {
  const double tiny = 1e-300;
  double c = 1.0, d = 1.0 - (a + b) * x / (a + 1.0);
  if (std::abs(d) < tiny) d = tiny;
  d = 1.0 / d;
  double h = d;
  for (int m = 1; m <= 500; ++m) {
    const double m2 = 2.0 * m;
    double aa = m * (b - m) * x / ((a + m2 - 1.0) * (a + m2));
    d = 1.0 + aa * d;
    if (std::abs(d) < tiny) d = tiny;
    c = 1.0 + aa / c;
    if (std::abs(c) < tiny) c = tiny;
    d = 1.0 / d;
    h *= d * c;
    aa = -(a + m) * (a + b + m) * x / ((a + m2) * (a + m2 + 1.0));
    d = 1.0 + aa * d;
    if (std::abs(d) < tiny) d = tiny;
    c = 1.0 + aa / c;
    if (std::abs(c) < tiny) c = tiny;
    d = 1.0 / d;
    const double del = d * c;
    h *= del;
    if (std::abs(del - 1.0) < 1e-15) break;
  }
  return h;
}

}  // namespace

double incompleteBeta(double a, double b, double x) {
  if (x <= 0.0) return 0.0;
  if (x >= 1.0) return 1.0;
  const double ln_front = std::lgamma(a + b) - std::lgamma(a) - std::lgamma(b) + a * std::log(x) +
                          b * std::log1p(-x);
  const double front = std::exp(ln_front);
  if (x < (a + 1.0) / (a + b + 2.0)) return front * betaFraction(a, b, x) / a;
  return 1.0 - front * betaFraction(b, a, 1.0 - x) / b;
}

double fSurvival(double f, double d1, double d2) {
  if (!(f > 0.0)) return 1.0;
  if (std::isinf(f)) return 0.0;
  return incompleteBeta(0.5 * d2, 0.5 * d1, d2 / (d2 + d1 * f));
}

double normalSurvival(double z) { return 0.5 * std::erfc(z / std::sqrt(2.0)); }

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
  for (size_t f = 0; f < omega.size(); ++f) {
    const double w = omega[f];
    double s2 = 0.0, c2 = 0.0;
    for (size_t i = 0; i < n; ++i) {
      s2 += std::sin(2.0 * w * t[i]);
      c2 += std::cos(2.0 * w * t[i]);
    }
    const double tau = std::atan2(s2, c2) / (2.0 * w);
    double yc = 0.0, ys = 0.0, cc = 0.0, ss = 0.0;
    for (size_t i = 0; i < n; ++i) {
      const double c = std::cos(w * (t[i] - tau)), s = std::sin(w * (t[i] - tau));
      const double d = y[i] - mean;
      yc += d * c;
      ys += d * s;
      cc += c * c;
      ss += s * s;
    }
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
