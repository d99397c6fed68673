// The verify pipeline: see pipeline/verify.h.
#include "pipeline/verify.h"

#include <tbb/parallel_for.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <future>
#include <map>
#include <memory>
#include <mutex>
#include <numeric>
#include <string>

#include "core/numerics/quantities.h"
#include "core/numerics/units.h"
#include "core/path/prediction_uncertainty.h"
#include "core/path/tool_motion.h"
#include "core/path/tool_path_prediction.h"
#include "geometry/cutter.h"
#include "geometry/nearest_point.h"
#include "io/common/io_error.h"
#include "io/common/text_util.h"
#include "io/machine/zone_file.h"
#include "io/mesh/mesh_file.h"
#include "io/program/apt_reader.h"
#include "io/program/compensated_program.h"
#include "io/program/process_file.h"
#include "io/program/tool_file.h"
#include "io/report/deviation_map.h"
#include "io/report/offscreen_display.h"

namespace tolver {
namespace {

namespace fs = std::filesystem;

std::mutex g_vtk_mutex;  // VTK rendering and writing are not thread-safe

// A part file and a program whose sizes differ by the inch factor: one of them is in inches.
void checkPartUnits(const VerifyInputs& o, const ClProgram& program, const TriangleMesh& mesh) {
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
                  "(%.1f mm): it looks like inches; give %s inch",
                  part, ratio, prog, inputName("mesh_units").c_str());
    throw InputError(o.part, 0, 0, "units", buf);
  }
  if (ratio < 1.0 / 12.0 && ratio > 1.0 / 60.0 && !program.units_declared &&
      o.program.units.empty()) {
    std::snprintf(buf, sizeof buf,
                  "the program declares no units and is %.1f times smaller than the part "
                  "(diagonal %.3f against %.1f mm): it looks like inches; give %s inch",
                  1.0 / ratio, prog, part, inputName("units").c_str());
    throw InputError(program.file, 0, 0, "units", buf);
  }
  // The cutting moves' tool tips must come near the part: boxes apart by more than a tenth of
  // the larger one's diagonal mean the part is not where the program cuts (set-up, mesh frame).
  const double gap = std::max({(lo - phi).maxCoeff(), (plo - hi).maxCoeff(), 0.0});
  if (gap > 0.1 * std::max(part, prog) + 1.0) {
    std::snprintf(
        buf, sizeof buf,
        "the part is not where the program cuts: %.1f mm between the part (x %.0f..%.0f, "
        "y %.0f..%.0f, z %.0f..%.0f mm) and the cutting moves (x %.0f..%.0f, y %.0f..%.0f, "
        "z %.0f..%.0f); check the set-up, %s or the program's frame",
        gap, lo.x(), hi.x(), lo.y(), hi.y(), lo.z(), hi.z(), plo.x(), phi.x(), plo.y(), phi.y(),
        plo.z(), phi.z(), inputName("mesh_offset").c_str());
    throw InputError(o.part, 0, 0, "position", buf);
  }
}

std::vector<ToleranceZone> zonesFrom(const VerifyInputs& o, const ImportedPart* part,
                                     std::vector<std::string>* notes) {
  std::vector<ToleranceZone> zones;
  if (!std::isnan(o.tolerance_mm)) {
    // The tolerance is in mm: 30 meant as micrometres would accept gouges of tens of millimetres.
    const std::string problem =
        outOfRange(Quantity::ProfileTolerance, o.tolerance_mm, o.tolerance_confirmed);
    if (!problem.empty())
      throw FieldError(
          "tolerance_mm",
          problem + (o.tolerance_mm > rangeOf(Quantity::ProfileTolerance).hi
                         ? ": give " + inputName("tolerance_units") + " mm to confirm it"
                         : ""));
    if (!std::isnan(o.uz_mm) && !std::isnan(o.asme_u_mm))
      throw FieldError("uz_mm", "give either " + inputName("uz_mm") + " (ISO) or " +
                                    inputName("asme_u_mm") + " (ASME), not both");
    try {
      zones.push_back(!std::isnan(o.uz_mm)       ? isoUzZone(o.tolerance_mm, o.uz_mm)
                      : !std::isnan(o.asme_u_mm) ? asmeUZone(o.tolerance_mm, o.asme_u_mm)
                                                 : bilateralZone(o.tolerance_mm));
    } catch (const std::invalid_argument& e) {
      throw FieldError("tolerance_mm", e.what());
    }
  }
  // A drawing's own tolerances on its faces override the general one; a zone file's rows, last,
  // override both.
  if (part && part->cad) {
    const auto pmi = pmiZones(*part->cad, part->mesh, notes);
    zones.insert(zones.end(), pmi.begin(), pmi.end());
  }
  if (!o.zones_file.empty()) {
    auto more = readZoneFile(o.zones_file, o.tolerance_confirmed);
    zones.insert(zones.end(), more.begin(), more.end());
  }
  if (zones.empty())
    throw FieldError("tolerance_mm", "give " + inputName("tolerance_mm") + " (mm) or " +
                                         inputName("zones_file") + " (file)" +
                                         (part && part->cad ? ": the STEP file has no profile "
                                                              "tolerance in its PMI"
                                                            : ""));
  // A zone naming a region that the part does not have would check nothing, silently.
  if (part)
    for (const ToleranceZone& z : zones) {
      if (z.has_box || z.region == "*" || z.region.empty()) continue;
      bool found = false;
      for (size_t g = 0; g < part->mesh.group_names.size() && !found; ++g) {
        found = part->mesh.group_names[g] == z.region;
        if (g < part->mesh.group_aliases.size())
          for (const std::string& a : part->mesh.group_aliases[g]) found = found || a == z.region;
      }
      if (!found) {
        // Its regions, then the CAD names and colours they may be called by, each once.
        std::vector<std::string> names = part->mesh.group_names, aliases;
        if (names.size() > 6) names.resize(6), names.push_back("...");
        for (const auto& as : part->mesh.group_aliases)
          for (const std::string& a : as)
            if (std::find(aliases.begin(), aliases.end(), a) == aliases.end()) aliases.push_back(a);
        if (aliases.size() > 6) aliases.resize(6), aliases.push_back("...");
        names.insert(names.end(), aliases.begin(), aliases.end());
        std::string list;
        for (const std::string& n : names) list += (list.empty() ? "'" : ", '") + n + "'";
        throw InputError(o.zones_file, 0, 0, "region",
                         "no region or CAD face of " + o.part + " is named '" + z.region +
                             "' (its regions: " + list + ")");
      }
    }
  return zones;
}

// The cutters the program cuts with: --cutter for every move, or each CUTTER/TLDATA of the
// program for the moves after it (the first one also for the moves before it: a tool change
// switches the cutter). A cutter statement that describes no cutter is an error naming it.
ToolSet toolsFrom(const VerifyInputs& o, const ClProgram& program) {
  ToolSet tools;
  Cutter c;
  if (!o.cutter.empty()) {
    std::vector<double> v = o.cutter;
    if (!cutterFromApt("TLDATA", v, &c))
      throw FieldError("cutter", "expected d,r[,length,taper_deg] with 0 <= r <= d/2");
    tools.cutters = {c};
    return tools;
  }
  if (program.cutters.empty())
    throw InputError(program.file, 0, 0, "CUTTER",
                     "the program declares no cutter (CUTTER or TLDATA; in G-code a tool comment "
                     "such as Fusion's (T1 D=6 CR=0)); give " +
                         inputName("cutter") + " d,r");
  // The shop's tool file describes the tools it names (over the program's comments).
  std::vector<CutterSpec> specs = program.cutters;
  if (!o.tools.empty()) {
    const std::map<std::string, ToolEntry> file = readToolFile(o.tools);
    for (CutterSpec& s : specs) {
      auto it = file.find(toUpper(s.kind));
      if (it != file.end()) {
        s.values = it->second.values;
        s.source = "TLDATA";
      }
    }
  }
  std::string unknown;
  for (const CutterSpec& s : specs)
    if (s.values.empty())
      unknown += (unknown.empty() ? "" : ", ") + s.kind + " (line " + std::to_string(s.line) + ")";
  if (!unknown.empty())
    throw InputError(program.file, 0, 0, "tool",
                     "the program cuts with " + unknown +
                         ", whose geometry it does not give (no "
                         "tool comment): describe them in a tool file (" +
                         inputName("tools") + "), or give " + inputName("cutter") + " d,r for all");
  for (const CutterSpec& s : specs) {
    if (!cutterFromApt(s.source, s.values, &c))
      throw InputError(program.file, s.line, 0, s.source, "the values do not describe a cutter");
    tools.cutters.push_back(c);
  }
  if (tools.cutters.size() == 1) return tools;
  tools.tool_of_cl = program.toolOfPoints();
  return tools;
}

