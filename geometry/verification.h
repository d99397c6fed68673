#pragma once
// Verification of a part program against the part's nominal surface ([AM01] 5.5.4-5.5.5, by the
// point-vector method of geometry/swept_surface.h): the surface the cutter leaves along
// CL_nominal (the program on a perfect machine) and along CL_predicted (on the real machine),
// each as a signed normal deviation at every sample of the nominal surface, then the profile
// tolerance zones. Deviations in mm along the outward normal, + material left, - gouge:
//   total   = predicted swept - nominal surface   (what the part will be; the verdict)
//   program = nominal swept - nominal surface     (the program's own error: scallops, gouges)
//   machine = predicted swept - nominal swept     (the machine's contribution)
#include <functional>
#include <string>
#include <vector>

#include "core/path/tool_motion.h"
#include "geometry/cutter.h"
#include "geometry/swept_surface.h"
#include "geometry/tolerance_zone.h"
#include "geometry/triangle_mesh.h"

namespace tolver {

struct DeviationStats {
  int samples = 0;                             // machined samples with a zone
  double min = 0, max = 0, mean = 0, rms = 0;  // mm, area-weighted mean and RMS
  int min_sample = -1, max_sample = -1;
};

// Whether a sample's deviation splits into program and machine shares (total = program + machine
// exactly when it does).
enum class Split : char {
  Attributable = 0,  // both sweeps cut it inside the search range
  BeyondRange,       // a sweep reaches the gouge limit or leaves it uncut: no number to split
  CutBoundary,       // the machine's share exceeds what moving the cutting placement can do: the
                     // sample lies on a cut's boundary (a lateral shift carries the boundary across
                     // it at grazing incidence), where a micrometre becomes a step of the surface
};
const char* splitName(Split s);

struct VerifyResult {
  std::vector<double> total, program, machine;  // #S, mm (0 where unmachined or not attributable)
  std::vector<Split> split;                     // #S: whether program + machine = total there
  std::vector<char> total_beyond;               // #S: the predicted cut reaches the gouge limit
  int split_beyond = 0, split_boundary = 0;     // machined samples not attributable, by reason
  std::vector<char> machined;                   // #S: cut on both machines
  std::vector<int> zone;                        // #S, -1: no zone holds it
  std::vector<Conformance> conformance;  // #S, of `total` (Unchecked: no zone, or on an edge)
  std::vector<int> cl_index;             // #S, CL point whose move cut it (predicted), -1
  // #S, the sample seen from the tip of the predicted placement that cut it (mm, in w; zero when
  // none): where on the cutter the contact lies, the lever arm of the tool axis's errors.
  std::vector<Eigen::Vector3f> contact_offset_w;
  DeviationStats total_stats, program_stats, machine_stats;
  double area = 0, area_machined = 0, area_in = 0, area_unmachined = 0;  // mm^2
  double area_edge = 0;   // mm^2 of samples on sharp edges and borders (not verified)
  double percent_in = 0;  // of the machined area with a zone
  std::vector<OutOfToleranceRegion> regions;
  bool pass = false;  // machined area nonempty and no region
};

// progress(fraction) over both sweeps. The machine's share at a sample is bounded by how far the
// placements that cut it move: |tip change| + |axis change| x (the entry's height on the tool) +
// the cutter's radius x |axis change|; a share beyond 1.5 x that bound + 0.1 um is a cut boundary.
VerifyResult verifyPart(const SurfaceSamples& samples, const Cutter& cutter,
                        const std::vector<ToolPlacement>& nominal,
                        const std::vector<ToolPlacement>& predicted,
                        const std::vector<ToleranceZone>& zones, const SweepOptions& options,
                        const std::function<void(double)>& progress = {});
// The same for a program that changes tools (geometry/swept_surface.h: ToolSet).
VerifyResult verifyPart(const SurfaceSamples& samples, const ToolSet& tools,
                        const std::vector<ToolPlacement>& nominal,
                        const std::vector<ToolPlacement>& predicted,
                        const std::vector<ToleranceZone>& zones, const SweepOptions& options,
                        const std::function<void(double)>& progress = {});

// The predicted placements cut with tools of their own (the tools as they are, when a measured
// part showed their radii off: pipeline/verify.cpp's process corrections).
VerifyResult verifyPart(const SurfaceSamples& samples, const ToolSet& tools,
                        const ToolSet& predicted_tools, const std::vector<ToolPlacement>& nominal,
                        const std::vector<ToolPlacement>& predicted,
                        const std::vector<ToleranceZone>& zones, const SweepOptions& options,
                        const std::function<void(double)>& progress = {});

// Conformance, statistics, regions and verdict from the three deviation fields (used by
// verifyPart and by the CL-only mode).
void evaluateZones(const SurfaceSamples& samples, const std::vector<ToleranceZone>& zones,
                   VerifyResult* result);

// Each region of the part (a mesh group: an OBJ group, a CAD face of a STEP part) summarised over
// its samples: area, the machined and checked area, the deviation furthest from zero among its
// checked samples and the one furthest out of its zone.
struct RegionSummary {
  int group = 0;
  double area_mm2 = 0, checked_mm2 = 0, out_mm2 = 0;
  int samples = 0, checked = 0, out = 0;
  double worst_mm = 0;  // signed total deviation of largest magnitude among checked samples
  int worst_sample = -1;
  // "out" (a checked sample out of its zone), "in", "unmachined" (none cut), "unchecked"
  std::string status;
};
std::vector<RegionSummary> summariseRegions(const SurfaceSamples& samples,
                                            const VerifyResult& result);

// Passes of a CL program: runs of points [first, last] between rapid moves and sharp turns of
// the feed direction (more than 60 deg), with at least two points.
struct ClPass {
  int first = 0, last = 0;
};
std::vector<ClPass> clPasses(const std::vector<ClPoint>& path);

// Line profile along one pass ([AM01] 5.5.4, Fig. 5.7): for each CL point of the pass, the
// sample its move cut closest to the nominal surface (the contact point), in pass order.
struct LineProfilePoint {
  int cl_index = 0;
  int sample = -1;
  double arc_length = 0;  // mm along the contact points
  double total = 0, machine = 0;
};
std::vector<LineProfilePoint> lineProfile(const SurfaceSamples& samples, const VerifyResult& r,
                                          const ClPass& pass);

// CL-only mode ([AM01] 5.5.4-5.5.5) when there is no CAD model: the nominal surface is the
// surface through the CL points, each piece of a pass (passes cut at each full turn about the
// tool axis) joined by triangle strips to the earlier pieces it lies beside (found from the
// points, not from their order), its normal turned towards the tool; the predicted one has the
// same connectivity through the CL_predicted points. A move longer than the typical gap between
// neighbours has samples along it, its nominal and predicted points interpolated (cl_index: the
// move's end). Deviation = (p_predicted - p_nominal) . n (the first-order distance along the
// normal; the second-order term is below 1e-6 of it for micrometre errors). `program` is zero.
// Fills `samples` (one per CL point used, and those along long moves) and `result`.
// `width_mm`: per CL point, the width its cutter sweeps (its largest diameter), the farthest
// apart two passes of one surface can lie; empty: no limit.
void clOnlyDeviation(const std::vector<ClPoint>& nominal, const std::vector<ClPoint>& predicted,
                     const std::vector<ToleranceZone>& zones, const std::vector<double>& width_mm,
                     SurfaceSamples* samples, VerifyResult* result);

}  // namespace tolver
