#include "geometry/cutter.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "core/numerics/units.h"

namespace tolver {

double Cutter::radiusAt(double h) const {
  if (h < 0.0) return -1.0;
  const double R = 0.5 * diameter;
  const double r = corner_radius;
  double rad;
  if (h < r) {
    // Corner torus: centre circle of radius R - r at height r.
    const double dz = r - h;
    rad = (R - r) + std::sqrt(std::max(0.0, r * r - dz * dz));
  } else {
    rad = R + (h - r) * std::tan(taper_angle);
  }
  return rad;
}

std::string Cutter::describe() const {
  static const char* names[] = {"flat end", "ball end", "bull nose", "tapered"};
  char buf[160];
  std::snprintf(buf, sizeof buf, "%s D%.4g mm, corner R%.4g mm", names[static_cast<int>(type)],
                diameter, corner_radius);
  std::string s = buf;
  if (taper_angle > 0) {
    std::snprintf(buf, sizeof buf, ", taper %.4g deg", radToDeg(taper_angle));
    s += buf;
  }
  return s;
}

bool cutterFromApt(const std::string& source, const std::vector<double>& v, Cutter* out) {
  if (v.empty() || !(v[0] > 0)) return false;
  Cutter c;
  c.diameter = v[0];
  c.corner_radius = v.size() > 1 ? v[1] : 0.0;
  if (source == "CUTTER") {
    // APT: d, r, e, f, alpha (deg, base angle), beta (deg, side angle from the axis), h.
    if (v.size() > 5) c.taper_angle = degToRad(v[5]);
    if (v.size() > 6) c.length = v[6];
  } else {
    // NX TLDATA/MILL: d, r, length, taper (deg), tip angle (deg).
    if (v.size() > 2) c.length = v[2];
    if (v.size() > 3) c.taper_angle = degToRad(v[3]);
  }
  if (c.corner_radius < 0 || c.corner_radius > 0.5 * c.diameter + 1e-9) return false;
  if (c.taper_angle < 0 || c.taper_angle >= kPi / 2) return false;
  if (c.taper_angle > 0)
    c.type = CutterType::Tapered;
  else if (std::abs(c.corner_radius - 0.5 * c.diameter) < 1e-9)
    c.type = CutterType::BallEnd;
  else if (c.corner_radius > 0)
    c.type = CutterType::BullNose;
  else
    c.type = CutterType::FlatEnd;
  *out = c;
  return true;
}

}  // namespace tolver

namespace tolver {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

struct Interval {
  double lo = kInf, hi = -kInf;
  bool empty() const { return !(lo <= hi); }
  Interval clip(double a, double b) const { return {std::max(lo, a), std::min(hi, b)}; }
};

// {s : h0 + s hd in [hl, hh]}.
Interval slab(double h0, double hd, double hl, double hh) {
  if (std::abs(hd) < 1e-15) return (h0 >= hl && h0 <= hh) ? Interval{-kInf, kInf} : Interval{};
  double a = (hl - h0) / hd, b = (hh - h0) / hd;
  if (a > b) std::swap(a, b);
  return {a, b};
}

// {s : A s^2 + B s + C <= 0} as up to two intervals.
int quadraticBelow(double A, double B, double C, Interval out[2]) {
  const double scale = std::max({std::abs(A), std::abs(B), std::abs(C), 1e-300});
  if (std::abs(A) <= 1e-14 * scale) {
    if (std::abs(B) <= 1e-14 * scale) {
      if (C <= 0) {
        out[0] = {-kInf, kInf};
        return 1;
      }
      return 0;
    }
    const double r = -C / B;
    out[0] = B > 0 ? Interval{-kInf, r} : Interval{r, kInf};
    return 1;
  }
  const double disc = B * B - 4 * A * C;
  if (disc < 0) {
    if (A < 0) {
      out[0] = {-kInf, kInf};
      return 1;
    }
    return 0;
  }
  const double sq = std::sqrt(disc);
  // Numerically stable roots.
  const double q = -0.5 * (B + (B >= 0 ? sq : -sq));
  double r1 = q / A, r2 = q != 0 ? C / q : r1;
  if (r1 > r2) std::swap(r1, r2);
  if (A > 0) {
    out[0] = {r1, r2};
    return 1;
  }
  out[0] = {-kInf, r1};
  out[1] = {r2, kInf};
  return 2;
}

}  // namespace