std::string describeCutter(const Cutter& c) {
  return c.describe() + ", length " + formatWith("%.4g", c.effectiveLength()) + " mm" +
         (c.length > 0 ? "" : " (assumed: 3 D)");
}

// Renders the maps and the histogram; returns (caption, path) pairs.
std::vector<std::pair<std::string, std::string>> renderImages(
    int line_pass, const std::string& dir, const SurfaceSamples& s, const VerifyResult& r,
    const std::vector<ToleranceZone>& zones, const std::vector<LineProfilePoint>& profile,
    const std::string& title, std::vector<std::string>* notes, const std::vector<int>* cl_lines,
    const DecimatedMesh* mesh) {
  std::vector<std::pair<std::string, std::string>> images;
  std::string why;
  if (!ensureDisplay(&why)) {
    notes->push_back(why);
    return images;
  }
  std::lock_guard<std::mutex> lock(g_vtk_mutex);
  // The surface: every sample, or the 3D view's decimated mesh (its vertices are samples, with
  // their own colours).
  const bool decimated = mesh && !mesh->vertex.empty() && mesh->vertex.size() < s.size();
  std::vector<Eigen::Vector3d> points;
  DeviationMap map;
  map.points = &points;
  map.faces = decimated ? &mesh->faces : &s.faces;
  const size_t n = decimated ? mesh->vertex.size() : s.size();
  points.resize(n);
  map.colours.resize(n);
  for (size_t k = 0; k < n; ++k) {
    const size_t i = decimated ? static_cast<size_t>(mesh->vertex[k]) : k;
    points[k] = s.p_w[i];
    map.colours[k] = sampleColour(r, zones, i);
  }
  if (decimated)
    notes->push_back("the deviation maps are drawn on the 3D view's mesh: " + std::to_string(n) +
                     " of " + std::to_string(s.size()) + " samples, every sample within " +
                     formatWith("%.3g", mesh->max_distance_mm) + " mm of it and within " +
                     formatWith("%.3g", mmToUm(mesh->max_value_difference)) +
                     " um of the value drawn over it, one CAD face, zone and state per triangle" +
                     (mesh->given_faces_drawn > 0
                          ? "; " + std::to_string(mesh->given_faces_drawn) + " of the part's " +
                                std::to_string(s.given_faces.size()) + " faces drawn as given"
                          : std::string()));
  map.bar_lower = zones.front().lower;
  map.bar_upper = zones.front().upper;
  map.title = title;
  // Callouts: the three worst regions (number, kind, value, where, CL line), or the largest
  // deviation when in tolerance.
  int worst = r.total_stats.max_sample;
  if (r.total_stats.min_sample >= 0 && std::abs(r.total_stats.min) > std::abs(r.total_stats.max))
    worst = r.total_stats.min_sample;
  auto where = [](const Eigen::Vector3d& p) {
    return formatWith("(%.1f, ", p.x()) + formatWith("%.1f, ", p.y()) + formatWith("%.1f)", p.z());
  };
  // The views that show the worst regions look along each one's normal at the whole part.
  const std::vector<MapView> views = deviationMapViews(s, r);
  if (!r.regions.empty()) {
    for (size_t k = 0; k < r.regions.size() && k < 3; ++k) {
      const auto& g = r.regions[k];
      const int line = g.worst_sample >= 0 && r.cl_index[g.worst_sample] >= 0 && cl_lines
                           ? (*cl_lines)[r.cl_index[g.worst_sample]]
                           : 0;
      map.callouts.push_back(
          {g.where_w, "R" + std::to_string(k + 1) + " " + conformanceName(g.kind) + " " +
                          formatWith("%+.1f um", mmToUm(g.worst_deviation)) + "\n" +
                          where(g.where_w) +
                          (line > 0 ? " line " + std::to_string(line) : std::string())});
    }
  } else if (worst >= 0) {
    map.callouts.push_back(
        {s.p_w[worst],
         "largest " + formatWith("%+.1f um", mmToUm(r.total[worst])) + "\n" + where(s.p_w[worst])});
  }
  std::vector<std::pair<std::string, MapView>> maps;
  for (const auto& v : views) {
    const std::string path = (fs::path(dir) / ("map_" + v.name + ".png")).string();
    maps.push_back({path, v});
    images.push_back(
        {"deviation map, " + (v.focus ? v.name + " (along the region's normal)" : v.name) + " view",
         path});
  }
  renderDeviationMaps(maps, map);
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
                      "line profile along pass " + std::to_string(line_pass));
    images.push_back({"line profile along pass " + std::to_string(line_pass), path});
  }
  return images;
}

// Work budgets, so that no input makes verify run for hours or exhaust memory: an input that
// would exceed one is refused, saying which budget and what to change.
constexpr double kMaxSamples = 5e6;     // surface samples (the remeshed part at --spacing)
constexpr double kMaxPlacements = 2e7;  // tool placements per sweep (the path at --step)

// The remeshed part's sample count, from its area: isotropic triangles of edge s have area
// (sqrt(3)/4) s^2, and a closed mesh has half as many vertices as faces; plus the points its
// edges are cut into (pieces of up to 4/3 s), which a face of no area (a long needle) still has.
void checkSampleBudget(const VerifyInputs& o, const TriangleMesh& mesh) {
  double area = 0, perimeter = 0;
  for (const Eigen::Vector3i& f : mesh.faces) {
    const Eigen::Vector3d& a = mesh.vertices[f[0]];
    const Eigen::Vector3d& b = mesh.vertices[f[1]];
    const Eigen::Vector3d& c = mesh.vertices[f[2]];
    area += 0.5 * (b - a).cross(c - a).norm();
    perimeter += (b - a).norm() + (c - b).norm() + (a - c).norm();
  }
  const double s = o.spacing_mm;
  const double samples = area / (std::sqrt(3.0) / 2.0 * s * s) + 0.5 * perimeter / (4.0 / 3.0 * s);
  // The spacing that fits: the count is a x^2 + b x in x = 1 / spacing, so the spacing is
  // (b + sqrt(b^2 + 4 a N)) / 2N (this form holds for a part of no area too); 0.1 % above it, so
  // that the three digits printed still fit.
  const double qa = area / (std::sqrt(3.0) / 2.0), qb = 0.5 * perimeter / (4.0 / 3.0);
  const double fitting =
      (qb + std::sqrt(qb * qb + 4.0 * qa * kMaxSamples)) / (2.0 * kMaxSamples) * 1.001;
  if (samples > kMaxSamples)
    throw FieldError(
        "spacing_mm",
        formatWith("the part, %.0f mm2 of surface at ", area) + formatWith("%g mm spacing", s) +
            formatWith(" make about %.3g surface samples, above the budget of ", samples) +
            formatWith("%.0f: give ", kMaxSamples) + inputName("spacing_mm") + " " +
            formatWith("%.3g or more", fitting));
}

