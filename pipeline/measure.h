#pragma once
// tolver measure: close the loop on a machined part. The measured points (a CMM's or the
// machine probe's, io/program/measured_points.h) are matched to the nominal surface (their feet
// on the part's mesh) and to the tool placements that cut them (verify's sweep at the feet); each
// point's measured normal deviation less the predicted one is the residual, which tracePart
// (core/diagnosis/part_trace.h) explains by the set-up, the cutters' radii and lengths, a uniform
// stock, the calibrated machine's parameters (with the calibration's covariance as their prior),
// or nothing. Before and after on held-out points (every N-th).
#include <memory>
#include <string>
#include <vector>

#include "io/report/measure_report.h"
#include "pipeline/command.h"
#include "pipeline/verify.h"

namespace tolver {

struct MeasureInputs {
  VerifyInputs verify;       // machine, program, set-up, part (required), tolerance, placement
  std::string points;        // the measured points file
  double search_mm = 0.5;    // farthest a point may lie from the nominal surface
  int heldout_every = 5;     // every N-th used point is held out of the fit (N >= 2)
  PlausibleRange plausible;  // beyond these a traced value is implausible, not added
  std::string report_dir;    // residuals.csv, report.json, process.txt, the residual's images
  bool images = true;        // the maps and histograms (PNG, off screen: a display is needed)
};

struct MeasureRun {
  MeasureReport report;
  std::string report_dir;
  Verdict verdict = Verdict::Ok;
};

// Reads, matches, predicts and traces; writes the report directory when in.report_dir is set.
// Throws InputError.
MeasureRun measurePart(const MeasureInputs& in, const Progress& progress = {});

}  // namespace tolver
