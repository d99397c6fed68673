// tolver verify: will this program on this machine make this part within its profile tolerance?
// ([AM01] 5.5.4-5.5.6, by swept surfaces; see geometry/verification.h.)
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>

#include "app/commands.h"
#include "app/common.h"
#include "core/numerics/units.h"
#include "io/common/text_util.h"
#include "io/report/verify_report.h"
#include "pipeline/verify.h"

namespace tolver::app {
namespace {

struct VerifyOptions {
  VerifyInputs in;
  std::string batch;
  std::string tolerance_units;  // "", "mm" or "um" (of --tolerance)
  bool no_images = false;
  bool no_3d = false;
  bool quiet = false;
};

void printVerification(const Verification& v, const VerifyOptions& o, const std::string& report) {
  const VerifyReport& r = v.report;
  const SurfaceSamples& samples = v.samples;
  const VerifyResult& result = v.result;
  std::printf("tolver verify: %s\n", verdictName(r).c_str());
  if (r.incomplete)
    std::printf("  %s\n", r.incomplete_text.c_str());
  else if (r.undecided)
    std::printf("  %s\n", r.undecided_text.c_str());
  std::printf("  machine    %s (%s)\n", r.machine_name.c_str(), v.machine_file.c_str());
  std::printf("  program    %s (%s): %d CL points, %d tool placements (step %.3g mm), %s\n",
              r.program_file.c_str(), v.program_dialect.c_str(), r.cl_points, r.placements,
              r.step_mm, r.cutter.c_str());
  if (r.mode == "cl-only")
    std::printf("  part       none: CL-only mode, %zu points\n", samples.size());
  else
    std::printf("  part       %s: %zu samples at %.3g mm%s\n", r.part_file.c_str(), samples.size(),
                r.spacing_mm, r.repair.notes.empty() ? "" : " (mesh repaired: see the report)");
  if (!r.cad_text.empty()) std::printf("  cad        %s\n", r.cad_text.c_str());
  for (const auto& z : r.zones)
    std::printf("  zone       %s: %s mm [%+.1f, %+.1f] um\n", z.region.c_str(), z.spec.c_str(),
                mmToUm(z.lower), mmToUm(z.upper));
  std::printf("  total      %+.2f .. %+.2f um, RMS %.2f um (+ material left, - gouge)\n",
              mmToUm(result.total_stats.min), mmToUm(result.total_stats.max),
              mmToUm(result.total_stats.rms));
  if (r.mode != "cl-only")
    std::printf("  program    %+.2f .. %+.2f um (nominal swept - CAD)\n",
                mmToUm(result.program_stats.min), mmToUm(result.program_stats.max));
  std::printf("  machine    %+.2f .. %+.2f um, RMS %.2f um (predicted - nominal swept)\n",
              mmToUm(result.machine_stats.min), mmToUm(result.machine_stats.max),
              mmToUm(result.machine_stats.rms));
  if (result.split_beyond + result.split_boundary > 0)
    std::printf(
        "  split      total = program + machine at every other machined sample; not split: %d "
        "samples beyond the search range, %d on a cut's boundary (a micrometre of the tool's "
        "shift moves the boundary across them)\n",
        result.split_beyond, result.split_boundary);
  if (v.banded)
    std::printf(
        "  band       the machine's share is known to +- %.2f um at most (95 %%, from the "
        "calibration's covariance at each contact, tip and tool axis%s%s)%s\n",
        r.band95_max_um,
        r.band_lack_of_fit_um > 0
            ? formatWith(" and its lack of fit, %.3f um per tip coordinate", r.band_lack_of_fit_um)
                  .c_str()
            : "; no lack of fit",
        r.band_spindle_tilt_urad > 0
            ? formatWith("; spindle tilt prior %.3g urad", r.band_spindle_tilt_urad).c_str()
            : "; spindle tilt not included",
        o.in.absolute ? "" : ", after the set-up a shop measures");
  std::printf(
      "  area       %.2f %% of %.1f mm2 machined in tolerance; %.1f mm2 not machined; "
      "%.1f mm2 on edges not verified\n",
      result.percent_in, result.area_machined, result.area_unmachined, result.area_edge);
  for (size_t k = 0; k < result.regions.size() && k < 5; ++k) {
    const auto& g = result.regions[k];
    std::printf("  region %zu   %s %.3f mm2, worst %s at (%.2f, %.2f, %.2f), cause: %s\n", k + 1,
                conformanceName(g.kind), g.area_mm2, worstDeviationText(result, g).c_str(),
                g.where_w.x(), g.where_w.y(), g.where_w.z(), regionCause(r, g).c_str());
  }
  if (result.regions.size() > 5)
    std::printf("  ...        %zu regions in all\n", result.regions.size());
  printNotes(r.notes);
  std::printf("  report     %s (and report.json, deviations.csv, swept_*.ply/.vtp%s)\n",
              report.c_str(), r.images.empty() ? "" : ", *.png");
}

void printBatch(const VerifyOptions& o, const BatchRun& run) {
  std::printf("tolver verify --batch %s: %zu jobs\n", o.batch.c_str(), run.jobs.size());
  std::printf("  %-20s %-7s %10s %10s %12s %8s %8s\n", "name", "verdict", "min um", "max um",
              "machine RMS", "% in", "regions");
  for (const JobOutcome& r : run.jobs)
    if (r.error.empty())
      std::printf("  %-20s %-7s %+10.2f %+10.2f %12.2f %8.2f %8d\n", r.name.c_str(),
                  r.verdict_text.c_str(), r.min_um, r.max_um, r.machine_rms_um, r.percent_in,
                  r.regions);
    else
      std::printf("  %-20s %-7s %s\n", r.name.c_str(), r.verdict_text.c_str(), r.error.c_str());
  std::printf("  wrote      %s\n", run.summary.c_str());
}

Verdict runVerify(VerifyOptions& o) {
  o.in.images = !o.no_images;
  o.in.view3d = !o.no_3d;
  o.in.tolerance_confirmed = !o.tolerance_units.empty();
  if (!o.batch.empty()) {
    const BatchRun run = verifyBatch(o.in, o.batch, [&o](int n, size_t total, const JobOutcome& r) {
      if (!o.quiet)
        std::fprintf(stderr, "  [%d/%zu] %s: %s\n", n, total, r.name.c_str(),
                     !r.error.empty()           ? "error"
                     : r.verdict == Verdict::Ok ? "pass"
                                                : "fail");
    });
    printBatch(o, run);
    return run.verdict;
  }
  if (o.tolerance_units == "um" && !std::isnan(o.in.tolerance_mm))
    o.in.tolerance_mm = umToMm(o.in.tolerance_mm);
  ProgressBar bar(!o.quiet);
  const VerifyRun run = verifyPart(o.in, "", progressOf(bar));
  if (!o.quiet) printVerification(*run.verification, o, run.report);
  return run.verdict;
}

}  // namespace

void registerVerify(CLI::App& app, Verdict* verdict) {
  auto o = std::make_shared<VerifyOptions>();
  CLI::App* cmd = app.add_subcommand(
      "verify",
      "Verify a part program on a machine: swept surfaces on the nominal and the real machine, "
      "signed normal deviations against profile tolerance zones, maps and reports. Exit 0 in "
      "tolerance, 1 out of tolerance or incomplete (a hole in the checked surface), 2 bad input, 4 "
      "undecided (a calibrated machine: a zone "
      "limit lies within the prediction's 95 % band).");
  addMachineOptions(cmd, o->in.machine, "machine file (XML), calibrated or not");
  cmd->get_option("--machine")->required(false);  // a batch names its machines in the jobs file
  addProgramOptions(cmd, o->in.program);
  cmd->add_option("--tolerance-units", o->tolerance_units,
                  "unit of --tolerance: mm (default; needed to confirm one above 1 mm) or um")
      ->check(CLI::IsMember({"mm", "um"}));
  cmd->add_option("--part", o->in.part,
                  "part model (STEP, STL, OBJ, PLY, OFF, 3MF, glTF); without it: CL-only mode");
  cmd->add_option("--part-name", o->in.part_name,
                  "the solid to verify in a STEP assembly (product or instance name)");
  cmd->add_option("--tolerance", o->in.tolerance_mm,
                  "profile tolerance all over, mm (zone width t)");
  cmd->add_option("--uz", o->in.uz_mm,
                  "ISO 1101 UZ offset of that zone, mm (+ towards material left)");
  cmd->add_option("--asme-u", o->in.asme_u_mm,
                  "ASME Y14.5 U: the part of t outside the material, mm");
  cmd->add_option("--zones", o->in.zones_file, "zones per region (CSV: region,tolerance,uz,u)");
  cmd->add_option("--report-dir", o->in.report_dir, "directory for the report (created)")
      ->required();
  cmd->add_option(
      "--batch", o->batch,
      "jobs file (CSV: name,machine,cl,part,tolerance[,setup,zones,probed]); verifies them "
      "in parallel, one report directory each, and writes summary.csv");
  cmd->add_option("--mesh-units", o->in.mesh_units,
                  "length unit of the part file: mm, inch or m "
                  "(default mm; m for glTF)");
  cmd->add_option("--mesh-offset", o->in.mesh_offset,
                  "placement of the part file in the part frame, mm (x,y,z)")
      ->delimiter(',')
      ->expected(3);
  cmd->add_option(
         "--mesh-rotation-deg", o->in.mesh_rotation_deg,
         "rotation of the part file about x, then y, then z of the part frame, deg (a,b,c)")
      ->delimiter(',')
      ->expected(3);
  cmd->add_option("--spacing", o->in.spacing_mm,
                  "surface sample spacing (remeshing target edge), mm (default 0.5)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--step", o->in.step_mm,
                  "largest tool advance between placements, mm (default sqrt(0.8 R t))")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--excess-range", o->in.excess_range_mm,
                  "stock above the surface considered, mm (default max(0.1, 5t))")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--gouge-range", o->in.gouge_range_mm,
                  "depth searched for gouges, mm (default max(0.1, 5t))")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--max-hole", o->in.max_hole_mm,
                  "largest mesh hole perimeter filled, mm (default 2 % of the size)");
  cmd->add_option("--tools", o->in.tools,
                  "tool file (CSV: tool,type,diameter_mm,corner_radius_mm,length_mm): the geometry "
                  "of the tools a posted program selects (T1, T=\"name\"), over its comments");
  cmd->add_option("--cutter", o->in.cutter,
                  "cutter d,r[,length,taper_deg] in mm, overriding the program's")
      ->delimiter(',');
  cmd->add_option("--line-pass", o->in.line_pass, "also a line profile along this pass (1-based)")
      ->check(CLI::PositiveNumber);
  cmd->add_flag("--no-images", o->no_images, "write no PNG images (no X server needed)");
  cmd->add_flag("--no-3d", o->no_3d,
                "no interactive 3D view in report.html (a smaller file; the maps stay)");
  cmd->add_flag("--quiet", o->quiet, "print nothing but errors");
  cmd->add_flag("--absolute", o->in.absolute,
                "a calibrated machine: verify without the set-up a shop measures (part probed, "
                "tool preset), i.e. with what the calibration cannot see left in");
  addProbedOption(cmd, o->in.probed);
  cmd->add_option("--process", o->in.process,
                  "process corrections learned from a measured part (tolver measure's "
                  "process.txt): the part's pose on the table, the tools' radii and lengths");
  cmd->add_flag(
      "--allow-open", o->in.allow_open,
      "holes in the part's surface (not covered by its mesh) do not make the verdict INCOMPLETE");
  cmd->add_option(
      "--compensated-from", o->in.compensated_from,
      "the program is the output of tolver compensate for this original: the nominal is "
      "the original's path, the machine runs the compensated program's joints");
  cmd->callback([o, verdict] { *verdict = runVerify(*o); });
}

}  // namespace tolver::app
