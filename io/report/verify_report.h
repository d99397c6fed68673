#pragma once
// Reports of `tolver verify`: report.json (machine-readable), report.html (self-contained, the
// images embedded), deviations.csv (one row per surface sample). Deviations in um in the files,
// signed along the outward normal: + material left, - gouge.
#include <string>
#include <utility>
#include <vector>

#include "geometry/mesh_decimate.h"
#include "geometry/mesh_repair.h"
#include "geometry/verification.h"
#include "io/common/io_error.h"

namespace tolver {

struct VerifyReport {
  std::string name;  // job name (batch) or the program's stem
  std::string machine_name, machine_file, program_file, part_file, cutter;
  std::string mode = "part";  // "part" (CAD model) or "cl-only"
  int cl_points = 0, placements = 0;
  std::vector<int> cl_lines;  // per CL point, its file line
  double step_mm = 0, spacing_mm = 0;
  const SurfaceSamples* samples = nullptr;
  const VerifyResult* result = nullptr;
  std::vector<ToleranceZone> zones;
  bool has_repair = false;
  MeshRepairReport repair;
  // Per region of the part (a CAD face of a STEP part), and what the STEP file said (one line:
  // system, schema, unit, solid, faces, tessellation), empty for other formats.
  std::vector<RegionSummary> region_table;
  std::string cad_text;
  bool cad = false;
  int line_pass = -1;  // 1-based pass of the line profile, -1 none
  std::vector<LineProfilePoint> line_profile;
  std::vector<std::pair<std::string, std::string>> images;  // caption, path
  std::vector<std::string> notes;
  // A calibrated machine: the 95 % band of the machine's share per sample (um), its largest
  // value, and the decision when a zone limit lies within it.
  std::vector<double> band95_um;
  double band95_max_um = 0;
  // What the band holds beyond the calibration's covariance: its lack of fit per tip coordinate
  // (um, 0: none). The spindle tilt's prior moves the axis, not the tip the band is taken at.
  double band_lack_of_fit_um = 0;
  double band_spindle_tilt_urad = 0;  // the stated prior of the spindle's tilt (0: none)
  int undecided_samples = 0;
  bool undecided = false;
  std::string undecided_text;
  // A checked face with a hole the mesh does not cover (MeshRepairReport::holes), without
  // --allow-open: the verdict cannot be PASS.
  bool incomplete = false;
  std::string incomplete_text;
  // The 3D view's surface (io/report/view3d.h): the samples kept by the decimation; null: none.
  const DecimatedMesh* view_mesh = nullptr;
  double seconds = 0;
  std::vector<std::pair<std::string, double>> timings;  // phase, seconds
  int exit_code = 0;  // the command's, as the pipeline decided it (pipeline/command.h, exitCode)
};

// The verdict: INCOMPLETE (holes in the checked surface, nothing out of tolerance), UNDECIDED
// (a limit within the band, nothing clearly out), PASS, FAIL.
std::string verdictName(const VerifyReport& r);

// The cause of an out-of-tolerance region at its worst sample: "program" when the program on a
// perfect machine is already out of the zone there, "machine" when it is in and the machine's
// errors take it out.
std::string regionCause(const VerifyReport& r, const OutOfToleranceRegion& region);
// A region's worst deviation as printed, in um: "+12.34 um", or "-500 um or deeper (beyond the
// search range)" where the cut reaches the gouge limit (never a clipped number); without the
// unit ("+12.34", "-500 or deeper (beyond the search range)") for a column headed in um.
std::string worstDeviationText(const VerifyResult& v, const OutOfToleranceRegion& region,
                               bool unit = true);

std::string formatVerifyJson(const VerifyReport& r);
std::string formatVerifyHtml(const VerifyReport& r);
std::string formatDeviationsCsv(const VerifyReport& r);
// The same, written in pieces (a file flushed every megabyte: a million samples' 112 MB never
// held whole).
void writeDeviationsCsv(const VerifyReport& r, TextOut& out);

}  // namespace tolver
