#pragma once
// The tool's motion between CL points as a five-axis control makes it: joint values
// interpolated linearly between consecutive points (so the tool tip does not follow the straight
// CL segment when rotary axes move), sampled into discrete tool placements for swept-surface
// computation. Placements are in the workpiece frame w, lengths in mm.
#include <Eigen/Core>
#include <vector>

#include "core/kinematics/forward_kinematics.h"
#include "core/path/tool_path_prediction.h"

namespace tolver {

// One position of the tool: tip (origin of the tool frame t) and unit axis (tip -> spindle)
// seen from w, and the CL point it follows from.
struct ToolPlacement {
  Eigen::Vector3d tip_w = Eigen::Vector3d::Zero();
  Eigen::Vector3d axis_w = Eigen::Vector3d::UnitZ();
  int cl_index = 0;  // index of the CL point at the end of the move this placement lies on
};

struct MotionSampling {
  // Largest advance between consecutive placements of the tool tip and of the point `reach` mm
  // up the tool axis (mm). For a cutter of effective radius R and a tolerance t, a step of
  // sqrt(0.8 R t) keeps the cusp between placements, step^2 / 8R, at a tenth of t.
  double step = 0.1;
  double reach = 10.0;
  int max_substeps = 10000;  // per CL segment
};

// Placements along `path` for joint values `q` (one per CL point, from inverse kinematics),
// on the nominal machine (`nominal`) and on the machine with errors (`actual`). Both are
// sampled at the same joint values, chosen from the nominal motion, so placement k of one
// corresponds to placement k of the other. Moves into a rapid point (APT RAPID) are not
// cutting moves and produce no placements but their end point.
void samplePlacements(const ForwardKinematics& nominal, const ForwardKinematics& actual,
                      const std::vector<ClPoint>& path, const std::vector<JointVector>& q,
                      const MotionSampling& sampling, std::vector<ToolPlacement>* nominal_out,
                      std::vector<ToolPlacement>* actual_out);
// The same with the nominal placements at q_nominal and the actual ones at q_actual (a
// compensated program: the original's joints and the compensating ones, point for point); the
// sub-steps follow q_nominal.
void samplePlacements(const ForwardKinematics& nominal, const ForwardKinematics& actual,
                      const std::vector<ClPoint>& path, const std::vector<JointVector>& q_nominal,
                      const std::vector<JointVector>& q_actual, const MotionSampling& sampling,
                      std::vector<ToolPlacement>* nominal_out,
                      std::vector<ToolPlacement>* actual_out);
// The placements of CL points [first, last) alone, appended: point 0 and a rapid point's its
// own, any other's the sub-steps of the move into it from the point before (which may lie
// before `first`). Pieces of a path, joined in order, are samplePlacements' placements; only for
// a machine without direction-dependent effects (`actual`'s model has no effect blocks: their
// approach directions follow the whole path), else std::invalid_argument.
void samplePlacementsOf(const ForwardKinematics& nominal, const ForwardKinematics& actual,
                        const std::vector<ClPoint>& path, const std::vector<JointVector>& q_nominal,
                        const std::vector<JointVector>& q_actual, const MotionSampling& sampling,
                        size_t first, size_t last, std::vector<ToolPlacement>* nominal_out,
                        std::vector<ToolPlacement>* actual_out);

// The program's clock: the time (min, from the first point) at which the tool reaches each CL
// point, each cutting move's tip path at its feed rate (ClPoint::feed_mm_min; TCP controls feed
// the tip), rapids at `rapid_mm_min` (the machine's rapid rate: an assumption, rapids are short).
// Acceleration and dwell are not modelled. Empty when a cutting move has no feed rate.
std::vector<double> programTimes(const std::vector<ClPoint>& path, double rapid_mm_min = 10000.0);

}  // namespace tolver
