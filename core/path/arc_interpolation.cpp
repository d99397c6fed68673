#include "core/path/arc_interpolation.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>

#include "core/numerics/units.h"

namespace tolver {

bool interpolateArc(const Eigen::Vector3d& start, const Eigen::Vector3d& end,
                    const Eigen::Vector3d& centre, const Eigen::Vector3d& axis,
                    double chordal_tolerance, double radius_tolerance,
                    std::vector<Eigen::Vector3d>& out, int extra_turns) {
  const Eigen::Vector3d k = axis.normalized();
  const Eigen::Vector3d vs = start - centre, ve = end - centre;
  const double hs = vs.dot(k), he = ve.dot(k);
  const Eigen::Vector3d rs = vs - hs * k, re = ve - he * k;
  const double r = rs.norm();
  if (r < 1e-12 || std::abs(re.norm() - r) > radius_tolerance) return false;
  double sweep = std::atan2(k.dot(rs.cross(re)), rs.dot(re));
  if (sweep <= 1e-12) sweep += 2.0 * kPi;  // counter-clockwise; equal points: full circle
  sweep += 2.0 * kPi * std::max(0, extra_turns);
  // Sagitta r (1 - cos(dphi/2)) <= tol.
  const double tol = std::min(std::max(chordal_tolerance, 1e-9), r);
  const double dphi_max = 2.0 * std::acos(1.0 - tol / r);
  const int n = std::max(1, static_cast<int>(std::ceil(sweep / dphi_max)));
  const Eigen::Vector3d e1 = rs / r, e2 = k.cross(e1);
  for (int i = 1; i <= n; ++i) {
    const double t = static_cast<double>(i) / n;
    const double phi = sweep * t;
    const double h = hs + (he - hs) * t;  // helical arcs rise linearly
    const double rr = r + (re.norm() - r) * t;
    if (i == n) {
      out.push_back(end);
    } else {
      out.push_back(centre + h * k + rr * (std::cos(phi) * e1 + std::sin(phi) * e2));
    }
  }
  return true;
}

double arcPointsPerTurn(double radius, double tol) {
  const double r = std::max(radius, 1e-12);
  const double dphi = 2.0 * std::acos(std::max(-1.0, 1.0 - std::min(tol, r) / r));
  return dphi > 0.0 ? 2.0 * kPi / dphi : std::numeric_limits<double>::infinity();
}

}  // namespace tolver
