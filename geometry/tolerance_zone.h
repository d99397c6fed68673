#pragma once
// Profile tolerance zones (ISO 1101 profile of a surface / of a line; ASME Y14.5 profile), each
// an interval [lower, upper] along the outward normal of the nominal surface, mm:
//   bilateral, tolerance t:              [-t/2, +t/2]
//   ISO 1101 UZ, t with offset x:        [x - t/2, x + t/2]   (x > 0 towards material left)
//   ASME Y14.5 U, t with u outside:      [u - t, u]           (u: the part of t that adds material)
// A deviation exactly on a limit is in tolerance (the zone is closed).
#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "geometry/triangle_mesh.h"

namespace tolver {

struct ToleranceZone {
  std::string region = "*";  // "*": every sample; else a mesh group (region) name
  bool has_box = false;      // or the samples inside box_w (mm, part frame)
  Eigen::AlignedBox3d box_w;
  double tolerance = 0.02;             // t, mm
  double lower = -0.01, upper = 0.01;  // mm along the outward normal
  std::string spec;                    // as it reads on a drawing, e.g. "profile 0.02 UZ+0.005"
};

// Throw std::invalid_argument on a tolerance <= 0, or u outside [0, t].
ToleranceZone bilateralZone(double t);
ToleranceZone isoUzZone(double t, double offset);
ToleranceZone asmeUZone(double t, double u);

enum class Conformance : unsigned char { In, Excess, Gouge, Unmachined, Unchecked };
const char* conformanceName(Conformance c);  // "in", "excess", "gouge", "unmachined", "unchecked"

Conformance classify(double deviation, bool machined, const ToleranceZone& zone);

// The zone of each sample: the last zone whose region holds it, -1 when none does.
std::vector<int> assignZones(const SurfaceSamples& samples,
                             const std::vector<ToleranceZone>& zones);

// A connected set of out-of-tolerance samples of one kind (excess or gouge), connected through
// the surface's faces.
struct OutOfToleranceRegion {
  Conformance kind = Conformance::Gouge;
  int zone = -1;
  int samples = 0;
  double area_mm2 = 0.0;
  double worst_deviation = 0.0;  // mm, signed
  double worst_excursion = 0.0;  // mm beyond the nearer limit, > 0
  int worst_sample = -1;
  Eigen::Vector3d where_w = Eigen::Vector3d::Zero();  // the worst sample
  Eigen::Vector3d normal_w = Eigen::Vector3d::UnitZ();
};

// Regions sorted by worst excursion, largest first.
std::vector<OutOfToleranceRegion> outOfToleranceRegions(const SurfaceSamples& samples,
                                                        const std::vector<double>& deviation,
                                                        const std::vector<Conformance>& conformance,
                                                        const std::vector<int>& zone_of,
                                                        const std::vector<ToleranceZone>& zones);

}  // namespace tolver
