// tolver verify: will this program on this machine make this part within its profile tolerance?
// ([AM01] 5.5.4-5.5.6, by swept surfaces; see geometry/verification.h.)
#include <tbb/parallel_for.h>

#include <atomic>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <string>

#include "app/commands.h"
#include "app/common.h"
#include "io/common/io_error.h"
#include "io/common/text_util.h"
#include "io/program/jobs_file.h"
#include "io/report/verify_report.h"
#include "pipeline/verify.h"
#include "core/numerics/units.h"

namespace tolver::app {
namespace {

namespace fs = std::filesystem;

struct VerifyOptions {
  VerifyInputs in;
  std::string report_dir, batch;
  std::string tolerance_units;  // "", "mm" or "um" (of --tolerance)
  bool no_images = false;
  bool quiet = false;
};

struct JobOutcome {
  std::string name;
  bool ok = false, pass = false;
  bool undecided = false;  // the decision lies within the prediction's 95 % band
  bool incomplete = false;  // a hole in the checked surface (without --allow-open)
  std::string error;
  double max_um = 0, min_um = 0, machine_rms_um = 0, percent_in = 0;
  int regions = 0;
  std::string report;
};

void printVerification(const Verification& v, const VerifyOptions& o, const std::string& report) {
  const VerifyReport& r = v.report;
  const SurfaceSamples& samples = v.samples;
  const VerifyResult& result = v.result;
  std::printf("tolver verify: %s\n", verdictName(r).c_str());
  if (r.incomplete) std::printf("  %s\n", r.incomplete_text.c_str());
  else if (r.undecided) std::printf("  %s\n", r.undecided_text.c_str());
  std::printf("  machine    %s (%s)\n", r.machine_name.c_str(), v.machine_file.c_str());
  std::printf("  program    %s (%s): %d CL points, %d tool placements (step %.3g mm), %s\n",
              r.program_file.c_str(), v.program_dialect.c_str(), r.cl_points, r.placements,
              r.step_mm, r.cutter.c_str());
  if (r.mode == "cl-only")
    std::printf("  part       none: CL-only mode, %zu points\n", samples.size());
  else
    std::printf("  part       %s: %zu samples at %.3g mm%s\n", r.part_file.c_str(), samples.size(), r.spacing_mm,
                r.repair.notes.empty() ? "" : " (mesh repaired: see the report)");
  for (const auto& z : r.zones)
    std::printf("  zone       %s: %s mm [%+.1f, %+.1f] um\n", z.region.c_str(), z.spec.c_str(),
                mmToUm(z.lower), mmToUm(z.upper));
  std::printf("  total      %+.2f .. %+.2f um, RMS %.2f um (+ material left, - gouge)\n",
              mmToUm(result.total_stats.min), mmToUm(result.total_stats.max), mmToUm(result.total_stats.rms));
  if (r.mode != "cl-only")
    std::printf("  program    %+.2f .. %+.2f um (nominal swept - CAD)\n", mmToUm(result.program_stats.min),
                mmToUm(result.program_stats.max));
  std::printf("  machine    %+.2f .. %+.2f um, RMS %.2f um (predicted - nominal swept)\n",
              mmToUm(result.machine_stats.min), mmToUm(result.machine_stats.max), mmToUm(result.machine_stats.rms));
  if (result.split_beyond + result.split_boundary > 0)
    std::printf("  split      total = program + machine at every other machined sample; not split: %d "
                "samples beyond the search range, %d on a cut's boundary (a micrometre of the tool's "
                "shift moves the boundary across them)\n",
                result.split_beyond, result.split_boundary);
  if (v.banded)
    std::printf("  band       the machine's share is known to +- %.2f um at most (95 %%, from the "
                "calibration's covariance)%s\n",
                r.band95_max_um, o.in.absolute ? "" : ", after the set-up a shop measures");
  std::printf("  area       %.2f %% of %.1f mm2 machined in tolerance; %.1f mm2 not machined; "
              "%.1f mm2 on edges not verified\n",
              result.percent_in, result.area_machined, result.area_unmachined, result.area_edge);
  for (size_t k = 0; k < result.regions.size() && k < 5; ++k) {
    const auto& g = result.regions[k];
    std::printf("  region %zu   %s %.3f mm2, worst %s at (%.2f, %.2f, %.2f), cause: %s\n", k + 1,
                conformanceName(g.kind), g.area_mm2, worstDeviationText(result, g).c_str(), g.where_w.x(),
                g.where_w.y(), g.where_w.z(), regionCause(r, g).c_str());
  }
  if (result.regions.size() > 5) std::printf("  ...        %zu regions in all\n", result.regions.size());
  for (const auto& n : r.notes) std::fprintf(stderr, "tolver: note: %s\n", n.c_str());
  std::printf("  report     %s (and report.json, deviations.csv, swept_*.ply/.vtp, *.png)\n",
              report.c_str());
}

JobOutcome runJob(const VerifyOptions& o, const std::string& name, bool progress_bar) {
  ProgressBar bar(progress_bar && !o.quiet);
  const auto v = runVerification(o.in, name, [&](double f) { bar("sweeping " + name, f); });
  JobOutcome out;
  out.name = name;
  out.report = writeVerification(*v, o.report_dir, !o.no_images);
  const VerifyResult& result = v->result;
  out.ok = true;
  out.pass = verdictName(v->report) == "PASS";
  out.undecided = verdictName(v->report) == "UNDECIDED";
  out.incomplete = v->report.incomplete;
  out.max_um = mmToUm(result.total_stats.max);
  out.min_um = mmToUm(result.total_stats.min);
  out.machine_rms_um = mmToUm(result.machine_stats.rms);
  out.percent_in = result.percent_in;
  out.regions = static_cast<int>(result.regions.size());
  if (!o.quiet && o.batch.empty()) printVerification(*v, o, out.report);
  return out;
}

// Batch: jobs.csv with columns name,machine,cl,part,tolerance[,setup,zones,probed]; paths relative to
// the jobs file.
int runBatch(const VerifyOptions& base) {
  std::vector<VerifyOptions> jobs;
  std::vector<std::string> names;
  for (const VerifyJob& j : readJobsFile(base.batch)) {
    VerifyOptions o = base;
    o.batch.clear();
    o.quiet = true;
    o.in.machine.machine = j.machine;
    o.in.machine.setup = j.setup;
    o.in.probed = j.probed;
    o.in.program.cl = j.cl;
    o.in.program.nc.clear();
    o.in.part = j.part;
    o.in.zones_file = j.zones;
    o.in.tolerance_mm = j.tolerance_mm;
    o.report_dir = (fs::path(base.report_dir) / j.name).string();
    jobs.push_back(o);
    names.push_back(j.name);
  }
  makeReportDir(base.report_dir);
  std::vector<JobOutcome> outcomes(jobs.size());
  std::atomic<int> done{0};
  std::mutex print;
  tbb::parallel_for(size_t(0), jobs.size(), [&](size_t k) {
    try {
      outcomes[k] = runJob(jobs[k], names[k], false);
    } catch (const InputError& e) {
      outcomes[k].name = names[k];
      outcomes[k].error = e.what();
    } catch (const std::exception& e) {
      outcomes[k].name = names[k];
      outcomes[k].error = std::string("internal error: ") + e.what();
    }
    std::lock_guard<std::mutex> lock(print);
    const int n = ++done;
    if (!base.quiet)
      std::fprintf(stderr, "  [%d/%zu] %s: %s\n", n, jobs.size(), names[k].c_str(),
                   !outcomes[k].ok ? "error" : outcomes[k].pass ? "pass" : "fail");
  });
  std::string csv = "name,verdict,min_um,max_um,machine_rms_um,percent_in_tolerance,regions,report,error\n";
  int code = 0;
  std::printf("tolver verify --batch %s: %zu jobs\n", base.batch.c_str(), jobs.size());
  std::printf("  %-20s %-7s %10s %10s %12s %8s %8s\n", "name", "verdict", "min um", "max um",
              "machine RMS", "% in", "regions");
  for (const auto& r : outcomes) {
    const std::string verdict = !r.ok ? "error" : r.pass ? "pass" : r.incomplete ? "incomplete"
                                : r.undecided ? "undecided" : "fail";
    code = std::max(code, !r.ok ? 2 : r.pass ? 0 : 1);
    csv += csvLine({r.name, verdict, formatWith("%.3f", r.min_um), formatWith("%.3f", r.max_um),
                    formatWith("%.3f", r.machine_rms_um), formatWith("%.3f", r.percent_in), std::to_string(r.regions),
                    r.report, r.error}) +
           "\n";
    if (r.ok)
      std::printf("  %-20s %-7s %+10.2f %+10.2f %12.2f %8.2f %8d\n", r.name.c_str(), verdict.c_str(), r.min_um,
                  r.max_um, r.machine_rms_um, r.percent_in, r.regions);
    else
      std::printf("  %-20s %-7s %s\n", r.name.c_str(), verdict.c_str(), r.error.c_str());
  }
  const std::string summary = (fs::path(base.report_dir) / "summary.csv").string();
  writeFileAtomically(summary, csv);
  std::printf("  wrote      %s\n", summary.c_str());
  return code;
}

}  // namespace

void registerVerify(CLI::App& app, int* exit_code) {
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
                  "part model (STL, OBJ, PLY, OFF, 3MF, glTF); without it: CL-only mode");
  cmd->add_option("--tolerance", o->in.tolerance_mm, "profile tolerance all over, mm (zone width t)");
  cmd->add_option("--uz", o->in.uz_mm, "ISO 1101 UZ offset of that zone, mm (+ towards material left)");
  cmd->add_option("--asme-u", o->in.asme_u_mm, "ASME Y14.5 U: the part of t outside the material, mm");
  cmd->add_option("--zones", o->in.zones_file, "zones per region (CSV: region,tolerance,uz,u)");
  cmd->add_option("--report-dir", o->report_dir, "directory for the report (created)")->required();
  cmd->add_option("--batch", o->batch,
                  "jobs file (CSV: name,machine,cl,part,tolerance[,setup,zones,probed]); verifies them "
                  "in parallel, one report directory each, and writes summary.csv");
  cmd->add_option("--mesh-units", o->in.mesh_units, "length unit of the part file: mm, inch or m "
                                                  "(default mm; m for glTF)");
  cmd->add_option("--mesh-offset", o->in.mesh_offset, "placement of the part file in the part frame, mm (x,y,z)")
      ->delimiter(',')
      ->expected(3);
  cmd->add_option("--mesh-rotation-deg", o->in.mesh_rotation_deg,
                  "rotation of the part file about x, then y, then z of the part frame, deg (a,b,c)")
      ->delimiter(',')
      ->expected(3);
  cmd->add_option("--spacing", o->in.spacing_mm, "surface sample spacing (remeshing target edge), mm (default 0.5)")->check(CLI::PositiveNumber);
  cmd->add_option("--step", o->in.step_mm, "largest tool advance between placements, mm (default sqrt(0.8 R t))")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--excess-range", o->in.excess_range_mm, "stock above the surface considered, mm (default max(0.1, 5t))")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--gouge-range", o->in.gouge_range_mm, "depth searched for gouges, mm (default max(0.1, 5t))")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--max-hole", o->in.max_hole_mm, "largest mesh hole perimeter filled, mm (default 2 % of the size)");
  cmd->add_option("--tools", o->in.tools,
                  "tool file (CSV: tool,type,diameter_mm,corner_radius_mm,length_mm): the geometry "
                  "of the tools a posted program selects (T1, T=\"name\"), over its comments");
  cmd->add_option("--cutter", o->in.cutter, "cutter d,r[,length,taper_deg] in mm, overriding the program's")
      ->delimiter(',');
  cmd->add_option("--line-pass", o->in.line_pass, "also a line profile along this pass (1-based)")
      ->check(CLI::PositiveNumber);
  cmd->add_flag("--no-images", o->no_images, "write no PNG images (no X server needed)");
  cmd->add_flag("--quiet", o->quiet, "print nothing but errors");
  cmd->add_flag("--absolute", o->in.absolute,
                "a calibrated machine: verify without the set-up a shop measures (part probed, "
                "tool preset), i.e. with what the calibration cannot see left in");
  addProbedOption(cmd, o->in.probed);
  cmd->add_flag("--allow-open", o->in.allow_open,
                "holes in the part's surface (not covered by its mesh) do not make the verdict INCOMPLETE");
  cmd->add_option("--compensated-from", o->in.compensated_from,
                  "the program is the output of tolver compensate for this original: the nominal is "
                  "the original's path, the machine runs the compensated program's joints");
  cmd->callback([o, exit_code] {
    o->in.tolerance_confirmed = !o->tolerance_units.empty();
    if (!o->batch.empty()) {
      *exit_code = runBatch(*o);
      return;
    }
    if (o->in.program.cl.empty() && o->in.program.nc.empty())
      throw InputError("--cl", 0, 0, "cl", "give the program (--cl or --nc) or a jobs file (--batch)");
    if (o->in.machine.machine.empty()) throw InputError("--machine", 0, 0, "machine", "give the machine file (--machine)");
    if (o->tolerance_units == "um" && !std::isnan(o->in.tolerance_mm)) o->in.tolerance_mm = umToMm(o->in.tolerance_mm);
    o->in.tolerance_confirmed = !o->tolerance_units.empty();
    const std::string name =
        fs::path(o->in.program.cl.empty() ? o->in.program.nc : o->in.program.cl).stem().string();
    const JobOutcome r = runJob(*o, name, true);
    *exit_code = r.pass ? 0 : r.undecided ? 4 : 1;
  });
}

}  // namespace tolver::app
