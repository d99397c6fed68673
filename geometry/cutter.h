#pragma once
// Cutter shapes for swept surfaces: flat end, ball end, bull nose (torus) and tapered, built
// from APT CUTTER (d, r, e, f, alpha, beta, h) or NX TLDATA/MILL (d, r, length, taper, tip).
//
// Tool frame t: origin at the tool tip (the CL point, the lowest point of the cutter on its
// axis), z along the tool axis towards the spindle; lengths in mm, angles in rad.
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
};

// From the values of CUTTER (source "CUTTER") or TLDATA/MILL (source "TLDATA"), lengths in mm
// and, for TLDATA, angles in degrees. Returns false when the values do not describe a cutter.
bool cutterFromApt(const std::string& source, const std::vector<double>& values, Cutter* out);

}  // namespace tolver