double Cutter::lineEntry(const Eigen::Vector3d& a_w, const Eigen::Vector3d& d_w,
                         const Eigen::Vector3d& u_w, double s_min, double s_max) const {
  const double L = effectiveLength();
  const double R = 0.5 * diameter, rc = corner_radius, Rt = R - rc;
  const double h0 = a_w.dot(u_w), hd = d_w.dot(u_w);
  const Eigen::Vector3d ra = a_w - h0 * u_w, rd = d_w - hd * u_w;
  const double A = rd.squaredNorm(), B = 2.0 * ra.dot(rd), C = ra.squaredNorm();
  double entry = kInf;
  auto take = [&](Interval iv) {
    iv = iv.clip(s_min, s_max);
    if (!iv.empty()) entry = std::min(entry, iv.lo);
  };

  // Upper part, h in [rc, L]: cylinder (or cone) of radius R + (h - rc) tan(taper).
  {
    const Interval in_slab = slab(h0, hd, rc, L);
    if (!in_slab.empty()) {
      const double k = taper_angle == 0.0 ? 0.0 : std::tan(taper_angle);  // (tan: 3 % of a sweep)
      const double g0 = R + k * (h0 - rc), g1 = k * hd;
      Interval parts[2];
      const int n = quadraticBelow(A - g1 * g1, B - 2 * g0 * g1, C - g0 * g0, parts);
      for (int i = 0; i < n; ++i) {
        const Interval iv{std::max(parts[i].lo, in_slab.lo), std::min(parts[i].hi, in_slab.hi)};
        if (!iv.empty()) take(iv);
      }
    }
  }
  if (rc <= 0) return entry;  // flat end (or sharp tapered): the upper part reaches the tip

  if (Rt <= 1e-12) {
    // Ball: sphere of radius rc about the point rc up the axis (its upper half lies within the
    // cylinder above, so the whole sphere may be taken).
    const Eigen::Vector3d c = a_w - rc * u_w;  // line origin relative to the centre
    Interval iv[2];
    if (quadraticBelow(1.0, 2.0 * c.dot(d_w), c.squaredNorm() - rc * rc, iv) == 1) take(iv[0]);
    return entry;
  }

  // Bull nose: the points within rc of the disk {h = rc, rho <= Rt}. Distance to a convex set is
  // convex along a line, so the inside set is one interval; find its lower end by bisection.
  auto excess = [&](double s) {
    const double h = h0 + s * hd - rc;
    const double rho = std::sqrt(std::max(0.0, C + s * (B + s * A)));
    const double out = std::max(0.0, rho - Rt);
    return std::sqrt(out * out + h * h) - rc;
  };
  double lo = s_min, hi = std::min(s_max, entry);
  if (!(lo <= hi)) return entry;
  if (excess(lo) <= 0) return std::min(entry, lo);
  // Locate a point inside: minimise the convex excess by golden section.
  double a = lo, b = hi;
  const double g = 0.5 * (std::sqrt(5.0) - 1.0);
  double x1 = b - g * (b - a), x2 = a + g * (b - a), f1 = excess(x1), f2 = excess(x2);
  int it = 0;
  while (f1 > 0 && f2 > 0 && b - a > 1e-9 && it++ < 100) {
    if (f1 < f2) {
      b = x2;
      x2 = x1;
      f2 = f1;
      x1 = b - g * (b - a);
      f1 = excess(x1);
    } else {
      a = x1;
      x1 = x2;
      f1 = f2;
      x2 = a + g * (b - a);
      f2 = excess(x2);
    }
  }
  double inside;
  if (f1 <= 0)
    inside = x1;
  else if (f2 <= 0)
    inside = x2;
  else if (excess(hi) <= 0)
    inside = hi;
  else
    return entry;
  // Bisection between lo (outside) and inside.
  double l = lo, r = inside;
  for (int k = 0; k < 60 && r - l > 1e-10; ++k) {
    const double m = 0.5 * (l + r);
    (excess(m) <= 0 ? r : l) = m;
  }
  return std::min(entry, r);
}

}  // namespace tolver
