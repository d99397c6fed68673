#pragma once
// Cutter shapes for swept surfaces: flat end, ball end, bull nose (torus) and tapered, built
// from APT CUTTER (d, r, e, f, alpha, beta, h) or NX TLDATA/MILL (d, r, length, taper, tip).
//
// Tool frame t: origin at the tool tip (the CL point, the lowest point of the cutter on its
// axis), z along the tool axis towards the spindle; lengths in mm, angles in rad.
#include <Eigen/Core>
#include <string>
#include <vector>

namespace tolver {

enum class CutterType { FlatEnd, BallEnd, BullNose, Tapered };

struct Cutter {
  CutterType type = CutterType::FlatEnd;
  double diameter = 0.0;       // at the end of the corner (mm)
  double corner_radius = 0.0;  // mm
  double taper_angle = 0.0;    // half-angle of the flank from the axis, rad
  double length = 0.0;         // cutting height, mm (0: unknown)

  // Radius of the cutter's surface of revolution at height h above the tip (mm);
  // negative when h is below the tip.
  double radiusAt(double h) const;
  std::string describe() const;
  // Length of the cutter considered in swept surfaces: the cutting height when known, else
  // three diameters (mm).
  double effectiveLength() const { return length > 0 ? length : 3.0 * diameter; }
  // Largest radius over the effective length (mm).
  double maxRadius() const { return radiusAt(effectiveLength()); }

  // Where the line x(s) = a_w + s d_w (|d_w| = 1), with a_w relative to the tool tip, first
  // enters the cutter solid of axis u_w (unit, tip -> spindle) over its effective length, for s in
  // [s_min, s_max]; +infinity when it does not. The solid is convex, so the line meets it in one
  // interval. Flat, ball and tapered cutters are solved in closed form (quadratics); the corner
  // of a bull nose by bisection on the convex distance to its core disk.
  double lineEntry(const Eigen::Vector3d& a_w, const Eigen::Vector3d& d_w,
                   const Eigen::Vector3d& u_w, double s_min, double s_max) const;
};

// From the values of CUTTER (source "CUTTER") or TLDATA/MILL (source "TLDATA"), lengths in mm
// and, for TLDATA, angles in degrees. Returns false when the values do not describe a cutter.
bool cutterFromApt(const std::string& source, const std::vector<double>& values, Cutter* out);

}  // namespace tolver
