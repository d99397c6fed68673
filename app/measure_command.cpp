// tolver measure: the machined part's measured points against the prediction, and the effects
// that explain the difference (pipeline/measure.h).
#include <cmath>
#include <cstdio>
#include <memory>

#include "app/commands.h"
#include "app/common.h"
#include "core/numerics/units.h"
#include "pipeline/measure.h"

namespace tolver::app {
namespace {

struct MeasureOptions {
  MeasureInputs in;
  bool quiet = false, no_images = false;
};

void printMeasurement(const MeasureRun& run) {
  const MeasureReport& r = run.report;
  const PartTrace& t = r.trace;
  std::printf("tolver measure: %s\n", t.verdict_text.c_str());
  std::printf(
      "  points     %zu in %s: %d used (%d fit, %d held out), %d beyond the %.3g mm "
      "search range, %d beyond an edge, %d on faces not machined\n",
      r.rows.size(), r.points_file.c_str(), r.used, t.fit_points, t.heldout_points, r.beyond_range,
      r.search_mm, r.off_face, r.unmachined);
  std::printf(
      "  deviation  measured RMS %.2f um, predicted RMS %.2f um; residual (measured - "
      "predicted) RMS %.2f um, max %.2f um\n",
      mmToUm(r.measured_rms), mmToUm(r.predicted_rms), mmToUm(r.residual_rms),
      mmToUm(r.residual_max));
  for (const TraceGroup& g : t.groups) {
    if (!g.added) continue;
    std::printf("  added      %s: %s", g.name.c_str(), describeTracedValues(g).c_str());
    std::printf(" (%s; held-out gain %.3g +- %.2g um2)\n", g.reason.c_str(), g.heldout_gain_um2,
                g.heldout_gain_se_um2);
    if (!g.confounded.empty()) {
      std::printf("  confounded");
      for (size_t k = 0; k < g.confounded.size(); ++k)
        std::printf("%s%s", k ? ", " : " ", g.confounded[k].c_str());
      std::printf(": these points cannot tell them from %s\n", g.name.c_str());
    }
  }
  for (const TraceGroup& g : t.groups)
    if (!g.added && !g.reason.empty())
      std::printf("  not added  %s: %s\n", g.name.c_str(), g.reason.c_str());
  std::printf("  before     held-out RMS %.2f um, max %.2f um (fit points %.2f um)\n",
              mmToUm(t.heldout_rms_before), mmToUm(t.heldout_max_before), mmToUm(t.fit_rms_before));
  std::printf("  after      held-out RMS %.2f um, max %.2f um (fit points %.2f um)\n",
              mmToUm(t.heldout_rms_after), mmToUm(t.heldout_max_after), mmToUm(t.fit_rms_after));
  if (r.worst_row >= 0) {
    const MeasureRow& w = r.rows[r.worst_row];
    std::printf(
        "  largest    %+.2f um after, at (%.3f, %.3f, %.3f) (points line %d), %s, CL line "
        "%d, tool %d%s\n",
        mmToUm(w.residual_after), w.p_w.x(), w.p_w.y(), w.p_w.z(), w.line,
        w.region.empty() ? "no region" : ("region " + w.region).c_str(), w.cl_line, w.tool + 1,
        w.operation.empty() ? "" : (", operation " + w.operation).c_str());
  }
  for (const std::string& n : r.notes) std::printf("  note       %s\n", n.c_str());
  if (!run.report_dir.empty())
    std::printf("  wrote      %s/{residuals.csv,report.json,report.html,process.txt%s%s%s}\n",
                run.report_dir.c_str(), r.machine_written.empty() ? "" : ",machine.xml",
                r.images.empty() ? "" : ",",
                [&] {
                  std::string s;
                  for (size_t k = 0; k < r.images.size(); ++k) s += (k ? "," : "") + r.images[k];
                  return s;
                }()
                    .c_str());
}

}  // namespace

void registerMeasure(CLI::App& app, Verdict* verdict) {
  auto o = std::make_shared<MeasureOptions>();
  CLI::App* cmd = app.add_subcommand(
      "measure",
      "Close the loop on a machined part: its measured points (CMM or probe) against the "
      "prediction, and the effects that explain the difference (set-up, cutter radius and "
      "length, stock, the calibrated machine's parameters), before and after on held-out "
      "points. Exit 0 done, 2 bad input.");
  addMachineOptions(cmd, o->in.verify.machine, "machine file (XML), calibrated or not");
  addProgramOptions(cmd, o->in.verify.program);
  cmd->add_option("--part", o->in.verify.part, "part model (STEP, STL, OBJ, PLY, ...)")->required();
  cmd->add_option("--points", o->in.points,
                  "measured points (CSV x_mm,y_mm,z_mm[,nx,ny,nz][,deviation_mm], or an ASC "
                  "point cloud), in the part file's frame")
      ->required();
  cmd->add_option("--tolerance", o->in.verify.tolerance_mm,
                  "the part's profile tolerance, mm (sets the sweep's step and ranges)")
      ->required();
  cmd->add_option("--search", o->in.search_mm,
                  "farthest a point may lie from the nominal surface, mm (default 0.5)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--heldout-every", o->in.heldout_every,
                  "hold every N-th used point out of the fit (default 5)");
  cmd->add_option("--report-dir", o->in.report_dir, "directory for the report (created)")
      ->required();
  cmd->add_option("--mesh-units", o->in.verify.mesh_units, "length unit of the part file");
  cmd->add_option("--mesh-offset", o->in.verify.mesh_offset,
                  "placement of the part file in the part frame, mm (x,y,z)")
      ->delimiter(',')
      ->expected(3);
  cmd->add_option("--tools", o->in.verify.tools, "tool file (CSV), as verify's");
  cmd->add_option("--cutter", o->in.verify.cutter,
                  "cutter d,r[,length,taper_deg] in mm, overriding the program's")
      ->delimiter(',');
  cmd->add_flag("--absolute", o->in.verify.absolute,
                "a calibrated machine: without the set-up a shop measures");
  cmd->add_option("--process", o->in.verify.process,
                  "process corrections the prediction already holds (a previous process.txt); "
                  "the new process.txt adds what this part shows to them");
  cmd->add_flag("--quiet", o->quiet, "print nothing but errors");
  cmd->add_flag("--no-images", o->no_images,
                "write no PNG maps or histograms (no X server needed)");
  cmd->callback([o, verdict] {
    o->in.images = !o->no_images;
    ProgressBar bar(!o->quiet);
    const MeasureRun run = measurePart(o->in, progressOf(bar));
    if (!o->quiet) printMeasurement(run);
    *verdict = run.verdict;
  });
}

}  // namespace tolver::app