// The placements of a sweep, from the path's length at the step.
void checkPlacementBudget(const ClProgram& program, const MotionSampling& sampling) {
  double length = 0;
  for (size_t i = 1; i < program.path.size(); ++i)
    length += (program.path[i].p_w - program.path[i - 1].p_w).norm();
  const double placements = length / sampling.step;
  if (placements > kMaxPlacements)
    throw FieldError(
        "step_mm", formatWith("the program, %.0f mm of tool path at ", length) +
                       formatWith("a %g mm step make about ", sampling.step) +
                       formatWith("%.3g tool placements, above the budget of ", placements) +
                       formatWith("%.0f: give ", kMaxPlacements) + inputName("step_mm") + " " +
                       formatWith("%.3g or more (or a larger tolerance)", length / kMaxPlacements));
}

// Phase timings: the seconds since the previous lap, by name.
class PhaseClock {
 public:
  explicit PhaseClock(std::vector<std::pair<std::string, double>>* timings)
      : timings_(timings), lap_(std::chrono::steady_clock::now()) {}
  void operator()(const char* what) {
    const auto now = std::chrono::steady_clock::now();
    timings_->push_back({what, std::chrono::duration<double>(now - lap_).count()});
    lap_ = now;
  }

 private:
  std::vector<std::pair<std::string, double>>* timings_;
  std::chrono::steady_clock::time_point lap_;
};

// The program on the machine: joints and CL_predicted, the measured set-up and the uncertainty
// on a calibrated machine, the nominal joints of a compensated program's original, and what the
// planner should know about them.
struct ProgramOnMachine {
  Machine machine;
  ClProgram program;
  PredictionResult pred;
  CalibratedPrediction cal;
  std::vector<JointVector> q_nominal;  // --compensated-from: the original's joints
  std::string setup_note;
  std::vector<std::string> warnings;
};

// A compensated program: the machine runs its joints, the nominal is the original's path.
void useOriginalAsNominal(const VerifyInputs& o, ProgramOnMachine& m) {
  ProgramOptions po = o.program;
  (po.nc.empty() ? po.cl : po.nc) = o.compensated_from;
  const ClProgram original = loadProgram(po, m.machine.model);
  if (original.path.size() != m.program.path.size())
    throw FieldError("compensated_from", o.compensated_from + ": the original has " +
                                             std::to_string(original.path.size()) +
                                             " tool positions, the "
                                             "compensated program " +
                                             std::to_string(m.program.path.size()) +
                                             ": give the program compensate read");
  const PredictionResult op = predictProgram(m.machine, original);
  for (size_t i = 0; i < m.program.path.size(); ++i) {
    m.program.path[i].p_w = original.path[i].p_w;
    m.program.path[i].u_w = original.path[i].u_w;
    m.q_nominal.push_back(op.points[i].q);
  }
}

ProgramOnMachine predictOnMachine(const VerifyInputs& o) {
  ProgramOnMachine m;
  m.machine = loadMachine(o.machine);
  m.program = loadProgram(o.program, m.machine.model);
  // Joint values and CL_predicted ([AM01] 5.5.3); a posted program's own rotary solution.
  m.pred = predictProgram(m.machine, m.program);
  // A calibrated machine: after the set-up a shop measures (part probed, tool preset), which
  // the calibration cannot see; and the uncertainty of each CL point's prediction.
  const std::vector<ProbedPoint> probed = loadProbed(o.probed, m.machine.model);
  m.cal = applyCalibration(m.machine, m.program, m.pred, o.absolute, probed);
  std::vector<std::string> probe_warnings;
  if (m.cal.probed)
    m.setup_note = describeProbedSetup(o.probed, m.cal.probe, probed, &probe_warnings);
  else if (!m.cal.uncertainty.empty())
    m.setup_note =
        o.absolute ? inputName("absolute") +
                         ": the machine's share includes what probing the part and "
                         "presetting the tool would take up, which the calibration cannot see"
                   : "the machine's share is after the set-up a shop measures (the part probed, "
                     "the tool preset): the ball-bar calibration cannot see either";
  if (!o.compensated_from.empty()) useOriginalAsNominal(o, m);
  const MachineModel& model = m.machine.model;
  m.warnings = setupWarnings(model);
  for (const std::string& w : unitWarnings(m.program, model, o.program.units))
    m.warnings.push_back(w);
  for (const std::string& w : programNotes(m.program))
    m.warnings.push_back(m.program.file + ": " + w);
  for (const std::string& w : probe_warnings) m.warnings.push_back(w);
  bool no_errors = false;
  const std::string errors = machineErrorsStatement(m.machine, &no_errors);
  if (no_errors) m.warnings.push_back(errors);
  for (const RotaryJump& j : findRotaryJumps(model, m.program.path, m.pred, degToRad(10.0)))
    m.warnings.push_back(
        formatWith("program risk: rotary step of %+.1f deg of ", radToDeg(j.step)) +
        model.axes[j.axis].name + " between cutting moves at line " + std::to_string(j.line));
  return m;
}

}  // namespace

Eigen::Isometry3d partPlacement(const VerifyInputs& o) {
  Eigen::Isometry3d w_T_file = Eigen::Isometry3d::Identity();
  if (!o.mesh_offset.empty())
    w_T_file.translation() = Eigen::Vector3d(o.mesh_offset[0], o.mesh_offset[1], o.mesh_offset[2]);
  if (!o.mesh_rotation_deg.empty()) {
    const double k = degToRad(1.0);
    w_T_file.linear() = (Eigen::AngleAxisd(o.mesh_rotation_deg[2] * k, Eigen::Vector3d::UnitZ()) *
                         Eigen::AngleAxisd(o.mesh_rotation_deg[1] * k, Eigen::Vector3d::UnitY()) *
                         Eigen::AngleAxisd(o.mesh_rotation_deg[0] * k, Eigen::Vector3d::UnitX()))
                            .toRotationMatrix();
  }
  // A measured part showed it sitting elsewhere on the table: the part's true pose.
  if (!o.process.empty()) return readProcessFile(o.process).part_error * w_T_file;
  return w_T_file;
}

