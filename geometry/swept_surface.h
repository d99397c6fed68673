#pragma once
// The surface a cutter leaves when it moves through a sequence of placements: the point-vector
// ("mow the grass") method of NC verification. From each sample of the nominal surface a blade
// runs along the outward normal, from gouge_range below the surface to excess_range above it;
// every tool placement that the blade meets cuts it down to where the line enters the cutter.
// What is left of the blade is the signed normal deviation of the machined surface from the
// nominal one: + material left, - gouge. A sample that no tool cuts below excess_range is
// unmachined (not part of this program). Bounding-volume hierarchies over the placements give
// each blade only the placements that can reach what is left of it (for a ball end, its ball by
// distance to the ball's centre and the rest of the tool by boxes); the answer is that of
// testing every placement. Samples on sharp edges are skipped (unmachined).
#include <functional>
#include <vector>

#include "core/path/tool_motion.h"
#include "geometry/cutter.h"
#include "geometry/triangle_mesh.h"

namespace tolver {

struct SweepOptions {
  double excess_range = 0.5;  // mm above the surface: stock considered; more left = unmachined
  double gouge_range = 0.5;   // mm below the surface searched for gouges
  // #S or null: per sample, a placement to try first (-1: none), e.g. the one that cut deepest in
  // the nominal sweep when sweeping the predicted placements, which lie microns from the nominal
  // ones, index for index. It only shortens the search: the answer is the same without it.
  const std::vector<int>* first_try = nullptr;
};

struct SweepResult {
  std::vector<double> deviation;  // #S, mm along the outward normal (excess_range when unmachined)
  std::vector<char> machined;     // #S, 1 when a placement cut the blade
  std::vector<int> placement;     // #S, the placement that cut deepest, -1 when none
};

// progress(fraction) is called from the calling thread between blocks of samples.
void sweepSurface(const SurfaceSamples& samples, const Cutter& cutter,
                  const std::vector<ToolPlacement>& placements, const SweepOptions& options,
                  SweepResult* result, const std::function<void(double)>& progress = {});

// A program that changes tools: cutter tool_of_cl[k] cuts along the moves that end at CL point k
// (ToolPlacement::cl_index). Each tool's placements are swept with its own cutter and every
// sample keeps the deepest cut of any; placement indices are into `placements`.
struct ToolSet {
  std::vector<Cutter> cutters;  // at least one
  std::vector<int> tool_of_cl;  // #CL points; empty: cutters[0] everywhere
  double maxLength() const;
  double maxRadius() const;
};
void sweepSurface(const SurfaceSamples& samples, const ToolSet& tools,
                  const std::vector<ToolPlacement>& placements, const SweepOptions& options,
                  SweepResult* result, const std::function<void(double)>& progress = {});

}  // namespace tolver
