#include "geometry/cutter.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

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
    std::snprintf(buf, sizeof buf, ", taper %.4g deg", taper_angle * 180.0 / M_PI);
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
    if (v.size() > 5) c.taper_angle = v[5] * M_PI / 180.0;
    if (v.size() > 6) c.length = v[6];
  } else {
    // NX TLDATA/MILL: d, r, length, taper (deg), tip angle (deg).
    if (v.size() > 2) c.length = v[2];
    if (v.size() > 3) c.taper_angle = v[3] * M_PI / 180.0;
  }
  if (c.corner_radius < 0 || c.corner_radius > 0.5 * c.diameter + 1e-9) return false;
  if (c.taper_angle < 0 || c.taper_angle >= M_PI / 2) return false;
  if (c.taper_angle > 0) c.type = CutterType::Tapered;
  else if (std::abs(c.corner_radius - 0.5 * c.diameter) < 1e-9) c.type = CutterType::BallEnd;
  else if (c.corner_radius > 0) c.type = CutterType::BullNose;
  else c.type = CutterType::FlatEnd;
  *out = c;
  return true;
}

}  // namespace tolver