namespace {

// The part file read, placed in w and repaired.
ImportedPart readPart(const VerifyInputs& o) {
  PartImportOptions io;
  io.units = o.mesh_units;
  io.w_T_file = partPlacement(o);
  io.repair.max_hole_perimeter = o.max_hole_mm;
  // A STEP part's chordal tolerance follows the sample spacing (spacing / 500), and is never
  // above 1 um: the facets' distance to the B-rep reads as deviation of the program, and 1 um is
  // 5 % of a 20 um zone (a 4 um tessellation of the NAS 979 cone put 11 % of its flank out).
  io.chordal_mm = std::min(o.spacing_mm / 500.0, 0.001);
  io.part_name = o.part_name;
  return readPartMesh(o.part, io);
}

// A measured part's thermal drift (the tip further out along the axis by the rate times the
// program's clock at the placement) and sideways deflection (along a x f, f the move's
// direction), on the predicted placements.
void applyTimedCorrections(const std::vector<ClPoint>& path, const ToolSet& tools,
                           const ProcessCorrections& process, std::vector<ToolPlacement>& actual,
                           std::vector<std::string>& notes) {
  if (process.drift_mm_per_h == 0.0 && process.across_feed_mm.empty()) return;
  const std::vector<double> t_min = programTimes(path);
  if (process.drift_mm_per_h != 0.0 && t_min.empty())
    notes.push_back(
        "the process file's thermal drift is not applied: the program's cutting moves have no "
        "feed rate in mm/min");
  for (ToolPlacement& a : actual) {
    const int i = a.cl_index;
    if (i < 1 || i >= static_cast<int>(path.size())) continue;
    const Eigen::Vector3d move = path[i].p_w - path[i - 1].p_w;
    const double len = move.norm();
    if (!t_min.empty() && process.drift_mm_per_h != 0.0) {
      // The placement's share of its move: its tip's distance from the move's start.
      const double frac =
          len > 0 ? std::clamp((a.tip_w - path[i - 1].p_w).norm() / len, 0.0, 1.0) : 1.0;
      const double t_h = (t_min[i - 1] + frac * (t_min[i] - t_min[i - 1])) / 60.0;
      a.tip_w -= process.drift_mm_per_h * t_h * a.axis_w;
    }
    const int k = tools.tool_of_cl.empty() ? 0 : tools.tool_of_cl[i];
    const auto it = process.across_feed_mm.find(k);
    if (it != process.across_feed_mm.end() && len > 0)
      a.tip_w += it->second * a.axis_w.cross(move / len);
  }
}

// The nominal and the predicted tool placements along the program, swept over the samples.
void sweepPart(const ProgramOnMachine& m, const ToolSet& tools, const ProcessCorrections& process,
               const std::vector<ToleranceZone>& zones, const MotionSampling& sampling,
               const SweepOptions& sweep, Verification& v, PhaseClock& phase,
               const std::function<void(double)>& progress) {
  const MachineModel& model = m.machine.model;
  ForwardKinematics fk_nominal(model, Eigen::VectorXd::Zero(model.parameterCount()));
  ForwardKinematics fk_actual(model, m.machine.params);
  std::vector<JointVector> q(m.pred.points.size());
  for (size_t i = 0; i < q.size(); ++i) q[i] = m.pred.points[i].q;
  std::vector<ToolPlacement> nominal, actual;
  const std::vector<JointVector>& q_nominal = m.q_nominal.empty() ? q : m.q_nominal;
  if (!fk_actual.model().effects.empty()) {
    samplePlacements(fk_nominal, fk_actual, m.program.path, q_nominal, q, sampling, &nominal,
                     &actual);
  } else {
    // In pieces of the path on both cores, joined in order (the same placements).
    const size_t n = m.program.path.size(), piece = 8192, pieces = (n + piece - 1) / piece;
    std::vector<std::vector<ToolPlacement>> nom(pieces), act(pieces);
    tbb::parallel_for(size_t(0), pieces, [&](size_t k) {
      samplePlacementsOf(fk_nominal, fk_actual, m.program.path, q_nominal, q, sampling, k * piece,
                         std::min(n, (k + 1) * piece), &nom[k], &act[k]);
    });
    size_t total = 0;
    for (const auto& piece_placements : nom) total += piece_placements.size();
    nominal.reserve(total);
    actual.reserve(total);
    for (size_t k = 0; k < pieces; ++k) {
      nominal.insert(nominal.end(), nom[k].begin(), nom[k].end());
      actual.insert(actual.end(), act[k].begin(), act[k].end());
    }
  }
  v.report.placements = static_cast<int>(nominal.size());
  // The tools as a measured part showed them: longer than preset (the tip further out along
  // the axis), radii off (the length preset to the tip: a ball's centre moves with its radius).
  ToolSet actual_tools = tools;
  for (const auto& [k, dr] : process.radius_mm) {
    if (k >= static_cast<int>(tools.cutters.size())) continue;
    Cutter& c = actual_tools.cutters[k];
    const bool ball = c.corner_radius >= 0.5 * c.diameter - 1e-9;
    c.diameter += 2.0 * dr;
    if (ball) c.corner_radius += dr;
  }
  if (!process.length_mm.empty())
    for (ToolPlacement& a : actual) {
      const int k = tools.tool_of_cl.empty() ? 0 : tools.tool_of_cl[a.cl_index];
      const auto it = process.length_mm.find(k);
      if (it != process.length_mm.end()) a.tip_w -= it->second * a.axis_w;
    }
  applyTimedCorrections(m.program.path, tools, process, actual, v.report.notes);
  phase("placements");
  v.result =
      verifyPart(v.samples, tools, actual_tools, nominal, actual, zones, sweep, [&](double f) {
        if (progress) progress(f);
      });
  phase("swept_surfaces");
}

// The operations of a program for the convention check: runs of CL points with one tool, one
// frame and one kind of words, cut where a rapid turns a rotary axis (a 3+2 index).
std::vector<std::pair<int, int>> programOperations(const ClProgram& p, const MachineModel& model,
                                                   const ToolSet& tools) {
  std::vector<std::pair<int, int>> ops;
  const int n = static_cast<int>(p.path.size());
  int first = 0;
  for (int i = 1; i <= n; ++i) {
    bool cut = i == n;
    if (!cut && !tools.tool_of_cl.empty()) cut = tools.tool_of_cl[i] != tools.tool_of_cl[i - 1];
    if (!cut && i < static_cast<int>(p.point_frame.size()))
      cut = p.point_frame[i] != p.point_frame[i - 1];
    if (!cut && i < static_cast<int>(p.tcp.size())) cut = p.tcp[i] != p.tcp[i - 1];
    if (!cut && p.path[i].rapid && i < static_cast<int>(p.joints.size()))
      for (size_t a = 0; a < model.axes.size(); ++a)
        if (model.axes[a].isRotary() && std::abs(p.joints[i][a] - p.joints[i - 1][a]) > 1e-3)
          cut = true;
    if (cut) {
      ops.emplace_back(first, i - 1);
      first = i;
    }
  }
  return ops;
}

// The convention check (issue 32): a posted program's rotary words place the tool as the post
// meant only if the machine file turns its rotary axes the same way and from the same zero.
// When most of the machined surface is gouged beyond the search range, or most of what one
// five-axis or indexed operation cuts, the program is read again under each other convention
// of the rotary axes (each axis's sense reversed, its zero half a turn away, or both) and its
// nominal sweep measured: a convention under which the cut fits names it, instead of a verdict
// that blames the program or the machine.
class ConventionCheck {
 public:
  ConventionCheck(const VerifyInputs& o, const ProgramOnMachine& m, const ToolSet& tools,
                  const MotionSampling& sampling, const SweepOptions& sweep, const Verification& v)
      : o_(o),
        program_(m.program),
        model_(m.machine.model),
        tools_(tools),
        sampling_(sampling),
        sweep_(sweep),
        v_(v) {}

  void run() {
    if (program_.dialect != "G-code" || !gcodeGivesRotaryWords(program_, model_)) return;
    if (program_.joints.size() != program_.path.size()) return;
    ops_ = programOperations(program_, model_, tools_);
    op_of_.assign(program_.path.size(), 0);
    for (size_t k = 0; k < ops_.size(); ++k)
      for (int i = ops_[k].first; i <= ops_[k].second; ++i) op_of_[i] = static_cast<int>(k);
    for (size_t a = 0; a < model_.axes.size(); ++a)
      if (model_.axes[a].isRotary()) rotary_.push_back(static_cast<int>(a));
    countAsRead();
    const std::vector<int> suspects = suspectOperations();
    if (suspects.empty()) return;
    makeVariants();
    after_.resize(variants_.size());
    for (size_t vi = 0; vi < variants_.size(); ++vi) countUnder(vi);
    for (int s : suspects) nameConvention(s);
  }

 private:
  // Samples cut (deepest) by an operation, and those beyond the gouge limit.
  struct Count {
    size_t machined = 0, beyond = 0;
    double share() const {
      return machined ? static_cast<double>(beyond) / static_cast<double>(machined) : 0.0;
    }
  };
  // One rotary axis's change of convention.
  struct Change {
    int axis;
    bool sense, zero;
  };

  // The counts under the machine file's convention, per operation; index ops_.size() is the
  // whole program.
  void countAsRead() {
    const VerifyResult& r = v_.result;
    before_.assign(ops_.size() + 1, Count{});
    for (size_t i = 0; i < r.machined.size(); ++i) {
      if (!r.machined[i]) continue;
      const int k = r.cl_index[i] >= 0 ? op_of_[r.cl_index[i]] : -1;
      for (int idx : {k, static_cast<int>(ops_.size())}) {
        if (idx < 0) continue;
        ++before_[idx].machined;
        before_[idx].beyond += r.total_beyond[i] ? 1 : 0;
      }
    }
  }

