#pragma once
// Chebyshev polynomials of the first kind for motion-error series ([AM01] eq. 54-59, 90-94).
//
// A motion error e(s) of a joint is the series  e(s) = sum_k c_k T_k(s_N),
// with s_N = (s - s_mid) / (range / 2) the joint coordinate normalised over its travel (eq. 58),
// and T_k evaluated by the recurrence T_k = 2 s_N T_{k-1} - T_{k-2} (eq. 57).
#include <cassert>

namespace tolver {

// Normalised joint coordinate of eq. 58: maps [s_min, s_max] onto [-1, 1].
inline double normalisedCoordinate(double s, double s_min, double s_max) {
  const double mid = 0.5 * (s_min + s_max);
  const double half_range = 0.5 * (s_max - s_min);
  return (s - mid) / half_range;
}

// Fills T[0..n] with T_0(x) .. T_n(x) by the recurrence of eq. 57.
inline void chebyshevBasis(double x, int n, double* T) {
  assert(n >= 0);
  T[0] = 1.0;
  if (n >= 1) T[1] = x;
  for (int k = 2; k <= n; ++k) T[k] = 2.0 * x * T[k - 1] - T[k - 2];
}

// sum_{k=0..n} c[k] T_k(x), by the basis recurrence.
inline double chebyshevSeries(const double* c, int n, double x) {
  double t_prev = 1.0, t = x;
  double sum = c[0];
  if (n >= 1) sum += c[1] * x;
  for (int k = 2; k <= n; ++k) {
    const double t_next = 2.0 * x * t - t_prev;
    sum += c[k] * t_next;
    t_prev = t;
    t = t_next;
  }
  return sum;
}

}  // namespace tolver
