#include "pipeline/measure.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <map>

#include "core/numerics/units.h"
#include "core/path/prediction_uncertainty.h"
#include "core/path/tool_motion.h"
#include "geometry/surface_projection.h"
#include "io/common/io_error.h"
#include "io/common/text_util.h"
#include "io/machine/machine_file.h"
#include "io/program/measured_points.h"
#include "io/program/process_file.h"
#include "io/report/deviation_map.h"
#include "io/report/offscreen_display.h"
#include "pipeline/inputs.h"

namespace tolver {
namespace {

// Where each measured point lands: its foot on the part and the sample verify sweeps there.
struct Matching {
  TriangleMesh part;  // the nominal part in w, for the maps
  std::vector<Eigen::Vector3d> p_w, given_n_w;
  std::vector<SurfaceFoot> feet;
  std::vector<int> sample_of;  // -1: not swept (beyond the search range, beyond an edge)
};

SurfaceSamples samplesAtFeet(const TriangleMesh& mesh, double search_mm, Matching& m) {
  m.part.vertices = mesh.vertices;
  m.part.faces = mesh.faces;
  m.feet = projectOntoMesh(mesh, m.p_w);
  m.sample_of.assign(m.p_w.size(), -1);
  SurfaceSamples s;
  s.group_names = mesh.group_names;
  s.group_aliases = mesh.group_aliases;
  for (size_t i = 0; i < m.p_w.size(); ++i) {
    const SurfaceFoot& f = m.feet[i];
    if (f.distance > search_mm || f.off_face) continue;
    m.sample_of[i] = static_cast<int>(s.p_w.size());
    s.p_w.push_back(f.foot_w);
    // The file's nominal normal where it gives one (the CAD's, exact), else the facet's.
    s.n_w.push_back(m.given_n_w[i].squaredNorm() > 0 ? m.given_n_w[i] : f.n_w);
    s.area.push_back(1.0);  // a point stands for itself: areas count points
    s.group.push_back(mesh.face_group.empty() ? 0 : mesh.face_group[f.face]);
    s.on_edge.push_back(0);
  }
  return s;
}

// d(normal deviation) / d(cutter radius), the tool's length preset to its tip (as shops set
// tools): a ball of radius R + dR has its centre dR further up the axis, so its contact with
// normal n moves by dR (a - n): -(1 - n.a), nothing on the ball's bottom, -1 on its equator. A
// flat or bull-nose cutter: the radial share of the normal (its floor does not move).
double radiusSensitivity(const Cutter& c, const Eigen::Vector3d& n, const Eigen::Vector3d& a) {
  if (c.corner_radius >= 0.5 * c.diameter - 1e-9) return -(1.0 - n.dot(a));
  return -(n - n.dot(a) * a).norm();
}

// process.txt: the corrections found, added to those the prediction already held (the set-up's
// small translations and angles add to first order; radii and lengths add).
void collectCorrections(const std::string& process_from, MeasureReport& rep) {
  std::map<std::string, MeasureReport::Correction> all;
  std::vector<std::string> order;
  auto add = [&](const std::string& key, double v, double sd) {
    if (!all.count(key)) {
      order.push_back(key);
      all[key] = {key, 0.0, NAN};
    }
    all[key].value += v;
    if (std::isfinite(sd)) all[key].sd = sd;
  };
  if (!process_from.empty()) {
    rep.process_from = process_from;
    const ProcessCorrections p = readProcessFile(process_from);
    const Eigen::Vector3d t = p.part_error.translation();
    const Eigen::AngleAxisd aa(p.part_error.linear());
    const Eigen::Vector3d w = aa.angle() * aa.axis();
    const char* names[6] = {"x mm", "y mm", "z mm", "about x rad", "about y rad", "about z rad"};
    for (int k = 0; k < 6; ++k)
      if ((k < 3 ? t[k] : w[k - 3]) != 0.0)
        add(processKey("set-up", names[k]), k < 3 ? t[k] : w[k - 3], NAN);
    for (const auto& [tool, v] : p.radius_mm)
      add(processKey(tool ? "cutter radius T" + std::to_string(tool + 1) : "cutter radius",
                     "dR mm"),
          v, NAN);
    for (const auto& [tool, v] : p.length_mm)
      add(processKey(tool ? "tool length T" + std::to_string(tool + 1) : "tool length", "dL mm"), v,
          NAN);
    if (p.drift_mm_per_h != 0.0)
      add(processKey("thermal drift", "spindle growth mm/h"), p.drift_mm_per_h, NAN);
    for (const auto& [tool, v] : p.across_feed_mm)
      add(processKey(tool ? "tool deflection T" + std::to_string(tool + 1) : "tool deflection",
                     "across the feed mm"),
          v, NAN);
  }
  for (const TraceGroup& g : rep.trace.groups) {
    if (!g.added) continue;
    for (Eigen::Index k = 0; k < g.values.size(); ++k)
      add(processKey(g.name, k < static_cast<Eigen::Index>(g.value_names.size())
                                 ? g.value_names[k]
                                 : std::string("value")),
          g.values[k], g.sd[k]);
  }
  for (const std::string& k : order) rep.corrections.push_back(all[k]);
}

// The residual's maps (before and after the trace, one scale: +-3 sigma of the final model's
// residual, so that what is left beyond the model stands out) and histograms, into dir. Returns
// the files' names; without a display, a note instead.
std::vector<std::string> renderResiduals(const std::string& dir, const TriangleMesh& part,
                                         MeasureReport& rep) {
  std::string why;
  if (!ensureDisplay(&why)) {
    rep.notes.push_back(why);
    return {};
  }
  const double band = std::max(3.0 * rep.trace.sigma_after, 0.5e-3);
  std::vector<double> before, after;
  std::vector<Eigen::Vector3d> at;
  for (const MeasureRow& w : rep.rows)
    if (w.status == "used") {
      before.push_back(w.residual);
      after.push_back(w.residual_after);
      at.push_back(w.foot_w);
    }
  std::vector<std::string> files;
  const std::vector<Rgb> grey(part.vertices.size(), kUncheckedColour);
  for (const bool is_after : {false, true}) {
    const std::vector<double>& r = is_after ? after : before;
    DeviationMap map;
    map.points = &part.vertices;
    map.faces = &part.faces;
    map.colours = grey;
    map.bar_lower = -band;
    map.bar_upper = band;
    map.grey_means = "the part; dots: measured points";
    map.bar_title = "residual um\n+ more material\nthan predicted";
    map.limit_names = {"-3 sigma", "+3 sigma"};
    map.title = is_after ? "residual after the trace (measured - predicted - effects added)"
                         : "residual (measured - predicted)";
    map.markers = at;
    for (double d : r) map.marker_colours.push_back(deviationColour(d, -band, band));
    if (!is_after && rep.worst_row >= 0) {
      const MeasureRow& w = rep.rows[rep.worst_row];
      map.callouts.push_back(
          {w.foot_w, formatWith("largest after %+.1f um", mmToUm(w.residual_after)) + "\n" +
                         formatWith("(%.1f, ", w.foot_w.x()) + formatWith("%.1f, ", w.foot_w.y()) +
                         formatWith("%.1f)", w.foot_w.z()) +
                         (w.cl_line > 0 ? " line " + std::to_string(w.cl_line) : std::string())});
    }
    const MapView iso{"isometric", Eigen::Vector3d(-1, 1, -1), Eigen::Vector3d::UnitZ(), false, {}};
    const std::string name = is_after ? "map_residual_after.png" : "map_residual.png";
    renderDeviationMap(dir + "/" + name, map, iso);
    files.push_back(name);
    const std::string hist = is_after ? "histogram_residual_after.png" : "histogram_residual.png";
    renderHistogram(dir + "/" + hist, r, std::vector<double>(r.size(), 1.0), -band, band,
                    is_after ? "residual after the trace" : "residual (measured - predicted)", 900,
                    500, "residual (µm)", "% of the points used", "3 sigma of the final model");
    files.push_back(hist);
  }
  return files;
}

// The machine file as the part refined it: the file as read, the machine group's values added
// to its identified parameters and their covariance the final model's (the calibration's prior
// and the part's points together). Empty when the machine group was not added.
std::string refinedMachineXml(const std::string& machine_file, const MeasureReport& rep) {
  for (const TraceGroup& g : rep.trace.groups) {
    if (!g.added || g.name != "machine") continue;
    Machine m = readMachineFile(machine_file);
    IdentificationUncertainty& id = m.identification;
    if (static_cast<Eigen::Index>(id.parameters.size()) != g.values.size()) return "";
    for (size_t c = 0; c < id.parameters.size(); ++c)
      m.params[id.parameters[c]] += g.values[static_cast<Eigen::Index>(c)];
    if (g.covariance.rows() == g.values.size()) id.covariance = g.covariance;
    return formatMachineXml(m, "refined by tolver measure from the machined part's points " +
                                   rep.points_file + " (" + rep.trace.verdict_text + ")");
  }
  return "";
}

}  // namespace

MeasureRun measurePart(const MeasureInputs& in, const Progress& progress) {
  if (in.verify.part.empty())
    throw FieldError("part", "measure needs the part's model: the points are matched to it");
  if (!(in.search_mm > 0 && in.search_mm <= 10))
    throw FieldError("search_mm", "the search range must lie in (0, 10] mm");
  if (in.heldout_every < 2)
    throw FieldError("heldout_every", "hold out every N-th point with N at least 2");
  const std::vector<MeasuredPoint> points = readMeasuredPoints(in.points);
  if (progress) progress("reading", 1.0);
  const Eigen::Isometry3d w_T_file = partPlacement(in.verify);
  Matching m;
  for (const MeasuredPoint& p : points) {
    m.p_w.push_back(w_T_file * p.p);
    m.given_n_w.push_back(w_T_file.linear() * p.n);
  }
  VerifyInputs vi = in.verify;
  vi.keep_poses = true;
  // Placements 0.05 mm apart: the cusp between them (step^2 / 8R) is 0.06 um on a 5 mm ball,
  // 0.3 um on a 1 mm one, below a CMM's noise; verify's default keeps it at a tenth of the
  // tolerance, which would read as residual here.
  if (std::isnan(vi.step_mm)) vi.step_mm = 0.05;
  vi.images = false;
  vi.view3d = false;
  vi.samples_at = [&](const TriangleMesh& mesh) { return samplesAtFeet(mesh, in.search_mm, m); };
  std::unique_ptr<Verification> v = runVerification(vi, "", [&](double f) {
    if (progress) progress("sweeping", f);
  });
  const VerifyResult& res = v->result;
  const Verification::Poses& poses = v->poses;

  MeasureRun run;
  MeasureReport& rep = run.report;
  rep.name = std::filesystem::path(in.points).stem().string();
  rep.machine_file = v->machine_file;
  rep.program_file = v->report.program_file;
  rep.part_file = in.verify.part;
  rep.points_file = in.points;
  rep.search_mm = in.search_mm;
  rep.heldout_every = in.heldout_every;
  std::vector<TracePoint> trace;
  const std::vector<double> times_min = programTimes(poses.path);
  if (times_min.empty())
    rep.notes.push_back(
        "thermal drift not tried: the program's cutting moves have no feed rate in mm/min (its "
        "clock)");
  std::map<std::array<long long, 3>, int> places;
  std::vector<int> row_of_trace;
  std::vector<int> cl_of_trace, sample_of_trace;
  for (size_t i = 0; i < points.size(); ++i) {
    MeasureRow w;
    w.line = points[i].line;
    w.p_w = m.p_w[i];
    w.foot_w = m.feet[i].foot_w;
    if (points[i].has_deviation) w.instrument = points[i].deviation;
    const int s = m.sample_of[i];
    if (s < 0) {
      w.n_w = m.feet[i].n_w;
      if (m.feet[i].distance > in.search_mm) {
        w.status = "beyond search range";
        ++rep.beyond_range;
      } else {
        w.status = "beyond an edge";
        ++rep.off_face;
      }
      rep.rows.push_back(w);
      continue;
    }
    w.n_w = v->samples.n_w[s];
    const int group = v->samples.group[s];
    if (group >= 0 && group < static_cast<int>(v->samples.group_names.size()))
      w.region = v->samples.group_names[group];
    w.measured = (m.p_w[i] - w.foot_w).dot(w.n_w);
    const int cl = res.cl_index[s];
    if (!res.machined[s] || cl < 0) {
      w.status = "not machined";
      ++rep.unmachined;
      rep.rows.push_back(w);
      continue;
    }
    w.predicted = res.total[s];
    const bool split = res.split.empty() || res.split[s] == Split::Attributable;
    if (split) {
      w.program = res.program[s];
      w.machine = res.machine[s];
    }
    w.residual = w.measured - w.predicted;
    w.cl_line = cl < static_cast<int>(v->report.cl_lines.size()) ? v->report.cl_lines[cl] : 0;
    w.tool = poses.tool[cl];
    w.operation = operationAt(poses.operations, w.cl_line);
    w.held_out = rep.used % in.heldout_every == in.heldout_every - 1;
    w.status = "used";
    TracePoint t;
    t.p_w = w.foot_w;
    t.n_w = w.n_w;
    t.axis_w = poses.path[cl].u_w;
    if (cl > 0) {
      const Eigen::Vector3d move = poses.path[cl].p_w - poses.path[cl - 1].p_w;
      if (move.norm() > 1e-9) t.feed_w = move.normalized();
      // The program's clock halfway along the move that cut it.
      if (!times_min.empty()) t.time_h = 0.5 * (times_min[cl - 1] + times_min[cl]) / 60.0;
    }
    t.tool = w.tool;
    t.radius_sensitivity = radiusSensitivity(poses.cutters[w.tool], t.n_w, t.axis_w);
    t.residual = w.residual;
    t.held_out = w.held_out;
    // Places measured more than once: the same foot within the 10 um grid cell.
    const std::array<long long, 3> cell = {std::llround(w.foot_w.x() / 0.01),
                                           std::llround(w.foot_w.y() / 0.01),
                                           std::llround(w.foot_w.z() / 0.01)};
    const auto [it, fresh] = places.emplace(cell, static_cast<int>(places.size()));
    t.repeat = it->second;
    trace.push_back(t);
    row_of_trace.push_back(static_cast<int>(rep.rows.size()));
    cl_of_trace.push_back(cl);
    sample_of_trace.push_back(s);
    ++rep.used;
    rep.rows.push_back(w);
  }
  if (rep.used == 0)
    throw InputError(in.points, 0, 0, "x_mm",
                     "none of the " + std::to_string(points.size()) +
                         " points lies on a machined face of the part within " +
                         formatNumber(in.search_mm) +
                         " mm: are they in the part's frame (the set-up, mesh_offset)?");
  // The machine's parameters, when calibrated: each point's row through the sensitivity
  // Jacobian at the joints of the move that cut it, at its contact on the cutter.
  TraceOptions opt;
  opt.plausible = in.plausible;
  opt.tools = static_cast<int>(poses.cutters.size());
  const Machine& machine = poses.machine;
  if (!machine.identification.empty()) {
    const IdentificationUncertainty& id = machine.identification;
    const ForwardKinematics fk(machine.model, machine.params);
    // Without --absolute the prediction takes the machine's share modulo the set-up a shop
    // measures (fitted over the program's evenly spaced poses, pipeline/inputs.h): the rows
    // are taken modulo the same set-up, so that a machine refined by them predicts what they fit.
    PredictionUncertainty pu(machine);
    if (!in.verify.absolute) {
      EvenPoses even;
      for (size_t i = 0; i < poses.q.size(); ++i)
        if (even.wants(i)) even.add(i, poses.q[i], Eigen::Vector3d::Zero());
      pu.setupModulo(even.q);
    }
    opt.machine_rows.resize(static_cast<Eigen::Index>(trace.size()), id.parameters.size());
    for (size_t k = 0; k < trace.size(); ++k) {
      const JointVector& q = poses.q[cl_of_trace[k]];
      const Eigen::MatrixXd J = pu.identifiedRows(q, nullptr);  // twist rows in t
      const Eigen::Matrix3d R = fk.w_T_t(q).linear();
      const Eigen::Vector3d r = res.contact_offset_w[sample_of_trace[k]].cast<double>();
      const Eigen::Vector3d n = trace[k].n_w, m_w = r.cross(n);
      for (size_t c = 0; c < id.parameters.size(); ++c)
        opt.machine_rows(static_cast<Eigen::Index>(k), static_cast<Eigen::Index>(c)) =
            n.dot(R * J.block<3, 1>(0, c)) + m_w.dot(R * J.block<3, 1>(3, c));
    }
    opt.machine_covariance = id.covariance;
    for (int p : id.parameters) opt.machine_names.push_back(machine.model.parameters[p].iso_code);
  }
  if (progress) progress("tracing", 0.0);
  rep.trace = tracePart(trace, opt);
  double m2 = 0, p2 = 0, r2 = 0;
  for (size_t k = 0; k < trace.size(); ++k) {
    MeasureRow& w = rep.rows[row_of_trace[k]];
    w.residual_after = rep.trace.residual_after[static_cast<Eigen::Index>(k)];
    m2 += w.measured * w.measured;
    p2 += w.predicted * w.predicted;
    r2 += w.residual * w.residual;
    rep.residual_max = std::max(rep.residual_max, std::abs(w.residual));
    if (rep.worst_row < 0 ||
        std::abs(w.residual_after) > std::abs(rep.rows[rep.worst_row].residual_after))
      rep.worst_row = row_of_trace[k];
  }
  rep.measured_rms = std::sqrt(m2 / trace.size());
  rep.predicted_rms = std::sqrt(p2 / trace.size());
  rep.residual_rms = std::sqrt(r2 / trace.size());
  if (rep.beyond_range + rep.off_face + rep.unmachined > 0)
    rep.notes.push_back(std::to_string(rep.beyond_range) + " points beyond the search range, " +
                        std::to_string(rep.off_face) + " beyond an edge of the part, " +
                        std::to_string(rep.unmachined) +
                        " on faces the program does not cut: not used");
  collectCorrections(in.verify.process, rep);
  if (!in.report_dir.empty()) {
    ReportDirectory dir(in.report_dir);
    writeFileAtomically(dir.staging() + "/residuals.csv", formatMeasureCsv(rep));
    writeFileAtomically(dir.staging() + "/process.txt", formatProcessFile(rep));
    const std::string machine_xml = refinedMachineXml(v->machine_file, rep);
    if (!machine_xml.empty()) {
      writeFileAtomically(dir.staging() + "/machine.xml", machine_xml);
      rep.machine_written = "machine.xml";
    }
    if (in.images) rep.images = renderResiduals(dir.staging(), m.part, rep);
    writeFileAtomically(dir.staging() + "/report.json", formatMeasureJson(rep));
    writeFileAtomically(dir.staging() + "/report.html", formatMeasureHtml(rep, dir.staging()));
    dir.commit();
    run.report_dir = dir.final();
  }
  run.verdict = Verdict::Ok;
  return run;
}

}  // namespace tolver