  // Suspect: the whole program gouged on 30 % of what it cuts, or an operation that turns a
  // rotary axis gouged on half of what it cuts.
  std::vector<int> suspectOperations() const {
    std::vector<int> suspects;
    const Count& all = before_.back();
    if (all.machined >= 20 && all.share() >= 0.3) suspects.push_back(static_cast<int>(ops_.size()));
    for (size_t k = 0; k < ops_.size() && ops_.size() > 1; ++k) {
      bool turned = false;
      for (int i = ops_[k].first; i <= ops_[k].second && !turned; ++i)
        for (int a : rotary_) turned = turned || std::abs(program_.joints[i][a]) > 1e-6;
      if (turned && before_[k].machined >= 20 && before_[k].share() >= 0.5)
        suspects.push_back(static_cast<int>(k));
    }
    return suspects;
  }

  // The conventions tried: each rotary axis as in the machine file, its sense reversed, its zero
  // half a turn away, or both (every combination but the file's own).
  void makeVariants() {
    const int combos = static_cast<int>(std::pow(4.0, static_cast<double>(rotary_.size())));
    for (int c = 1; c < combos; ++c) {
      std::vector<Change> ch;
      for (size_t k = 0, code = static_cast<size_t>(c); k < rotary_.size(); ++k, code /= 4)
        if (code % 4) ch.push_back({rotary_[k], (code % 4 & 1) != 0, (code % 4 & 2) != 0});
      variants_.push_back(ch);
    }
  }

  // The program read again and swept under variant vi: the counts of every operation and the
  // whole (left empty when it does not read).
  void countUnder(size_t vi) {
    MachineModel mm = model_;
    for (const Change& c : variants_[vi]) {
      Axis& ax = mm.axes[c.axis];
      if (c.sense) {
        ax.nc_sign = -ax.nc_sign;
        const double lo = ax.travel_min;
        ax.travel_min = -ax.travel_max;
        ax.travel_max = -lo;
      }
      // Zero half a turn away: joint q of the file's machine is q + pi of this one.
      if (c.zero) ax.parent_T_joint = ax.parent_T_joint * Eigen::AngleAxisd(kPi, ax.direction);
    }
    ClProgram p;
    try {
      p = loadProgram(o_.program, mm);
    } catch (const InputError&) {
      return;  // the program does not read with this convention (a rotary word out of travel)
    }
    if (p.path.size() != program_.path.size()) return;
    const ForwardKinematics fk(mm, Eigen::VectorXd::Zero(mm.parameterCount()));
    std::vector<ToolPlacement> nominal, unused;
    samplePlacements(fk, fk, p.path, p.joints, sampling_, &nominal, &unused);
    SweepResult res;
    sweepSurface(v_.samples, tools_, nominal, sweep_, &res);
    const double floor_mm = -sweep_.gouge_range + 1e-9;
    std::vector<Count>& cnt = after_[vi];
    cnt.assign(ops_.size() + 1, Count{});
    for (size_t i = 0; i < res.machined.size(); ++i) {
      if (!res.machined[i] || res.placement[i] < 0) continue;
      const int k = op_of_[nominal[res.placement[i]].cl_index];
      for (int idx : {k, static_cast<int>(ops_.size())}) {
        ++cnt[idx].machined;
        cnt[idx].beyond += res.deviation[i] <= floor_mm ? 1 : 0;
      }
    }
  }

  // A convention in words ("C turns the other way"), and in *fix what to set in the machine file.
  std::string describe(const std::vector<Change>& change, std::string* fix) const {
    std::string what;
    for (size_t k = 0; k < change.size(); ++k) {
      const Change& c = change[k];
      const std::string& name = model_.axes[c.axis].name;
      what += std::string(k == 0                   ? ""
                          : k + 1 == change.size() ? " and "
                                                   : ", ") +
              (c.sense && c.zero ? name + " turns the other way from a zero half a turn away"
               : c.sense         ? name + " turns the other way"
                                 : "the zero of " + name + " is half a turn away");
      if (fix)
        *fix += std::string(k == 0 ? "" : ", ") + (c.sense ? "the nc_sign of " + name : "") +
                (c.sense && c.zero ? " and " : "") +
                (c.zero ? "the zero of " + name + " (its link rotation)" : "");
    }
    return what;
  }

  // The convention under which suspect s fits best, when it fits (a tenth of the gouges and a
  // third of the file's): an InputError naming it, and the others that fit as well.
  void nameConvention(int s) const {
    const double share0 = before_[s].share();
    double best_share = 1.0;
    int best = -1;
    for (size_t vi = 0; vi < variants_.size(); ++vi) {
      if (after_[vi].empty() || after_[vi][s].machined < before_[s].machined / 2) continue;
      // A tie goes to the convention tried first (one axis before two).
      if (after_[vi][s].share() < best_share - 1e-12)
        best_share = after_[vi][s].share(), best = static_cast<int>(vi);
    }
    if (best < 0 || best_share > 0.1 || best_share > share0 / 3.0) return;
    std::string fix;
    const std::string what = describe(variants_[best], &fix);
    // Conventions that fit as well cannot be told apart by this part: named, so the user checks.
    // (Not those that add changes to the best one: the program does not see what they add.)
    auto adds = [&](const std::vector<Change>& a) {
      for (const Change& b : variants_[best]) {
        bool in = false;
        for (const Change& c : a)
          in = in || (c.axis == b.axis && c.sense == b.sense && c.zero == b.zero);
        if (!in) return false;
      }
      return true;
    };
    std::string also;
    for (size_t vi = 0; vi < variants_.size(); ++vi)
      if (static_cast<int>(vi) != best && !after_[vi].empty() &&
          after_[vi][s].machined >= before_[s].machined / 2 &&
          after_[vi][s].share() <= best_share + 0.005 && !adds(variants_[vi]))
        also += (also.empty() ? "" : "; or ") + describe(variants_[vi], nullptr);
    const bool whole = s == static_cast<int>(ops_.size());
    const std::string where =
        whole
            ? "the program's cut fits the part"
            : "the operation of lines " + std::to_string(program_.path[ops_[s].first].line) + "-" +
                  std::to_string(program_.path[ops_[s].second].line) + " fits the part it cuts";
    throw InputError(
        o_.machine.machine, 0, 0, "convention",
        what + " in this program compared with the machine file: with that convention " + where +
            " (gouged beyond " + formatWith("%.3g", sweep_.gouge_range) + " mm on " +
            formatWith("%.1f", 100.0 * best_share) + " % of the surface it cuts instead of " +
            formatWith("%.1f", 100.0 * share0) + " %)" +
            (also.empty() ? ""
                          : " (it fits as well if " + also + ": the part cannot tell them apart)") +
            ": set " + fix + " in the machine file to the control's convention");
  }

