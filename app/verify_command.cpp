// tolver verify: will this program on this machine make this part within its profile tolerance?
// (thesis 5.5.4-5.5.6, by swept surfaces; see geometry/verification.h.)
#include <tbb/parallel_for.h>
#include <unistd.h>

#include <Eigen/Geometry>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <mutex>
#include <string>

#include "app/commands.h"
#include "core/path/prediction_uncertainty.h"
#include "geometry/nearest_point.h"
#include "app/common.h"
#include "core/path/tool_motion.h"
#include "core/path/tool_path_prediction.h"
#include "geometry/cutter.h"
#include "geometry/verification.h"
#include "io/program/apt_reader.h"
#include "io/report/deviation_map.h"
#include "io/common/io_error.h"
#include "io/mesh/mesh_file.h"
#include "io/report/offscreen_display.h"
#include "io/common/text_util.h"
#include "io/report/verify_report.h"
#include "io/machine/zone_file.h"

namespace tolver::app {
namespace {

namespace fs = std::filesystem;

struct VerifyOptions {
  MachineOptions machine;
  ProgramOptions program;
  std::string part, zones_file, report_dir, batch;
  std::string mesh_units, tolerance_units;
  std::vector<double> mesh_offset, mesh_rotation_deg;
  double tolerance = NAN, uz = NAN, asme_u = NAN;
  double spacing = 0.5, step = NAN, excess_range = NAN, gouge_range = NAN, max_hole = -1;
  std::vector<double> cutter;
  int line_pass = 0;
  bool no_images = false;
  bool quiet = false;
  bool absolute = false;
  std::string probed;
  std::string compensated_from;  // the original of a compensated program: the nominal path
  bool allow_open = false;       // holes in the checked surface do not make the verdict INCOMPLETE
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

std::mutex g_vtk_mutex;  // VTK rendering and writing are not thread-safe

// A part file and a program whose sizes differ by the inch factor: one of them is in inches.
void checkPartUnits(const VerifyOptions& o, const ClProgram& program, const TriangleMesh& mesh) {
  if (mesh.vertices.empty() || program.path.empty()) return;
  Eigen::Vector3d lo = mesh.vertices[0], hi = lo, plo = program.path[0].p_w, phi = plo;
  for (const auto& v : mesh.vertices) lo = lo.cwiseMin(v), hi = hi.cwiseMax(v);
  for (const auto& c : program.path) {
    if (c.rapid) continue;
    plo = plo.cwiseMin(c.p_w);
    phi = phi.cwiseMax(c.p_w);
  }
  const double part = (hi - lo).norm(), prog = (phi - plo).norm();
  if (!(part > 0.0) || !(prog > 0.0)) return;
  const double ratio = prog / part;
  char buf[400];
  if (ratio > 12.0 && ratio < 60.0 && o.mesh_units.empty()) {
    std::snprintf(buf, sizeof buf,
                  "the part (diagonal %.3f mm as read) is %.1f times smaller than the program "
                  "(%.1f mm): it looks like inches; give --mesh-units inch",
                  part, ratio, prog);
    throw InputError(o.part, 0, 0, "units", buf);
  }
  if (ratio < 1.0 / 12.0 && ratio > 1.0 / 60.0 && !program.units_declared && o.program.units.empty()) {
    std::snprintf(buf, sizeof buf,
                  "the program declares no units and is %.1f times smaller than the part "
                  "(diagonal %.3f against %.1f mm): it looks like inches; give --cl-units inch",
                  1.0 / ratio, prog, part);
    throw InputError(program.file, 0, 0, "units", buf);
  }
}

std::vector<ToleranceZone> zonesFrom(const VerifyOptions& o) {
  std::vector<ToleranceZone> zones;
  if (!std::isnan(o.tolerance)) {
    // --tolerance is in mm: 30 meant as micrometres would accept gouges of tens of millimetres.
    if (o.tolerance > 1.0 && o.tolerance_units.empty())
      throw InputError("--tolerance", 0, 0, "tolerance",
                       formatNumber(o.tolerance) + " mm is not a plausible profile tolerance: "
                       "--tolerance is in mm (" + formatNumber(o.tolerance / 1000.0) +
                       " for " + formatNumber(o.tolerance) + " um); give --tolerance-units mm to "
                       "confirm a tolerance above 1 mm");
    if (!std::isnan(o.uz) && !std::isnan(o.asme_u))
      throw InputError("--uz", 0, 0, "zone", "give either --uz (ISO) or --asme-u (ASME), not both");
    try {
      zones.push_back(!std::isnan(o.uz)       ? isoUzZone(o.tolerance, o.uz)
                      : !std::isnan(o.asme_u) ? asmeUZone(o.tolerance, o.asme_u)
                                              : bilateralZone(o.tolerance));
    } catch (const std::invalid_argument& e) {
      throw InputError("--tolerance", 0, 0, "tolerance", e.what());
    }
  }
  if (!o.zones_file.empty()) {
    auto more = readZoneFile(o.zones_file);
    zones.insert(zones.end(), more.begin(), more.end());
  }
  if (zones.empty())
    throw InputError("--tolerance", 0, 0, "tolerance", "give --tolerance (mm) or --zones (file)");
  return zones;
}

Cutter cutterFrom(const VerifyOptions& o, const ClProgram& program) {
  Cutter c;
  if (!o.cutter.empty()) {
    std::vector<double> v = o.cutter;
    if (!cutterFromApt("TLDATA", v, &c))
      throw InputError("--cutter", 0, 0, "cutter", "expected d,r[,length,taper_deg] with 0 <= r <= d/2");
    return c;
  }
  if (program.cutters.empty())
    throw InputError(program.file, 0, 0, "CUTTER",
                     "the program declares no cutter (CUTTER or TLDATA; G-code never does); give "
                     "--cutter d,r");
  const CutterSpec& s = program.cutters.back();
  if (!cutterFromApt(s.source, s.values, &c))
    throw InputError(program.file, s.line, 0, s.source, "the values do not describe a cutter");
  return c;
}

std::string fmt(const char* f, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, f, v);
  return buf;
}

// Renders the maps and the histogram; returns (caption, path) pairs.
std::vector<std::pair<std::string, std::string>> renderImages(
    const VerifyOptions& o, const std::string& dir, const SurfaceSamples& s, const VerifyResult& r,
    const std::vector<ToleranceZone>& zones, const std::vector<LineProfilePoint>& profile,
    const std::string& title, std::vector<std::string>* notes, const std::vector<int>* cl_lines) {
  std::vector<std::pair<std::string, std::string>> images;
  if (o.no_images) return images;
  std::string why;
  if (!ensureDisplay(&why)) {
    notes->push_back(why);
    return images;
  }
  std::lock_guard<std::mutex> lock(g_vtk_mutex);
  std::vector<Eigen::Vector3d> points(s.p_w);
  DeviationMap map;
  map.points = &points;
  map.faces = &s.faces;
  map.colours.resize(s.size());
  for (size_t i = 0; i < s.size(); ++i) {
    if (r.conformance[i] == Conformance::Unmachined) map.colours[i] = kUnmachinedColour;
    else if (r.conformance[i] == Conformance::Unchecked) map.colours[i] = kUncheckedColour;
    else map.colours[i] = deviationColour(r.total[i], zones[r.zone[i]].lower, zones[r.zone[i]].upper);
  }
  map.bar_lower = zones.front().lower;
  map.bar_upper = zones.front().upper;
  map.title = title;
  // Callouts: the three worst regions (number, kind, value, where, CL line), or the largest
  // deviation when in tolerance.
  int worst = r.total_stats.max_sample;
  if (r.total_stats.min_sample >= 0 &&
      std::abs(r.total_stats.min) > std::abs(r.total_stats.max))
    worst = r.total_stats.min_sample;
  auto where = [](const Eigen::Vector3d& p) { return fmt("(%.1f, ", p.x()) + fmt("%.1f, ", p.y()) + fmt("%.1f)", p.z()); };
  std::vector<MapView> views = {{"isometric", Eigen::Vector3d(-1, 1, -1), Eigen::Vector3d::UnitZ(), false, {}},
                                {"top", Eigen::Vector3d(0, 0, -1), Eigen::Vector3d::UnitY(), false, {}}};
  auto upFor = [](const Eigen::Vector3d& n) {
    return std::abs(n.z()) > 0.9 ? Eigen::Vector3d::UnitY() : Eigen::Vector3d::UnitZ();
  };
  if (!r.regions.empty()) {
    for (size_t k = 0; k < r.regions.size() && k < 3; ++k) {
      const auto& g = r.regions[k];
      const int line = g.worst_sample >= 0 && r.cl_index[g.worst_sample] >= 0 && cl_lines
                           ? (*cl_lines)[r.cl_index[g.worst_sample]]
                           : 0;
      map.callouts.push_back({g.where_w, "R" + std::to_string(k + 1) + " " + conformanceName(g.kind) + " " +
                                             fmt("%+.1f um", g.worst_deviation * 1e3) + "\n" + where(g.where_w) +
                                             (line > 0 ? " line " + std::to_string(line) : std::string())});
      // The views that show the worst regions: along each one's normal, the whole part.
      views.push_back({k == 0 ? "worst" : "region" + std::to_string(k + 1), -g.normal_w, upFor(g.normal_w), true,
                       g.where_w});
    }
  } else if (worst >= 0) {
    map.callouts.push_back({s.p_w[worst], "largest " + fmt("%+.1f um", r.total[worst] * 1e3) + "\n" + where(s.p_w[worst])});
    views.push_back({"worst", -s.n_w[worst], upFor(s.n_w[worst]), true, s.p_w[worst]});
  }
  for (const auto& v : views) {
    const std::string path = (fs::path(dir) / ("map_" + v.name + ".png")).string();
    renderDeviationMap(path, map, v);
    images.push_back({"deviation map, " + (v.focus ? v.name + " (along the region's normal)" : v.name) + " view", path});
  }
  std::vector<double> dev, w;
  for (size_t i = 0; i < s.size(); ++i)
    if (r.machined[i] && r.zone[i] >= 0) {
      dev.push_back(r.total[i]);
      w.push_back(s.area[i]);
    }
  if (!dev.empty()) {
    const std::string path = (fs::path(dir) / "histogram.png").string();
    renderHistogram(path, dev, w, zones.front().lower, zones.front().upper,
                    "total deviation (predicted swept - CAD), area-weighted");
    images.push_back({"histogram of the total deviation", path});
  }
  if (!profile.empty()) {
    std::vector<double> x, t, m;
    for (const auto& p : profile) {
      x.push_back(p.arc_length);
      t.push_back(p.total);
      m.push_back(p.machine);
    }
    const std::string path = (fs::path(dir) / "line_profile.png").string();
    renderLineProfile(path, x, t, m, zones.front().lower, zones.front().upper,
                      "line profile along pass " + std::to_string(o.line_pass));
    images.push_back({"line profile along pass " + std::to_string(o.line_pass), path});
  }
  return images;
}

JobOutcome runJob(const VerifyOptions& o, const std::string& name, bool progress_bar) {
  const auto t0 = std::chrono::steady_clock::now();
  auto lap = t0;
  std::vector<std::pair<std::string, double>> timings;
  auto phase = [&](const char* what) {
    const auto now = std::chrono::steady_clock::now();
    timings.push_back({what, std::chrono::duration<double>(now - lap).count()});
    lap = now;
  };
  JobOutcome out;
  out.name = name;
  ProgressBar bar(progress_bar && !o.quiet);
  Machine machine = loadMachine(o.machine);
  const std::vector<ToleranceZone> zones = zonesFrom(o);
  ClProgram program = loadProgram(o.program, machine.model);
  const Cutter cutter = cutterFrom(o, program);

  // Joint values and CL_predicted (thesis 5.5.3); a posted program's own rotary solution.
  PredictionResult pred = predictProgram(machine, program);
  // A calibrated machine: after the set-up a shop measures (part probed, tool preset), which
  // the calibration cannot see; and the uncertainty of each CL point's prediction.
  const std::vector<ProbedPoint> probed = loadProbed(o.probed, machine.model);
  const CalibratedPrediction cal = applyCalibration(machine, program, pred, o.absolute, probed);
  const std::vector<PoseUncertainty>& cl_unc = cal.uncertainty;
  std::vector<std::string> probe_warnings;
  std::string setup_note;
  if (cal.probed)
    setup_note = describeProbedSetup(o.probed, cal.probe, probed, &probe_warnings);
  else if (!cl_unc.empty())
    setup_note = o.absolute
                     ? "--absolute: the machine's share includes what probing the part and "
                       "presetting the tool would take up, which the calibration cannot see"
                     : "the machine's share is after the set-up a shop measures (the part probed, "
                       "the tool preset): the ball-bar calibration cannot see either";
  // A compensated program: the machine runs its joints, the nominal is the original's path.
  std::vector<JointVector> q_nominal;
  if (!o.compensated_from.empty()) {
    ProgramOptions po = o.program;
    (po.nc.empty() ? po.cl : po.nc) = o.compensated_from;
    const ClProgram original = loadProgram(po, machine.model);
    if (original.path.size() != program.path.size())
      throw InputError(o.compensated_from, 0, 0, "--compensated-from",
                       "the original has " + std::to_string(original.path.size()) + " tool positions, the "
                       "compensated program " + std::to_string(program.path.size()) +
                       ": give the program compensate read");
    const PredictionResult op = predictProgram(machine, original);
    for (size_t i = 0; i < program.path.size(); ++i) {
      program.path[i].p_w = original.path[i].p_w;
      program.path[i].u_w = original.path[i].u_w;
      q_nominal.push_back(op.points[i].q);
    }
  }
  std::vector<std::string> warnings = setupWarnings(machine.model);
  for (const std::string& w : unitWarnings(program, machine.model, o.program.units)) warnings.push_back(w);
  for (const std::string& w : programNotes(program)) warnings.push_back(program.file + ": " + w);
  for (const std::string& w : probe_warnings) warnings.push_back(w);
  bool no_errors = false;
  const std::string errors = machineErrorsStatement(machine, &no_errors);
  if (no_errors) warnings.push_back(errors);
  for (const RotaryJump& j : findRotaryJumps(machine.model, program.path, pred, 10.0 * M_PI / 180.0))
    warnings.push_back(fmt("program risk: rotary step of %+.1f deg of ", j.step * 180.0 / M_PI) +
                       machine.model.axes[j.axis].name + " between cutting moves at line " +
                       std::to_string(j.line));
  phase("read_and_predict");
  double t_min = INFINITY;
  for (const auto& z : zones) t_min = std::min(t_min, z.tolerance);
  const double r_eff = cutter.corner_radius > 0 ? cutter.corner_radius : 0.5 * cutter.diameter;
  MotionSampling sampling;
  sampling.step = std::isnan(o.step) ? std::clamp(std::sqrt(0.8 * r_eff * t_min), 0.005, 1.0) : o.step;
  sampling.reach = cutter.effectiveLength();
  SweepOptions sweep;
  sweep.excess_range = std::isnan(o.excess_range) ? std::max(0.1, 5.0 * t_min) : o.excess_range;
  sweep.gouge_range = std::isnan(o.gouge_range) ? std::max(0.1, 5.0 * t_min) : o.gouge_range;

  VerifyReport rep;
  rep.name = name;
  rep.machine_name = machine.model.name;
  rep.machine_file = o.machine.machine;
  rep.program_file = program.file;
  rep.notes = warnings;
  rep.cutter = cutter.describe() + ", length " + fmt("%.4g", cutter.effectiveLength()) + " mm" +
               (cutter.length > 0 ? "" : " (assumed: 3 D)");
  rep.cl_points = static_cast<int>(program.path.size());
  for (const auto& p : program.path) rep.cl_lines.push_back(p.line);
  rep.zones = zones;
  rep.step_mm = sampling.step;

  SurfaceSamples samples;
  VerifyResult result;
  if (o.part.empty()) {
    rep.mode = "cl-only";
    std::vector<ClPoint> predicted = program.path;
    for (size_t i = 0; i < predicted.size(); ++i) {
      predicted[i].p_w = pred.points[i].p_pred_w;
      predicted[i].u_w = pred.points[i].u_pred_w;
    }
    clOnlyDeviation(program.path, predicted, zones, &samples, &result);
    rep.notes.push_back("CL-only mode: no part model; the surfaces are built through the CL points "
                        "(thesis 5.5.4-5.5.5) and the deviation is the machine's alone");
  } else {
    PartImportOptions io;
    io.units = o.mesh_units;
    if (!o.mesh_offset.empty()) io.w_T_file.translation() = Eigen::Vector3d(o.mesh_offset[0], o.mesh_offset[1], o.mesh_offset[2]);
    if (!o.mesh_rotation_deg.empty()) {
      const double k = M_PI / 180.0;
      io.w_T_file.linear() = (Eigen::AngleAxisd(o.mesh_rotation_deg[2] * k, Eigen::Vector3d::UnitZ()) *
                              Eigen::AngleAxisd(o.mesh_rotation_deg[1] * k, Eigen::Vector3d::UnitY()) *
                              Eigen::AngleAxisd(o.mesh_rotation_deg[0] * k, Eigen::Vector3d::UnitX()))
                                 .toRotationMatrix();
    }
    io.repair.max_hole_perimeter = o.max_hole;
    const ImportedPart part = readPartMesh(o.part, io);
    checkPartUnits(o, program, part.mesh);
    rep.has_repair = true;
    rep.repair = part.repair;
    rep.part_file = o.part;
    phase("read_part");
    samples = sampleSurface(part.mesh, o.spacing);
    rep.spacing_mm = o.spacing;
    phase("sample_surface");

    ForwardKinematics fk_nominal(machine.model, Eigen::VectorXd::Zero(machine.model.parameterCount()));
    ForwardKinematics fk_actual(machine.model, machine.params);
    std::vector<JointVector> q(pred.points.size());
    for (size_t i = 0; i < q.size(); ++i) q[i] = pred.points[i].q;
    std::vector<ToolPlacement> nominal, actual;
    if (q_nominal.empty())
      samplePlacements(fk_nominal, fk_actual, program.path, q, sampling, &nominal, &actual);
    else
      samplePlacements(fk_nominal, fk_actual, program.path, q_nominal, q, sampling, &nominal, &actual);
    rep.placements = static_cast<int>(nominal.size());
    phase("placements");
    result = verifyPart(samples, cutter, nominal, actual, zones, sweep,
                        [&](double f) { bar("sweeping " + name, f); });
    phase("swept_surfaces");
  }
  rep.samples = &samples;
  rep.result = &result;
  // The 95 % band of the machine's share at each verified sample (the prediction's uncertainty
  // at the nearest CL point, along the sample's normal), and the decision it allows: FAIL when
  // a sample is out of its zone by more than the band, UNDECIDED when a limit lies inside the
  // band of some sample, else PASS.
  if (!cl_unc.empty() && samples.size() > 0) {
    if (!setup_note.empty()) rep.notes.push_back(setup_note);
    std::vector<Eigen::Vector3d> cl(program.path.size());
    for (size_t i = 0; i < cl.size(); ++i) cl[i] = program.path[i].p_w;
    const std::vector<int> nearest = nearestPointIndices(cl, samples.p_w);
    const std::vector<int> zone_of = assignZones(samples, zones);
    double worst_u = 0;
    int definite_fail = 0, undecided = 0, undecided_at = -1;
    rep.band95_um.assign(samples.size(), 0.0);
    for (size_t i = 0; i < samples.size(); ++i) {
      const double u95 = 1.96 * PredictionUncertainty::along(cl_unc[nearest[i]], samples.n_w[i]);
      rep.band95_um[i] = u95 * 1e3;
      worst_u = std::max(worst_u, u95);
      const Conformance c = result.conformance[i];
      if (c == Conformance::Unchecked || c == Conformance::Unmachined || zone_of[i] < 0) continue;
      const ToleranceZone& z = zones[zone_of[i]];
      const double t = result.total[i];
      const double beyond = std::max(t - z.upper, z.lower - t);  // > 0: outside the zone
      if (beyond > u95) ++definite_fail;
      else if (std::abs(beyond) <= u95) {
        if (undecided++ == 0 || std::abs(beyond) < 1e-12) undecided_at = static_cast<int>(i);
      }
    }
    rep.band95_max_um = worst_u * 1e3;
    rep.undecided_samples = undecided;
    if (definite_fail == 0 && undecided > 0) {
      rep.undecided = true;
      const int i = undecided_at;
      char text[400];
      std::snprintf(text, sizeof text,
                    "UNDECIDED: %d samples lie within the prediction's 95 %% band of a zone limit; "
                    "e.g. at (%.2f, %.2f, %.2f) the total is %+.2f um, the machine's share %+.2f "
                    "+- %.2f um here",
                    undecided, samples.p_w[i].x(), samples.p_w[i].y(), samples.p_w[i].z(),
                    result.total[i] * 1e3, result.machine[i] * 1e3, rep.band95_um[i]);
      rep.undecided_text = text;
    }
  }
  if (o.line_pass > 0) {
    const auto passes = clPasses(program.path);
    if (o.line_pass > static_cast<int>(passes.size()))
      throw InputError("--line-pass", 0, 0, "line pass",
                       "the program has " + std::to_string(passes.size()) + " passes, not " +
                           std::to_string(o.line_pass));
    rep.line_pass = o.line_pass;
    rep.line_profile = lineProfile(samples, result, passes[o.line_pass - 1]);
  }

  // Coverage: a hole in the checked surface is area nobody verified.
  if (rep.has_repair && !rep.repair.holes.empty()) {
    const MeshHole& h = rep.repair.holes.front();
    char text[400];
    std::snprintf(text, sizeof text,
                  "%zu holes in the part's surface are not covered by its mesh: %.1f mm2 not verified "
                  "(the first, %.1f mm2, at (%.2f, %.2f, %.2f)); holes with a border shorter than %.2f mm "
                  "are filled (--max-hole)%s",
                  rep.repair.holes.size(), rep.repair.hole_area, h.area, h.centre_w.x(), h.centre_w.y(),
                  h.centre_w.z(), rep.repair.max_hole_perimeter,
                  o.allow_open ? "; --allow-open: not part of the verdict" : "; --allow-open accepts them");
    rep.incomplete_text = std::string("INCOMPLETE: ") + text;
    rep.incomplete = !o.allow_open && result.pass;
    if (o.allow_open || !result.pass) rep.notes.push_back(text);
  }
  // Files: deviations, swept surfaces, images, reports.
  // Written as a whole into a staging directory, swapped in at the end (a killed run leaves the
  // previous report; a concurrent run on the same directory is refused).
  ReportDirectory report_dir(o.report_dir);
  const fs::path dir(report_dir.staging());
  VerifyReport& r = rep;
  writeFileAtomically((dir / "deviations.csv").string(), formatDeviationsCsv(r));
  {
    std::vector<Eigen::Vector3d> nominal_swept(samples.size()), predicted_swept(samples.size());
    std::vector<double> total_um(samples.size()), machine_um(samples.size()), program_um(samples.size()),
        state(samples.size());
    for (size_t i = 0; i < samples.size(); ++i) {
      const bool cut = result.machined[i];
      predicted_swept[i] = samples.p_w[i] + (cut ? result.total[i] : 0.0) * samples.n_w[i];
      nominal_swept[i] = samples.p_w[i] + (cut ? result.program[i] : 0.0) * samples.n_w[i];
      total_um[i] = result.total[i] * 1e3;
      machine_um[i] = result.machine[i] * 1e3;
      program_um[i] = result.program[i] * 1e3;
      state[i] = static_cast<double>(result.conformance[i]);
    }
    writePlyWithScalar((dir / "swept_predicted.ply").string(), predicted_swept, samples.faces, total_um,
                       "deviation_um");
    writePlyWithScalar((dir / "swept_nominal.ply").string(), nominal_swept, samples.faces, program_um,
                       "deviation_um");
    std::lock_guard<std::mutex> lock(g_vtk_mutex);
    writeVtpWithScalars((dir / "swept_predicted.vtp").string(), predicted_swept, samples.faces,
                        {{"total_um", &total_um}, {"machine_um", &machine_um}, {"program_um", &program_um},
                         {"state", &state}});
    writeVtpWithScalars((dir / "swept_nominal.vtp").string(), nominal_swept, samples.faces,
                        {{"program_um", &program_um}});
  }
  phase("write_surfaces");
  const std::string title = verdictName(rep) + "  " + name +
                            ": total deviation (predicted swept - CAD)";
  r.images = renderImages(o, dir.string(), samples, result, zones, r.line_profile, title, &r.notes, &r.cl_lines);
  phase("images");
  r.timings = timings;
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  writeFileAtomically((dir / "report.json").string(), formatVerifyJson(r));
  writeFileAtomically((dir / "report.html").string(), formatVerifyHtml(r));
  report_dir.commit();

  out.ok = true;
  out.pass = verdictName(rep) == "PASS";
  out.undecided = verdictName(rep) == "UNDECIDED";
  out.incomplete = rep.incomplete;
  out.max_um = result.total_stats.max * 1e3;
  out.min_um = result.total_stats.min * 1e3;
  out.machine_rms_um = result.machine_stats.rms * 1e3;
  out.percent_in = result.percent_in;
  out.regions = static_cast<int>(result.regions.size());
  out.report = (fs::path(report_dir.final()) / "report.html").string();

  if (!o.quiet && o.batch.empty()) {
    std::printf("tolver verify: %s\n", verdictName(rep).c_str());
    if (rep.incomplete) std::printf("  %s\n", rep.incomplete_text.c_str());
    else if (rep.undecided) std::printf("  %s\n", rep.undecided_text.c_str());
    std::printf("  machine    %s (%s)\n", machine.model.name.c_str(), o.machine.machine.c_str());
    std::printf("  program    %s (%s): %d CL points, %d tool placements (step %.3g mm), %s\n",
                program.file.c_str(), program.dialect.c_str(), r.cl_points, r.placements,
                r.step_mm, r.cutter.c_str());
    if (r.mode == "cl-only")
      std::printf("  part       none: CL-only mode, %zu points\n", samples.size());
    else
      std::printf("  part       %s: %zu samples at %.3g mm%s\n", o.part.c_str(), samples.size(), o.spacing,
                  r.repair.notes.empty() ? "" : " (mesh repaired: see the report)");
    for (const auto& z : zones)
      std::printf("  zone       %s: %s mm [%+.1f, %+.1f] um\n", z.region.c_str(), z.spec.c_str(),
                  z.lower * 1e3, z.upper * 1e3);
    std::printf("  total      %+.2f .. %+.2f um, RMS %.2f um (+ material left, - gouge)\n",
                result.total_stats.min * 1e3, result.total_stats.max * 1e3, result.total_stats.rms * 1e3);
    if (r.mode != "cl-only")
      std::printf("  program    %+.2f .. %+.2f um (nominal swept - CAD)\n", result.program_stats.min * 1e3,
                  result.program_stats.max * 1e3);
    std::printf("  machine    %+.2f .. %+.2f um, RMS %.2f um (predicted - nominal swept)\n",
                result.machine_stats.min * 1e3, result.machine_stats.max * 1e3, result.machine_stats.rms * 1e3);
    if (result.split_beyond + result.split_boundary > 0)
      std::printf("  split      total = program + machine at every other machined sample; not split: %d "
                  "samples beyond the search range, %d on a cut's boundary (a micrometre of the tool's "
                  "shift moves the boundary across them)\n",
                  result.split_beyond, result.split_boundary);
    if (!cl_unc.empty())
      std::printf("  band       the machine's share is known to +- %.2f um at most (95 %%, from the "
                  "calibration's covariance)%s\n",
                  rep.band95_max_um, o.absolute ? "" : ", after the set-up a shop measures");
    std::printf("  area       %.2f %% of %.1f mm2 machined in tolerance; %.1f mm2 not machined; "
                "%.1f mm2 on edges not verified\n",
                result.percent_in, result.area_machined, result.area_unmachined, result.area_edge);
    for (size_t k = 0; k < result.regions.size() && k < 5; ++k) {
      const auto& g = result.regions[k];
      std::printf("  region %zu   %s %.3f mm2, worst %s um at (%.2f, %.2f, %.2f), cause: %s\n", k + 1,
                  conformanceName(g.kind), g.area_mm2, worstDeviationText(result, g).c_str(), g.where_w.x(),
                  g.where_w.y(), g.where_w.z(), regionCause(r, g).c_str());
    }
    if (result.regions.size() > 5) std::printf("  ...        %zu regions in all\n", result.regions.size());
    for (const auto& n : r.notes) std::fprintf(stderr, "tolver: note: %s\n", n.c_str());
    std::printf("  report     %s (and report.json, deviations.csv, swept_*.ply/.vtp, *.png)\n",
                out.report.c_str());
  }
  return out;
}

// Batch: jobs.csv with columns name,machine,cl,part,tolerance[,setup,zones,probed]; paths relative to
// the jobs file.
int runBatch(const VerifyOptions& base) {
  const std::string text = readFile(base.batch);
  const auto lines = splitLines(text);
  const fs::path root = fs::path(base.batch).parent_path();
  auto resolve = [&](const std::string& p) {
    if (p.empty() || fs::path(p).is_absolute()) return p;
    return (root / p).string();
  };
  std::vector<VerifyOptions> jobs;
  std::vector<std::string> names;
  std::map<std::string, int> col;
  for (size_t i = 0; i < lines.size(); ++i) {
    const auto t = trim(lines[i]);
    if (t.empty() || t[0] == '#') continue;
    const int line = static_cast<int>(i) + 1;
    const auto c = splitCsvLine(lines[i]);
    if (col.empty()) {
      for (size_t k = 0; k < c.size(); ++k) col[c[k]] = static_cast<int>(k);
      for (const char* r : {"name", "machine", "cl", "tolerance"})
        if (!col.count(r)) throw InputError(base.batch, line, 0, r, "missing column (name,machine,cl,part,tolerance[,setup,zones,probed])");
      continue;
    }
    auto cell = [&](const char* n) -> std::string {
      auto it = col.find(n);
      return it == col.end() || it->second >= static_cast<int>(c.size()) ? "" : c[it->second];
    };
    VerifyOptions o = base;
    o.batch.clear();
    o.quiet = true;
    o.machine.machine = resolve(cell("machine"));
    o.machine.setup = resolve(cell("setup"));
    o.probed = resolve(cell("probed"));
    o.program.cl = resolve(cell("cl"));
    o.program.nc.clear();
    o.part = resolve(cell("part"));
    o.zones_file = resolve(cell("zones"));
    const auto tol = parseNumber(cell("tolerance"));
    if (!tol && o.zones_file.empty())
      throw InputError(base.batch, line, col["tolerance"] + 1, "tolerance", "'" + cell("tolerance") + "' is not a number");
    o.tolerance = tol ? *tol : NAN;
    const std::string name = cell("name");
    if (name.empty() || name.find('/') != std::string::npos || name == "." || name == "..")
      throw InputError(base.batch, line, col["name"] + 1, "name", "a job name is a plain file name");
    // Two jobs of one name would write one directory, one report lost.
    if (std::find(names.begin(), names.end(), name) != names.end())
      throw InputError(base.batch, line, col["name"] + 1, "name",
                       "job '" + name + "' is named twice: each job needs its own name");
    o.report_dir = (fs::path(base.report_dir) / name).string();
    jobs.push_back(o);
    names.push_back(name);
  }
  if (jobs.empty()) throw InputError(base.batch, 0, 0, "jobs", "the file lists no job");
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
    char buf[512];
    std::snprintf(buf, sizeof buf, "%s,%s,%.3f,%.3f,%.3f,%.3f,%d,%s,\"%s\"\n", r.name.c_str(), verdict.c_str(),
                  r.min_um, r.max_um, r.machine_rms_um, r.percent_in, r.regions, r.report.c_str(),
                  r.error.c_str());
    csv += buf;
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
  addMachineOptions(cmd, o->machine, "machine file (XML), calibrated or not");
  cmd->get_option("--machine")->required(false);  // a batch names its machines in the jobs file
  addProgramOptions(cmd, o->program);
  cmd->add_option("--tolerance-units", o->tolerance_units,
                  "unit of --tolerance: mm (default; needed to confirm one above 1 mm) or um")
      ->check(CLI::IsMember({"mm", "um"}));
  cmd->add_option("--part", o->part,
                  "part model (STL, OBJ, PLY, OFF, 3MF, glTF); without it: CL-only mode");
  cmd->add_option("--tolerance", o->tolerance, "profile tolerance all over, mm (zone width t)");
  cmd->add_option("--uz", o->uz, "ISO 1101 UZ offset of that zone, mm (+ towards material left)");
  cmd->add_option("--asme-u", o->asme_u, "ASME Y14.5 U: the part of t outside the material, mm");
  cmd->add_option("--zones", o->zones_file, "zones per region (CSV: region,tolerance,uz,u)");
  cmd->add_option("--report-dir", o->report_dir, "directory for the report (created)")->required();
  cmd->add_option("--batch", o->batch,
                  "jobs file (CSV: name,machine,cl,part,tolerance[,setup,zones,probed]); verifies them "
                  "in parallel, one report directory each, and writes summary.csv");
  cmd->add_option("--mesh-units", o->mesh_units, "length unit of the part file: mm, inch or m "
                                                  "(default mm; m for glTF)");
  cmd->add_option("--mesh-offset", o->mesh_offset, "placement of the part file in the part frame, mm (x,y,z)")
      ->delimiter(',')
      ->expected(3);
  cmd->add_option("--mesh-rotation-deg", o->mesh_rotation_deg,
                  "rotation of the part file about x, then y, then z of the part frame, deg (a,b,c)")
      ->delimiter(',')
      ->expected(3);
  cmd->add_option("--spacing", o->spacing, "surface sample spacing (remeshing target edge), mm (default 0.5)")->check(CLI::PositiveNumber);
  cmd->add_option("--step", o->step, "largest tool advance between placements, mm (default sqrt(0.8 R t))")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--excess-range", o->excess_range, "stock above the surface considered, mm (default max(0.1, 5t))")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--gouge-range", o->gouge_range, "depth searched for gouges, mm (default max(0.1, 5t))")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--max-hole", o->max_hole, "largest mesh hole perimeter filled, mm (default 2 % of the size)");
  cmd->add_option("--cutter", o->cutter, "cutter d,r[,length,taper_deg] in mm, overriding the program's")
      ->delimiter(',');
  cmd->add_option("--line-pass", o->line_pass, "also a line profile along this pass (1-based)")
      ->check(CLI::PositiveNumber);
  cmd->add_flag("--no-images", o->no_images, "write no PNG images (no X server needed)");
  cmd->add_flag("--quiet", o->quiet, "print nothing but errors");
  cmd->add_flag("--absolute", o->absolute,
                "a calibrated machine: verify without the set-up a shop measures (part probed, "
                "tool preset), i.e. with what the calibration cannot see left in");
  addProbedOption(cmd, o->probed);
  cmd->add_flag("--allow-open", o->allow_open,
                "holes in the part's surface (not covered by its mesh) do not make the verdict INCOMPLETE");
  cmd->add_option("--compensated-from", o->compensated_from,
                  "the program is the output of tolver compensate for this original: the nominal is "
                  "the original's path, the machine runs the compensated program's joints");
  cmd->callback([o, exit_code] {
    if (!o->batch.empty()) {
      *exit_code = runBatch(*o);
      return;
    }
    if (o->program.cl.empty() && o->program.nc.empty())
      throw InputError("--cl", 0, 0, "cl", "give the program (--cl or --nc) or a jobs file (--batch)");
    if (o->machine.machine.empty()) throw InputError("--machine", 0, 0, "machine", "give the machine file (--machine)");
    if (o->tolerance_units == "um" && !std::isnan(o->tolerance)) {
      o->tolerance /= 1000.0;
      o->tolerance_units = "mm";
    }
    const std::string name =
        fs::path(o->program.cl.empty() ? o->program.nc : o->program.cl).stem().string();
    const JobOutcome r = runJob(*o, name, true);
    *exit_code = r.pass ? 0 : r.undecided ? 4 : 1;
  });
}

}  // namespace tolver::app
