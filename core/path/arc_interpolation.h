#pragma once
// Expansion of circular arcs (APT CIRCLE / MOVARC) into points within a chordal tolerance.
#include <Eigen/Core>
#include <vector>

namespace tolver {

// Points along the arc from `start` to `end` about the circle centre `centre` and unit `axis`,
// traversed counter-clockwise about `axis` (right-hand rule, the APT convention), excluding
// `start` and including `end`. The sagitta between consecutive points is at most
// chordal_tolerance (mm). Returns false when start and end are not on one circle about the
// axis (radius differs by more than radius_tolerance), leaving `out` unchanged; a radius
// difference within it is taken up linearly along the arc. `extra_turns` full turns are made
// before the end (NX CLSF CIRCLE ... TIMES,n; LinuxCNC's P n-1), a helix rising linearly.
bool interpolateArc(const Eigen::Vector3d& start, const Eigen::Vector3d& end,
                    const Eigen::Vector3d& centre, const Eigen::Vector3d& axis,
                    double chordal_tolerance, double radius_tolerance,
                    std::vector<Eigen::Vector3d>& out, int extra_turns = 0);

// Points a full turn of radius r (mm) needs at the chordal tolerance: what a reader checks
// against its budget before expanding an arc (a 1.7 kB file of 9e8 mm circles must not expand
// for minutes). Infinite for a non-positive tolerance.
double arcPointsPerTurn(double radius, double chordal_tolerance);
constexpr double kMaxArcPoints = 1e6;

}  // namespace tolver