  const VerifyInputs& o_;
  const ClProgram& program_;
  const MachineModel& model_;
  const ToolSet& tools_;
  const MotionSampling& sampling_;
  const SweepOptions& sweep_;
  const Verification& v_;
  std::vector<std::pair<int, int>> ops_;  // first and last CL point of each operation
  std::vector<int> op_of_;                // per CL point, its operation
  std::vector<int> rotary_;               // the rotary axes
  std::vector<Count> before_;
  std::vector<std::vector<Change>> variants_;
  std::vector<std::vector<Count>> after_;  // per variant
};

void checkRotaryConvention(const VerifyInputs& o, const ProgramOnMachine& m, const ToolSet& tools,
                           const MotionSampling& sampling, const SweepOptions& sweep,
                           const Verification& v) {
  ConventionCheck(o, m, tools, sampling, sweep, v).run();
}

// The 95 % band of the machine's share at each verified sample (the prediction's uncertainty
// at the CL point whose move cut it, along the sample's normal at its contact on the cutter:
// the tip's and the tool axis's errors with the contact's lever arm; at the nearest CL point
// where no move cut it), and the decision it allows: FAIL when
// a sample is out of its zone by more than the band, UNDECIDED when a limit lies inside the
// band of some sample, else PASS.
void decideWithinBand(const std::vector<PoseUncertainty>& cl_unc, const ClProgram& program,
                      const std::vector<ToleranceZone>& zones, Verification& v) {
  VerifyReport& rep = v.report;
  const SurfaceSamples& samples = v.samples;
  const VerifyResult& result = v.result;
  // The nearest CL point stands in only where no move cut the sample (its band is shown, not
  // decided on).
  std::vector<int> nearest;
  if (std::find(result.cl_index.begin(), result.cl_index.end(), -1) != result.cl_index.end()) {
    std::vector<Eigen::Vector3d> cl(program.path.size());
    for (size_t i = 0; i < cl.size(); ++i) cl[i] = program.path[i].p_w;
    nearest = nearestPointIndices(cl, samples.p_w);
  }
  const std::vector<int> zone_of = assignZones(samples, zones);
  double worst_u = 0;
  int definite_fail = 0, undecided = 0, undecided_at = -1;
  rep.band95_um.assign(samples.size(), 0.0);
  for (size_t i = 0; i < samples.size(); ++i) {
    const int cut_by = result.cl_index[i];
    const double u95 =
        cut_by >= 0
            ? 1.96 * PredictionUncertainty::alongContact(cl_unc[cut_by], samples.n_w[i],
                                                         result.contact_offset_w[i].cast<double>())
            : 1.96 * PredictionUncertainty::along(cl_unc[nearest[i]], samples.n_w[i]);
    rep.band95_um[i] = mmToUm(u95);
    worst_u = std::max(worst_u, u95);
    const Conformance c = result.conformance[i];
    if (c == Conformance::Unchecked || c == Conformance::Unmachined || zone_of[i] < 0) continue;
    const ToleranceZone& z = zones[zone_of[i]];
    const double t = result.total[i];
    const double beyond = std::max(t - z.upper, z.lower - t);  // > 0: outside the zone
    if (beyond > u95)
      ++definite_fail;
    else if (std::abs(beyond) <= u95) {
      if (undecided++ == 0 || std::abs(beyond) < 1e-12) undecided_at = static_cast<int>(i);
    }
  }
  rep.band95_max_um = mmToUm(worst_u);
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
                  mmToUm(result.total[i]), mmToUm(result.machine[i]), rep.band95_um[i]);
    rep.undecided_text = text;
  }
}

// Coverage: a hole in the checked surface is area nobody verified.
void reportHoles(bool allow_open, Verification& v) {
  VerifyReport& rep = v.report;
  const VerifyResult& result = v.result;
  if (!rep.has_repair || rep.repair.holes.empty()) return;
  const MeshHole& h = rep.repair.holes.front();
  char text[400];
  std::snprintf(
      text, sizeof text,
      "%zu holes in the part's surface are not covered by its mesh: %.1f mm2 not verified "
      "(the first, %.1f mm2, at (%.2f, %.2f, %.2f)); holes with a border shorter than %.2f mm "
      "are filled (%s)%s",
      rep.repair.holes.size(), rep.repair.hole_area, h.area, h.centre_w.x(), h.centre_w.y(),
      h.centre_w.z(), rep.repair.max_hole_perimeter, inputName("max_hole_mm").c_str(),
      ("; " + inputName("allow_open") +
       (allow_open ? ": not part of the verdict" : " accepts them"))
          .c_str());
  rep.incomplete_text = std::string("INCOMPLETE: ") + text;
  rep.incomplete = !allow_open && result.pass;
  if (allow_open || !result.pass) rep.notes.push_back(text);
}

}  // namespace

std::vector<ToleranceZone> pmiZones(const StepPart& cad, const TriangleMesh& mesh,
                                    std::vector<std::string>* notes) {
  std::vector<ToleranceZone> zones;
  std::vector<double> widths;
  for (const StepTolerance& t : cad.tolerances) {
    const std::string label = t.type + " " + formatNumber(t.value_mm) + " mm" +
                              (t.name.empty() ? "" : " ('" + t.name + "')");
    // A composite frame (ASME Y14.5 10.5.1) reads as two tolerances of one name on the same
    // faces: the wider, located segment is checked; the refining one floats in location.
    const bool refining =
        std::any_of(cad.tolerances.begin(), cad.tolerances.end(), [&](const StepTolerance& u) {
          return &u != &t && u.type == t.type && u.name == t.name && u.faces == t.faces &&
                 u.value_mm > t.value_mm;
        });
    if (refining) {
      notes->push_back("PMI " + label +
                       ": the refining segment of a composite frame, not checked "
                       "(its zone is not located on the nominal surface)");
      continue;
    }
    if (t.type != "profile of a surface" || t.faces.empty() || !(t.value_mm > 0)) {
      notes->push_back("PMI " + label + " on " + std::to_string(t.faces.size()) +
                       " faces: not checked (verify checks profile of a surface only)");
      continue;
    }
    ToleranceZone z;
    try {
      z = t.unequal ? isoUzZone(t.value_mm, t.offset_mm) : bilateralZone(t.value_mm);
    } catch (const std::invalid_argument& e) {
      notes->push_back("PMI " + label + ": not checked (" + e.what() + ")");
      continue;
    }
    z.spec += " (PMI" + (t.name.empty() ? std::string() : " '" + t.name + "'") + ")";
    for (int g : t.faces) {
      z.region = mesh.group_names[g];
      zones.push_back(z);
      widths.push_back(t.value_mm);
    }
    notes->push_back("PMI " + label + (t.unequal ? " UZ " + formatNumber(t.offset_mm) : "") +
                     " on " + std::to_string(t.faces.size()) +
                     " faces: checked as a profile zone on the nominal surface in the part frame "
                     "(datum references are not evaluated)");
  }
  // A face under two frames must lie in both: the narrower zone comes last, so it decides.
  std::vector<size_t> order(zones.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t a, size_t b) { return widths[a] > widths[b]; });
  std::vector<ToleranceZone> sorted;
  for (size_t i : order) sorted.push_back(zones[i]);
  return sorted;
}

