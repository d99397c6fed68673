#pragma once
// The verify pipeline ([AM01] 5.5.4-5.5.6, by swept surfaces; see geometry/verification.h) as
// library functions: will this program on this machine make this part within its profile
// tolerance? runVerification reads the inputs and computes; writeVerification writes the report
// directory as a whole. `tolver verify` parses options into VerifyInputs and prints.
#include <Eigen/Geometry>
#include <chrono>
#include <cmath>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "geometry/mesh_decimate.h"
#include "geometry/verification.h"
#include "io/report/verify_report.h"
#include "pipeline/command.h"
#include "pipeline/inputs.h"

namespace tolver {

struct StepPart;

// The zones of a STEP file's semantic PMI (docs/formats.md, STEP parts): each profile-of-a-surface
// tolerance a zone on each of its faces (of a composite frame, the located segment; the narrower
// zone last, so it decides where frames overlap); the other tolerances listed as not checked.
std::vector<ToleranceZone> pmiZones(const StepPart& cad, const TriangleMesh& mesh,
                                    std::vector<std::string>* notes);

struct VerifyInputs {
  MachineOptions machine;
  ProgramOptions program;
  std::string part;                       // part model; empty: CL-only mode
  std::string part_name;                  // the solid of a STEP assembly
  std::string zones_file;                 // zones per region (CSV)
  std::string mesh_units;                 // "", "mm", "inch", "m"
  std::vector<double> mesh_offset;        // placement of the part file in w, mm (x, y, z)
  std::vector<double> mesh_rotation_deg;  // about x, then y, then z of w, deg
  double tolerance_mm = NAN;              // profile tolerance all over (zone width t)
  bool tolerance_confirmed = false;       // a tolerance above 1 mm was meant (else refused)
  double uz_mm = NAN, asme_u_mm = NAN;    // ISO 1101 UZ offset, or ASME Y14.5 U
  double spacing_mm = 0.5;                // surface sample spacing
  double step_mm = NAN, excess_range_mm = NAN, gouge_range_mm = NAN;  // NAN: from t and the cutter
  double max_hole_mm = -1;       // largest mesh hole perimeter filled; < 0: default
  std::vector<double> cutter;    // d, r[, length, taper_deg]; empty: the program's
  std::string tools;             // tool file (io/program/tool_file.h): posted tools' geometry
  int line_pass = 0;             // 1-based pass for a line profile, 0 none
  bool absolute = false;         // calibrated machine: no measured set-up
  std::string probed;            // probed points (CSV)
  std::string compensated_from;  // the original of a compensated program
  bool allow_open = false;       // holes in the checked surface do not make INCOMPLETE
  // The samples to verify instead of the part's surface sampled at spacing_mm (tolver measure:
  // the measured points' feet on the part), given the part's mesh in w; and whether to keep
  // each CL point's joints, tool axis and tool (Verification::poses).
  std::function<SurfaceSamples(const TriangleMesh&)> samples_at;
  bool keep_poses = false;
  // Process corrections learned from a measured part (io/program/process_file.h): the part's
  // pose on the table, the tools' radii and lengths as they are.
  std::string process;
  // The outputs (verifyPart, verifyBatch): the report directory, with images or without.
  std::string report_dir;
  bool images = true;
  bool view3d = true;  // report.html's interactive 3D view (io/report/view3d.h)
};

// What a verification computed. Not copyable: `report` points at `samples` and `result`.
struct Verification {
  VerifyReport report;
  SurfaceSamples samples;
  VerifyResult result;
  DecimatedMesh view_mesh;  // the 3D view's (writeVerification)
  std::string machine_file, program_dialect;
  bool banded = false;  // a calibrated machine: report.band95_* hold the prediction's band
  // With VerifyInputs::keep_poses: per CL point its joints (nominal IK), the CL point itself
  // (tip, axis, feed) and tool (index into cutters); the machine as predicted (its
  // identification included).
  struct Poses {
    std::vector<JointVector> q;
    std::vector<ClPoint> path;
    std::vector<int> tool;
    std::vector<Cutter> cutters;
    std::vector<ProgramOperation> operations;  // the program's named operations
    Machine machine;
  } poses;
  std::chrono::steady_clock::time_point started;
  // PASS: Ok; FAIL and INCOMPLETE: NotMet; UNDECIDED: Undecided (report.exit_code says the same).
  Verdict verdict = Verdict::Ok;

  Verification() = default;
  Verification(const Verification&) = delete;
  Verification& operator=(const Verification&) = delete;
};

// The part file's placement in w (mesh_offset, mesh_rotation_deg).
Eigen::Isometry3d partPlacement(const VerifyInputs& in);

// Reads the inputs, predicts the program, samples the part, sweeps the nominal and predicted
// tool and classifies every sample. `progress` gets the sweep's fraction done. Throws InputError.
std::unique_ptr<Verification> runVerification(const VerifyInputs& in, const std::string& name,
                                              const std::function<void(double)>& progress = {});

// Writes deviations.csv, swept_{predicted,nominal}.{ply,vtp}, the images (unless !images, or
// no display: then a note), report.json and report.html into `report_dir`, staged and swapped in
// as a whole (ReportDirectory); report.html with its 3D view unless !view3d. Returns the path of
// report.html. Throws InputError.
std::string writeVerification(Verification& v, const std::string& report_dir, bool images,
                              bool view3d = true, const Progress& progress = {});

// The 3D view's surface: the samples decimated (geometry/mesh_decimate.h) down to 120 000
// vertices within min(0.5 x the spacing, 1e-3 x the part's diagonal) of the surface, and 1/8 of
// the narrowest zone (half a band of the colour scale) of the total deviation; CAD faces, zones and
// states (in, out, unmachined, unchecked, beyond the search range) keep their boundaries, sharp
// edges and borders stay.
DecimatedMesh viewMesh(const SurfaceSamples& samples, const VerifyResult& result,
                       const std::vector<ToleranceZone>& zones, double spacing_mm,
                       const std::function<void(double)>& progress = {});

// tolver verify on one program: runVerification, then writeVerification into in.report_dir.
// name: the report's (empty: the program's stem). progress: "sweeping <name>".
struct VerifyRun {
  std::unique_ptr<Verification> verification;
  std::string report;  // report.html
  Verdict verdict = Verdict::Ok;
};
VerifyRun verifyPart(const VerifyInputs& in, const std::string& name = "",
                     const Progress& progress = {});

// tolver verify --batch: the jobs of a jobs file (io/program/jobs_file.h; paths relative to it),
// each over `base` with its own machine, set-up, probed points, program, part, zones and
// tolerance, verified in parallel into <base.report_dir>/<name>; summary.csv beside them.
struct JobOutcome {
  std::string name;
  Verdict verdict = Verdict::BadInput;
  std::string verdict_text;  // pass, fail, incomplete, undecided, error
  std::string error;         // the refusal of a job whose inputs are bad
  double max_um = 0, min_um = 0, machine_rms_um = 0, percent_in = 0;
  int regions = 0;
  std::string report;
};
struct BatchRun {
  std::vector<JobOutcome> jobs;
  std::string summary;            // summary.csv
  Verdict verdict = Verdict::Ok;  // the worst of the jobs'
};
// done(k, n, outcome): job k finished (from a worker thread, serialised), n jobs in all.
BatchRun verifyBatch(const VerifyInputs& base, const std::string& jobs_file,
                     const std::function<void(int, size_t, const JobOutcome&)>& done = {});

}  // namespace tolver