std::unique_ptr<Verification> runVerification(const VerifyInputs& o, const std::string& name,
                                              const std::function<void(double)>& progress) {
  auto v = std::make_unique<Verification>();
  v->started = std::chrono::steady_clock::now();
  VerifyReport& rep = v->report;
  PhaseClock phase(&rep.timings);
  std::unique_ptr<ImportedPart> part;
  if (!o.part.empty()) {
    part = std::make_unique<ImportedPart>(readPart(o));
    phase("read_part");
  } else if (!o.part_name.empty()) {
    throw FieldError("part_name", "names a solid of a STEP part: give the part too");
  } else if (!o.process.empty()) {
    throw FieldError("process", "corrects the part's set-up and the tools' sweep: give the part");
  }
  std::vector<std::string> zone_notes;
  const std::vector<ToleranceZone> zones = zonesFrom(o, part.get(), &zone_notes);
  const ProgramOnMachine m = predictOnMachine(o);
  const ClProgram& program = m.program;
  const ToolSet tools = toolsFrom(o, program);
  phase("read_and_predict");
  double t_min = INFINITY;
  for (const auto& z : zones) t_min = std::min(t_min, z.tolerance);
  double r_eff = INFINITY;  // the smallest cutter sets the step
  for (const Cutter& c : tools.cutters)
    r_eff = std::min(r_eff, c.corner_radius > 0 ? c.corner_radius : 0.5 * c.diameter);
  MotionSampling sampling;
  sampling.step =
      std::isnan(o.step_mm) ? std::clamp(std::sqrt(0.8 * r_eff * t_min), 0.005, 1.0) : o.step_mm;
  sampling.reach = tools.maxLength();
  SweepOptions sweep;
  sweep.excess_range =
      std::isnan(o.excess_range_mm) ? std::max(0.1, 5.0 * t_min) : o.excess_range_mm;
  sweep.gouge_range = std::isnan(o.gouge_range_mm) ? std::max(0.1, 5.0 * t_min) : o.gouge_range_mm;

  rep.name = name;
  rep.machine_name = m.machine.model.name;
  rep.machine_file = o.machine.machine;
  rep.program_file = program.file;
  rep.notes = m.warnings;
  rep.notes.insert(rep.notes.end(), zone_notes.begin(), zone_notes.end());
  // A drill's point (APT CUTTER alpha with no corner radius) is swept as a flat end.
  for (const CutterSpec& c : program.cutters)
    if (o.cutter.empty() && c.source == "CUTTER" && c.values.size() > 4 && c.values[4] > 0 &&
        c.values[1] == 0)
      rep.notes.push_back("the cutter of line " + std::to_string(c.line) + " has a point (alpha " +
                          formatNumber(c.values[4]) +
                          " deg): it is swept as a flat end, so the "
                          "bottoms of its holes read as gouges up to its point's height");
  if (tools.cutters.size() == 1) {
    rep.cutter = describeCutter(tools.cutters[0]);
  } else {
    rep.cutter = std::to_string(tools.cutters.size()) + " tools, each from its line on:";
    for (size_t k = 0; k < tools.cutters.size(); ++k)
      rep.cutter += (k ? "; " : " ") + std::string("line ") +
                    std::to_string(program.cutters[k].line) + " " +
                    describeCutter(tools.cutters[k]);
  }
  rep.cl_points = static_cast<int>(program.path.size());
  for (const auto& p : program.path) rep.cl_lines.push_back(p.line);
  rep.zones = zones;
  rep.step_mm = sampling.step;
  v->machine_file = o.machine.machine;
  v->program_dialect = program.dialect;
  v->banded = !m.cal.uncertainty.empty();
  if (o.part.empty()) {
    rep.mode = "cl-only";
    std::vector<ClPoint> predicted = program.path;
    for (size_t i = 0; i < predicted.size(); ++i) {
      predicted[i].p_w = m.pred.points[i].p_pred_w;
      predicted[i].u_w = m.pred.points[i].u_pred_w;
    }
    std::vector<double> width(program.path.size(), 0.0);
    for (size_t i = 0; i < width.size(); ++i) {
      const int k = tools.tool_of_cl.empty() ? 0 : tools.tool_of_cl[i];
      if (k >= 0 && k < static_cast<int>(tools.cutters.size()))
        width[i] = 2.0 * tools.cutters[k].maxRadius();
    }
    clOnlyDeviation(program.path, predicted, zones, width, &v->samples, &v->result);
    size_t along = 0, lone = 0;  // samples on a move between its CL points; on no strip
    for (size_t i = 0; i < v->samples.size(); ++i) {
      along += v->samples.p_w[i] != program.path[v->result.cl_index[i]].p_w;
      lone += !(v->samples.area[i] > 0);
    }
    rep.notes.push_back(
        "CL-only mode: no part model; the surfaces are built through the CL points "
        "(thesis 5.5.4-5.5.5) and the deviation is the machine's alone" +
        (along == 0
             ? std::string()
             : "; " + std::to_string(along) + " of its " + std::to_string(v->samples.size()) +
                   " points lie on moves longer than the gap between neighbouring passes, "
                   "between their CL points (nominal and predicted interpolated)"));
    if (lone > 0)
      rep.notes.push_back(
          std::to_string(lone) + " of the " + std::to_string(v->samples.size()) +
          " points lie on no surface through the CL points (no pass beside theirs within the "
          "cutter's width: a single pass or contour, a drilled hole, a flank pass): their "
          "deviation is taken along the tool axis" +
          (lone == v->samples.size() ? "; give the part (--part) to check a surface" : ""));
  } else {
    checkPartUnits(o, program, part->mesh);
    checkSampleBudget(o, part->mesh);
    checkPlacementBudget(program, sampling);
    rep.has_repair = true;
    rep.repair = part->repair;
    rep.part_file = o.part;
    if (part->cad) {
      const StepPart& c = *part->cad;
      rep.cad = true;
      rep.cad_text = "STEP: " + (c.system.empty() ? std::string("system not named") : c.system) +
                     ", " + c.schema + ", unit " + c.file_unit + "; solid '" + c.solid + "' of " +
                     std::to_string(c.solids.size()) + "; " + std::to_string(c.faces.size()) +
                     formatWith(" CAD faces, %.1f mm2; ", c.area_mm2) +
                     formatWith("tessellated within %.2g um (chordal", mmToUm(c.chordal_mm)) +
                     (c.deflection_mm > c.chordal_mm
                          ? formatWith(" asked; BRepMesh reports %.2g um on its worst face)",
                                       mmToUm(c.deflection_mm))
                          : std::string(")")) +
                     formatWith(" and %.2g deg", radToDeg(c.angular_rad));
      for (const std::string& n : c.notes) rep.notes.push_back(o.part + ": " + n);
    }
    v->samples = o.samples_at ? o.samples_at(part->mesh) : sampleSurface(part->mesh, o.spacing_mm);
    part.reset();  // the samples are what the rest needs
    rep.spacing_mm = o.spacing_mm;
    phase("sample_surface");
    const ProcessCorrections process =
        o.process.empty() ? ProcessCorrections{} : readProcessFile(o.process);
    for (const std::string& k : process.not_applied)
      rep.notes.push_back(o.process + ": " + k + " is reported, not applied");
    sweepPart(m, tools, process, zones, sampling, sweep, *v, phase, progress);
    checkRotaryConvention(o, m, tools, sampling, sweep, *v);
  }
  rep.samples = &v->samples;
  rep.result = &v->result;
  if (o.keep_poses) {
    Verification::Poses& k = v->poses;
    k.q.resize(m.pred.points.size());
    k.path = program.path;
    k.tool.assign(program.path.size(), 0);
    for (size_t i = 0; i < k.q.size(); ++i) k.q[i] = m.pred.points[i].q;
    for (size_t i = 0; i < k.path.size() && i < tools.tool_of_cl.size(); ++i)
      k.tool[i] = tools.tool_of_cl[i];
    k.cutters = tools.cutters;
    k.operations = program.operations;
    k.machine = m.machine;
  }
  if (rep.mode == "part") rep.region_table = summariseRegions(v->samples, v->result);
  if (v->banded && v->samples.size() > 0) {
    if (!m.setup_note.empty()) rep.notes.push_back(m.setup_note);
    decideWithinBand(m.cal.uncertainty, program, zones, *v);
    rep.band_lack_of_fit_um = mmToUm(m.machine.identification.lack_of_fit_mm);
    rep.band_spindle_tilt_urad = radToUrad(m.machine.identification.spindle_tilt_rad);
  }
  if (o.line_pass > 0) {
    const auto passes = clPasses(program.path);
    if (o.line_pass > static_cast<int>(passes.size()))
      throw FieldError("line_pass", "the program has " + std::to_string(passes.size()) +
                                        " passes, not " + std::to_string(o.line_pass));
    rep.line_pass = o.line_pass;
    rep.line_profile = lineProfile(v->samples, v->result, passes[o.line_pass - 1]);
  }
  reportHoles(o.allow_open, *v);
  // A program that cuts none of the checked surface verifies nothing: INCOMPLETE, never PASS.
  if (!o.part.empty() && v->samples.size() > 0 && !(v->result.area_machined > 0)) {
    rep.incomplete = true;
    rep.incomplete_text = "INCOMPLETE: the program cuts none of the checked surface (" +
                          formatWith("%.1f", v->result.area) +
                          " mm2 sampled, none machined): is this the part the "
                          "program makes, placed where it cuts (the set-up, " +
                          inputName("mesh_offset") + ")?";
  }
  v->verdict = v->report.incomplete  ? Verdict::NotMet
               : v->report.undecided ? Verdict::Undecided
               : v->result.pass      ? Verdict::Ok
                                     : Verdict::NotMet;
  rep.exit_code = exitCode(v->verdict);
  return v;
}

DecimatedMesh viewMesh(const SurfaceSamples& s, const VerifyResult& r,
                       const std::vector<ToleranceZone>& zones, double spacing_mm,
                       const std::function<void(double)>& progress) {
  std::vector<double> value(s.size());
  std::vector<int> category(s.size());
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(INFINITY), hi = -lo;
  const int zone_count = static_cast<int>(zones.size());
  for (size_t i = 0; i < s.size(); ++i) {
    const bool beyond = !r.total_beyond.empty() && r.total_beyond[i];
    value[i] = r.machined[i] && !beyond ? r.total[i] : 0.0;
    const int state = static_cast<int>(r.conformance[i]) + (beyond ? 5 : 0);
    const int group = i < s.group.size() ? s.group[i] : 0;
    category[i] = (group * (zone_count + 1) + r.zone[i] + 1) * 10 + state;
    lo = lo.cwiseMin(s.p_w[i]);
    hi = hi.cwiseMax(s.p_w[i]);
  }
  double narrowest = INFINITY;
  for (const ToleranceZone& z : zones) narrowest = std::min(narrowest, z.upper - z.lower);
  DecimateOptions o;
  o.max_distance_mm = std::min(0.5 * spacing_mm, 1e-3 * (hi - lo).norm());
  // Half a band of the colour scale (a band is a quarter of the zone's width)
  o.max_value_difference = std::isfinite(narrowest) ? narrowest / 8 : 1e-3;
  o.max_vertices = 120000;
  o.progress = progress;
  // Sharp edges stay (a CL-only surface has none marked).
  const std::vector<char> locked =
      s.on_edge.size() == s.size() ? s.on_edge : std::vector<char>(s.size(), 0);
  // Over the budget, a resampled part's own faces where they carry the map, the rest decimated.
  if (s.size() > static_cast<size_t>(o.max_vertices) && !s.given_faces.empty()) {
    DecimatedMesh given =
        coarseForDisplay(s.p_w, s.faces, s.given_faces, s.face_given, value, category, locked, o);
    if (!given.vertex.empty()) return given;
  }
  return decimateForDisplay(s.p_w, s.faces, value, category, locked, o);
}

std::string writeVerification(Verification& v, const std::string& report_dir_path, bool images,
                              bool view3d, const Progress& progress) {
  // Written as a whole into a staging directory, swapped in at the end (a killed run leaves the
  // previous report; a concurrent run on the same directory is refused).
  ReportDirectory report_dir(report_dir_path);
  const fs::path dir(report_dir.staging());
  VerifyReport& r = v.report;
  const SurfaceSamples& samples = v.samples;
  const VerifyResult& result = v.result;
  r.samples = &samples;
  r.result = &result;
  auto lap = std::chrono::steady_clock::now();
  auto phase = [&](const char* what) {
    const auto now = std::chrono::steady_clock::now();
    r.timings.push_back({what, std::chrono::duration<double>(now - lap).count()});
    lap = now;
  };
  std::vector<Eigen::Vector3d> nominal_swept(samples.size()), predicted_swept(samples.size());
  std::vector<double> total_um(samples.size()), machine_um(samples.size()),
      program_um(samples.size()), state(samples.size());
  tbb::parallel_for(size_t(0), samples.size(), [&](size_t i) {
    const bool cut = result.machined[i];
    predicted_swept[i] = samples.p_w[i] + (cut ? result.total[i] : 0.0) * samples.n_w[i];
    nominal_swept[i] = samples.p_w[i] + (cut ? result.program[i] : 0.0) * samples.n_w[i];
    total_um[i] = mmToUm(result.total[i]);
    machine_um[i] = mmToUm(result.machine[i]);
    program_um[i] = mmToUm(result.program[i]);
    state[i] = static_cast<double>(result.conformance[i]);
  });
  // The table and the PLY surfaces are written on a second thread while VTK renders the images
  // (VTK runs on one thread at a time, g_vtk_mutex): they fill the core the images leave. When
  // the 3D view is decimated too, they wait for it (its slabs take both cores and the images
  // wait for its mesh: at a million samples, started at once, the tables slowed it by 0.5 s of
  // the command's wall time); else they start at once, beside the VTP files.
  const bool decimating = view3d && !samples.faces.empty() && !r.zones.empty();
  std::future<double> tables;
  auto startTables = [&] {
    tables = std::async(std::launch::async, [&] {
      const auto start = std::chrono::steady_clock::now();
      {
        OutputSet table;
        table.addStreamed((dir / "deviations.csv").string(),
                          [&](TextOut& out) { writeDeviationsCsv(r, out); });
        table.commit();
      }
      writePlyWithScalar((dir / "swept_predicted.ply").string(), predicted_swept, samples.faces,
                         total_um, "deviation_um");
      writePlyWithScalar((dir / "swept_nominal.ply").string(), nominal_swept, samples.faces,
                         program_um, "deviation_um");
      return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    });
  };
  if (!(decimating && images)) startTables();
  // The 3D view's decimation, on a third thread (it reads only).
  double view_s = 0;
  std::atomic<double> view_done{-1};  // the decimation's fraction, -1 before it starts
  auto view = std::async(std::launch::async, [&] {
    const auto start = std::chrono::steady_clock::now();
    DecimatedMesh m = decimating ? viewMesh(samples, result, r.zones, r.spacing_mm,
                                            [&](double f) { view_done = f; })
                                 : DecimatedMesh{};
    view_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return m;
  });
  try {
    {
      std::lock_guard<std::mutex> lock(g_vtk_mutex);
      writeVtpWithScalars((dir / "swept_predicted.vtp").string(), predicted_swept, samples.faces,
                          {{"total_um", &total_um},
                           {"machine_um", &machine_um},
                           {"program_um", &program_um},
                           {"state", &state}});
      writeVtpWithScalars((dir / "swept_nominal.vtp").string(), nominal_swept, samples.faces,
                          {{"program_um", &program_um}});
    }
    phase("write_surfaces");
    const std::string title =
        verdictName(r) + "  " + r.name + ": total deviation (predicted swept - CAD)";
    // The view's decimation may still run (a part of more than 120 000 samples): its progress.
    // The maps are drawn on its mesh (a million samples render in seconds in software, and at
    // an image's resolution the decimated mesh, within its bounds, draws the same map).
    while (view.wait_for(std::chrono::milliseconds(200)) != std::future_status::ready)
      if (progress && view_done >= 0)
        progress("3D view: decimating " + std::to_string(samples.size()) + " samples", view_done);
    v.view_mesh = view.get();
    if (!v.view_mesh.vertex.empty()) r.view_mesh = &v.view_mesh;
    phase("wait_view3d");
    if (!tables.valid()) startTables();
    if (images)
      r.images = renderImages(r.line_pass, dir.string(), samples, result, r.zones, r.line_profile,
                              title, &r.notes, &r.cl_lines, r.view_mesh);
    phase("images");
  } catch (...) {
    if (tables.valid()) tables.wait();  // it writes into the staging directory: let it finish
    if (view.valid()) view.wait();
    throw;
  }
  // The table and PLY thread's own time (concurrent with the images, or with the VTP files and the
  // view's wait), then what was left of it to wait for.
  const double tables_s = tables.get();
  phase("wait_tables");
  r.timings.push_back({"tables_and_ply_concurrent", tables_s});
  r.timings.push_back({"view3d_concurrent", view_s});
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - v.started).count();
  writeFileAtomically((dir / "report.json").string(), formatVerifyJson(r));
  writeFileAtomically((dir / "report.html").string(), formatVerifyHtml(r));
  report_dir.commit();
  return (fs::path(report_dir.final()) / "report.html").string();
}

}  // namespace tolver
