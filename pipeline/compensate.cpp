// The compensate pipeline: see pipeline/compensate.h.
#include "pipeline/compensate.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <set>
#include <stdexcept>

#include "core/numerics/units.h"
#include "core/path/prediction_uncertainty.h"
#include "core/path/tool_motion.h"
#include "io/common/io_error.h"
#include "io/common/text_util.h"
#include "pipeline/parallel_prediction.h"

namespace tolver {
namespace {

double angle(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b));
}

// Figures over points [from, to): tip deviations (um) and axis angles (urad).
PathFigures figuresOf(const std::vector<double>& tip_um, const std::vector<double>& axis_urad,
                      const std::vector<int>& line, size_t from, size_t to) {
  PathFigures f;
  double st = 0, sa = 0;
  for (size_t i = from; i < to; ++i) {
    const double t = tip_um[i], a = axis_urad[i];
    st += t * t;
    sa += a * a;
    if (t > f.tip_max_um) f.tip_max_um = t, f.tip_max_line = line[i];
    f.axis_max_urad = std::max(f.axis_max_urad, a);
  }
  const double n = static_cast<double>(std::max<size_t>(1, to - from));
  f.tip_rms_um = std::sqrt(st / n);
  f.axis_rms_urad = std::sqrt(sa / n);
  return f;
}

// The corrected program in the source's dialect, with the source's byte-order mark and line
// endings.
CompensatedProgramText correctedText(const CompensateInputs& in, const CompensationRun& run) {
  const ClProgram& program = run.program;
  const std::vector<CompensatedPoint>& cp = run.compensation.points;
  const std::vector<std::string> header = {
      "tolver compensate: " + program.file + " for " + run.machine.model.name + " (" +
      in.machine.machine +
      "): the machine with its errors runs this program onto the original's nominal path"};
  CompensatedProgramText text;
  if (program.dialect == "G-code") {
    std::vector<JointVector> q(cp.size());
    std::vector<Eigen::Vector3d> p(cp.size());
    for (size_t i = 0; i < q.size(); ++i) {
      q[i] = cp[i].q;
      p[i] = cp[i].nominal_p_w;
    }
    text = formatCompensatedGcode(program, run.machine.model, program.joints, q, p, header);
  } else {
    std::vector<ClPoint> corrected = program.path;
    for (size_t i = 0; i < corrected.size(); ++i) {
      corrected[i].p_w = cp[i].nominal_p_w;
      corrected[i].u_w = cp[i].nominal_u_w;
    }
    text = formatCompensatedApt(program, corrected, header);
  }
  const std::string raw = readFile(in.program.nc.empty() ? in.program.cl : in.program.nc);
  const size_t eol = raw.find('\n');
  if (eol != std::string::npos && eol > 0 && raw[eol - 1] == '\r') {
    std::string crlf;
    crlf.reserve(text.text.size() + text.text.size() / 30);
    for (char ch : text.text) {
      if (ch == '\n') crlf += '\r';
      crlf += ch;
    }
    text.text = std::move(crlf);
  }
  if (raw.rfind("\xEF\xBB\xBF", 0) == 0) text.text.insert(0, "\xEF\xBB\xBF");
  return text;
}

// The written text read back as the next command will, whole, then the points of the source
// lines compensated (--lines); one point per program point, or an internal error.
ClProgram readBack(const CompensateInputs& in, const CompensationRun& run,
                   const std::string& output) {
  ProgramOptions whole = in.program;
  whole.lines.clear();
  ClProgram back = parseProgram(run.text.text, output, whole, run.machine.model);
  const ClProgram& program = run.program;
  if (!in.program.lines.empty()) {
    std::set<int> lines;
    for (const ClPoint& c : program.path) lines.insert(c.line);
    const std::vector<int>& source_line = run.text.source_line;
    size_t k = 0;
    for (size_t i = 0; i < back.path.size(); ++i) {
      const int l = back.path[i].line;
      const int src = l >= 1 && l <= static_cast<int>(source_line.size()) ? source_line[l - 1] : 0;
      if (!lines.count(src)) continue;
      back.path[k] = back.path[i];
      back.path[k].line = src;
      if (i < back.joints.size()) back.joints[k] = back.joints[i];
      ++k;
    }
    back.path.resize(k);
    if (back.joints.size() > k) back.joints.resize(k);
  }
  if (back.path.size() != program.path.size()) {
    size_t k = 0;
    while (k < back.path.size() && back.path[k].line == program.path[k].line) ++k;
    throw std::runtime_error(
        "the compensated program reads back with " + std::to_string(back.path.size()) +
        " points instead of " + std::to_string(program.path.size()) + " (from line " +
        std::to_string(k < program.path.size() ? program.path[k].line : 0) + ")");
  }
  return back;
}

// Before and after per point, in um and urad.
void pointFigures(CompensationRun& run) {
  const std::vector<ClPoint>& path = run.target.empty() ? run.program.path : run.target;
  const size_t n = path.size();
  run.line.resize(n);
  run.tip_before_um.resize(n);
  run.tip_after_um.resize(n);
  run.axis_before_urad.resize(n);
  run.axis_after_urad.resize(n);
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d u_t = path[i].u_w.normalized();
    const PredictedPoint& b = run.before.points[i];
    const PredictedPoint& a = run.after.points[i];
    run.line[i] = path[i].line;
    run.tip_before_um[i] = mmToUm((b.p_pred_w - path[i].p_w).norm());
    run.tip_after_um[i] = mmToUm((a.p_pred_w - path[i].p_w).norm());
    run.axis_before_urad[i] = radToUrad(angle(b.u_pred_w, u_t));
    run.axis_after_urad[i] =
        run.orientation ? radToUrad(angle(a.u_pred_w, u_t)) : run.axis_before_urad[i];
  }
}

// Segments: runs of cutting moves between rapids.
std::vector<SegmentFigures> segmentFigures(const CompensationRun& run) {
  const std::vector<ClPoint>& path = run.program.path;
  const size_t n = path.size();
  std::vector<SegmentFigures> out;
  for (size_t i = 0; i < n;) {
    if (path[i].rapid) {
      ++i;
      continue;
    }
    size_t j = i;
    while (j < n && !path[j].rapid) ++j;
    SegmentFigures s;
    s.first_line = path[i].line;
    s.last_line = path[j - 1].line;
    s.points = static_cast<int>(j - i);
    s.before = figuresOf(run.tip_before_um, run.axis_before_urad, run.line, i, j);
    s.after = figuresOf(run.tip_after_um, run.axis_after_urad, run.line, i, j);
    out.push_back(s);
    i = j;
  }
  return out;
}

// The model's own uncertainty of the after on a calibrated machine: the 95 % radii of the tip's
// distance and the tool axis's angle, median and max.
void afterBand(const CompensateInputs& in, const std::vector<ProbedPoint>& probed, bool probed_fit,
               CompensationRun& run) {
  const size_t n = run.program.path.size();
  PredictionUncertainty pu(run.machine);
  if (probed_fit) {
    pu.setupModuloProbed(probed);
  } else if (!in.absolute) {
    std::vector<JointVector> sub;
    const size_t step = std::max<size_t>(1, n / 2000);
    for (size_t i = 0; i < n; i += step) sub.push_back(run.after.points[i].q);
    pu.setupModulo(sub);
  }
  std::vector<double> band(n), axis(n);
  for (size_t i = 0; i < n; ++i) {
    const PoseUncertainty u = pu.at(run.after.points[i].q);
    band[i] = mmToUm(PredictionUncertainty::tipRadius95(u));
    axis[i] = radToUrad(PredictionUncertainty::axisRadius95(u));
  }
  auto medianMax = [n](std::vector<double>& v, double* median, double* max) {
    *max = *std::max_element(v.begin(), v.end());
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(n / 2), v.end());
    *median = v[n / 2];
  };
  medianMax(band, &run.report.after_band95_median_um, &run.report.after_band95_max_um);
  medianMax(axis, &run.report.after_axis_band95_median_urad,
            &run.report.after_axis_band95_max_urad);
  run.report.after_lack_of_fit_um = mmToUm(run.machine.identification.lack_of_fit_mm);
  run.report.after_tilt_prior_urad = radToUrad(run.machine.identification.spindle_tilt_rad);
}

void fillReport(const CompensateInputs& in, const std::string& output, CompensationRun& run) {
  CompensationReport& rep = run.report;
  const ClProgram& program = run.program;
  const std::vector<CompensatedPoint>& cp = run.compensation.points;
  const size_t n = program.path.size();
  rep.machine = in.machine.machine;
  rep.program = program.file;
  rep.dialect = program.dialect;
  rep.output = output;
  rep.points = static_cast<int>(n);
  rep.before = figuresOf(run.tip_before_um, run.axis_before_urad, run.line, 0, n);
  rep.after = figuresOf(run.tip_after_um, run.axis_after_urad, run.line, 0, n);
  std::vector<double> t, a;
  std::vector<int> at;
  for (size_t i = 0; i < n; ++i)
    if (run.text.written[i] && (cp[i].status == CompensationStatus::Compensated ||
                                cp[i].status == CompensationStatus::IllConditioned)) {
      t.push_back(run.tip_after_um[i]);
      a.push_back(run.axis_after_urad[i]);
      at.push_back(run.line[i]);
    }
  rep.compensated_points = static_cast<int>(t.size());
  rep.after_compensated = figuresOf(t, a, at, 0, t.size());
  rep.setup_note = run.setup_note;
  rep.notes = run.text.notes;
  if (const auto n =
          std::count(run.program.cycle_orientation.begin(), run.program.cycle_orientation.end(), 1))
    rep.notes.push_back(std::to_string(n) +
                        " points in a swivelled plane (CYCLE800): the tip compensated by the "
                        "linear axes, the tool axis left where the cycle puts it");
  const MachineModel& model = run.machine.model;
  for (size_t k = 0; k < model.axes.size(); ++k) {
    double m = 0;
    for (const CompensatedPoint& c : cp) m = std::max(m, std::abs(c.q[k] - c.q0[k]));
    const bool rot = model.axes[k].isRotary();
    rep.joint_correction_max.push_back({model.axes[k].name, rot ? radToUrad(m) : mmToUm(m)});
    rep.joint_rotary.push_back(rot);
  }
  rep.ill_conditioned = run.compensation.ill_conditioned;
  rep.out_of_travel = run.compensation.out_of_travel;
  rep.not_converged = run.compensation.not_converged;
  for (size_t i = 0; i < n; ++i) {
    if (cp[i].status == CompensationStatus::IllConditioned)
      rep.ill_conditioned_lines.push_back(run.line[i]);
    if (cp[i].status == CompensationStatus::OutOfTravel)
      rep.out_of_travel_lines.push_back(run.line[i]);
    rep.left_by_writer += !run.text.written[i] && cp[i].status != CompensationStatus::OutOfTravel &&
                          cp[i].status != CompensationStatus::NotConverged;
  }
  rep.segments = segmentFigures(run);
}

}  // namespace

std::vector<ClPoint> processTargets(const ClProgram& program, const ProcessCorrections& process,
                                    std::vector<std::string>* notes) {
  const std::vector<ClPoint>& path = program.path;
  std::vector<ClPoint> target = path;
  const std::vector<int> tool = program.toolOfPoints();
  const std::vector<double> t_min =
      process.drift_mm_per_h != 0.0 ? programTimes(path) : std::vector<double>{};
  if (process.drift_mm_per_h != 0.0 && t_min.empty() && notes)
    notes->push_back(
        "the process file's thermal drift is not compensated: the program's cutting moves have "
        "no feed rate in mm/min (its clock)");
  const Eigen::Isometry3d& E = process.part_error;
  for (size_t i = 0; i < path.size(); ++i) {
    ClPoint& c = target[i];
    c.u_w = (E.linear() * path[i].u_w).normalized();
    c.p_w = E * path[i].p_w;
    const int k = tool.empty() ? 0 : tool[i];
    if (const auto it = process.length_mm.find(k); it != process.length_mm.end())
      c.p_w += it->second * c.u_w;
    if (!t_min.empty()) c.p_w += process.drift_mm_per_h * (t_min[i] / 60.0) * c.u_w;
    const auto d = process.across_feed_mm.find(k);
    if (d != process.across_feed_mm.end() && i > 0 && !path[i].rapid) {
      const Eigen::Vector3d move = E.linear() * (path[i].p_w - path[i - 1].p_w);
      if (move.norm() > 0) c.p_w -= d->second * c.u_w.cross(move.normalized());
    }
  }
  if (notes) {
    for (const auto& [k, dr] : process.radius_mm)
      notes->push_back(formatWith("the process file's cutter radius error (tool %.0f, ",
                                  static_cast<double>(k + 1)) +
                       formatWith("%+.1f um) is not in the program: enter it as the tool's radius "
                                  "wear in the control's tool table",
                                  mmToUm(dr)));
    for (const std::string& key : process.not_applied)
      notes->push_back("the process file's " + key + " is reported, not compensated");
  }
  return target;
}

std::string describeProcessTargets(const ProcessCorrections& process) {
  std::string s;
  auto add = [&s](const std::string& part) { s += (s.empty() ? "" : ", ") + part; };
  const Eigen::Isometry3d& E = process.part_error;
  if (!E.isApprox(Eigen::Isometry3d::Identity(), 0.0)) {
    const Eigen::Vector3d t = E.translation();
    const Eigen::AngleAxisd r(E.linear());
    char buf[160];
    std::snprintf(buf, sizeof buf, "the part's set-up (%+.1f, %+.1f, %+.1f um; %.1f urad)",
                  mmToUm(t.x()), mmToUm(t.y()), mmToUm(t.z()), radToUrad(r.angle()));
    add(buf);
  }
  auto tool = [](int k) { return "T" + std::to_string(k + 1); };
  for (const auto& [k, v] : process.length_mm)
    add("tool " + tool(k) + formatWith(" length %+.1f um", mmToUm(v)));
  if (process.drift_mm_per_h != 0.0)
    add(formatWith("thermal drift %+.1f um/h along the tool axis", mmToUm(process.drift_mm_per_h)));
  for (const auto& [k, v] : process.across_feed_mm)
    add("tool " + tool(k) + formatWith(" deflection %+.1f um across the feed", mmToUm(v)));
  return s.empty() ? "nothing the program can take up" : s;
}

CompensationRun runCompensation(const CompensateInputs& in, const std::string& output,
                                const Progress& progress) {
  auto phase = [&progress](const char* p) {
    if (progress) progress(p, 0.0);
  };
  phase("reading and predicting");
  CompensationRun run;
  run.machine = loadMachine(in.machine);
  ProgramOptions program_options = in.program;
  program_options.keep_motion_text = true;  // the in-place writer edits the GOTO statements
  run.program = loadProgram(program_options, run.machine.model);
  if (!in.process.empty()) {
    const ProcessCorrections process = readProcessFile(in.process);
    run.target = processTargets(run.program, process, &run.warnings);
    run.report.process = in.process;
    run.report.process_applied = describeProcessTargets(process);
  }
  run.before = predictProgram(run.machine, run.program);
  // A calibrated machine: its share after the set-up the shop measures (the calibration cannot
  // see the rest), as predict takes it.
  const std::vector<ProbedPoint> probed = loadProbed(in.probed, run.machine.model);
  const CalibratedPrediction cal =
      applyCalibration(run.machine, run.program, run.before, in.absolute, probed);
  if (cal.probed)
    run.setup_note = describeProbedSetup(in.probed, cal.probe, probed, &run.warnings);
  else if (!run.machine.identification.empty())
    run.setup_note = in.absolute
                         ? "absolute (" + inputName("absolute") +
                               "): what probing and presetting would take up is compensated too"
                         : "after the set-up a shop measures (part probed, tool preset), which the "
                           "calibration cannot see";
  for (const std::string& w : setupWarnings(run.machine.model)) run.warnings.push_back(w);
  // A nominal machine file: nothing to compensate; said, so that an unchanged program is not
  // taken for a compensated one.
  bool no_errors = false;
  const std::string errors = machineErrorsStatement(run.machine, &no_errors);
  if (no_errors && run.target.empty())
    run.warnings.push_back(errors + "; the program is written as it came");
  const ClProgram& program = run.program;
  run.orientation = program.dialect == "G-code" ? gcodeGivesRotaryWords(program, run.machine.model)
                                                : program.multiax;
  std::vector<JointVector> q0(run.before.points.size());
  for (size_t i = 0; i < q0.size(); ++i) q0[i] = run.before.points[i].q;
  phase("compensating");
  CompensationOptions co;
  co.max_condition = in.max_condition;
  if (std::count(program.cycle_orientation.begin(), program.cycle_orientation.end(), 1) > 0)
    co.tip_only = &program.cycle_orientation;
  run.compensation = compensateToolPath(run.machine.model, run.machine.params,
                                        run.target.empty() ? program.path : run.target, q0,
                                        run.orientation, co, &run.before.points);
  phase("writing and reading back");
  run.text = correctedText(in, run);
  // The after, measured on the file as written: read back, predicted on the machine.
  const ClProgram back = readBack(in, run, output);
  run.after = predictToolPathParallel(run.machine.model, run.machine.params, back.path, 20,
                                      back.joints.empty() ? nullptr : &back.joints);
  if (!run.after.ok())
    throw std::runtime_error("the compensated program does not predict: " +
                             run.after.failures.front().message);
  pointFigures(run);
  fillReport(in, output, run);
  if (!cal.uncertainty.empty()) afterBand(in, probed, cal.probed, run);
  return run;
}

std::string compensatedJointsPath(const std::string& report_json) {
  std::filesystem::path p(report_json);
  return (p.parent_path() / (p.stem().string() + "_joints.csv")).string();
}

void writeCompensation(const CompensationRun& run, const std::string& output,
                       const std::string& report_json, const std::string& report_dir_path) {
  // The report directory is taken first: one that cannot be written leaves nothing written.
  std::unique_ptr<ReportDirectory> report_dir;
  if (!report_dir_path.empty()) report_dir = std::make_unique<ReportDirectory>(report_dir_path);
  OutputSet outputs;
  outputs.add(output, run.text.text);
  // The joints of every point, before and after (the compensating ones where written).
  {
    const MachineModel& m = run.machine.model;
    const std::vector<CompensatedPoint>& cp = run.compensation.points;
    std::vector<std::string> names, status;
    std::vector<bool> rotary;
    for (const Axis& ax : m.axes) {
      names.push_back(ax.name);
      rotary.push_back(ax.isRotary());
    }
    std::vector<std::vector<double>> before(cp.size()), after(cp.size());
    for (size_t i = 0; i < cp.size(); ++i) {
      const bool written = i < run.text.written.size() && run.text.written[i];
      status.push_back(!written                                             ? "kept"
                       : cp[i].status == CompensationStatus::Compensated    ? "compensated"
                       : cp[i].status == CompensationStatus::IllConditioned ? "ill_conditioned"
                       : cp[i].status == CompensationStatus::OutOfTravel    ? "out_of_travel"
                                                                            : "not_converged");
      for (size_t a = 0; a < m.axes.size(); ++a) {
        const double k = m.axes[a].isRotary() ? radToDeg(1.0) : 1.0;
        before[i].push_back(cp[i].q0[a] * k);
        after[i].push_back((written ? cp[i].q[a] : cp[i].q0[a]) * k);
      }
    }
    outputs.add(compensatedJointsPath(report_json),
                formatCompensatedJointsCsv(names, rotary, run.line, status, before, after,
                                           run.tip_after_um, run.axis_after_urad));
  }
  CompensationReport rep = run.report;
  rep.joints_file = compensatedJointsPath(report_json);
  outputs.add(report_json, formatCompensationJson(rep));
  if (report_dir) {  // written as a whole before the set is committed, swapped in at the end
    writeCompensationReport(report_dir->staging(), run.report, run.line, run.tip_before_um,
                            run.tip_after_um, run.axis_before_urad, run.axis_after_urad);
  }
  outputs.commit();
  if (report_dir) report_dir->commit();
}

TableRun runTables(const MachineOptions& machine_options, double step_mm,
                   const std::string& table) {
  TableRun run;
  run.machine = loadMachine(machine_options);
  const MachineModel& model = run.machine.model;
  JointVector q_ref = JointVector::Zero(static_cast<int>(model.axes.size()));
  for (size_t a = 0; a < model.axes.size(); ++a)
    q_ref[a] = std::clamp(0.0, model.axes[a].travel_min, model.axes[a].travel_max);
  run.tables = linearAxisTables(model, run.machine.params, q_ref, step_mm);
  std::vector<std::string> names;
  if (!run.tables.empty())
    for (int a : run.tables[0].prismatic) names.push_back(model.axes[a].name);
  char buf[160];
  for (size_t a = 0; a < model.axes.size(); ++a) {
    const bool rot = model.axes[a].isRotary();
    std::snprintf(buf, sizeof buf, "%s%s=%g %s", a ? " " : "", model.axes[a].name.c_str(),
                  rot ? radToDeg(q_ref[a]) : q_ref[a], rot ? "deg" : "mm");
    run.reference += buf;
  }
  OutputSet outputs;
  const std::string stem = replaceExtension(table, "");
  for (size_t k = 0; k < run.tables.size(); ++k) {
    const AxisTable& t = run.tables[k];
    std::vector<std::vector<double>> um;
    for (const Eigen::Vector3d& d : t.correction) {
      std::vector<double> row;
      for (size_t j = 0; j < names.size(); ++j)
        row.push_back(mmToUm(d[static_cast<Eigen::Index>(j)]));
      um.push_back(row);
    }
    std::snprintf(buf, sizeof buf, "grid: %s from %.3f mm, step %.3f mm, %zu points",
                  names[k].c_str(), t.start, t.step, t.position.size());
    const std::vector<std::string> header = {
        "tolver compensate, axis tables: " + model.name + " (" + machine_options.machine +
            "), axis " + names[k] + " (pitch and straightness)",
        buf,
        "corrections: the joint changes to command (machine-file joint convention; NC values: "
        "times nc_sign), "
        "um, added to those of the other axes' tables",
        "zero at the reference pose " + run.reference + "; tool tip " +
            formatNumber(model.setup.gauge_length) +
            " mm below the gauge point (the constant goes into the work offset)"};
    const std::string file = stem + "_" + names[k] + ".csv";
    checkOutputDir(file, "table");
    outputs.add(file, formatAxisTableCsv(names, static_cast<int>(k), t.position, um, header));
    run.files.push_back(file);
  }
  outputs.commit();
  run.flat = tableEffect(model, run.machine.params, run.tables, q_ref, false);
  run.full = tableEffect(model, run.machine.params, run.tables, q_ref, true);
  // The rotary axes' non-zero error terms: a linear table has no place for them.
  for (const ParameterBlock& b : model.blocks) {
    if (b.axis < 0 || !model.axes[b.axis].isRotary()) continue;
    for (int k = 0; k < b.size; ++k) {
      const int idx = b.offset + k;
      if (run.machine.params[idx] == 0.0) continue;
      if (run.rotary_terms++ < 8)
        run.rotary_names += (run.rotary_names.empty() ? "" : ", ") + model.parameters[idx].iso_code;
    }
  }
  return run;
}

CompensateRun compensateProgram(const CompensateInputs& in, const Progress& progress) {
  if (!(in.table_step >= 0.1 && in.table_step <= 1000.0))
    throw FieldError("table_step", "expected 0.1 to 1000 mm");
  if (!(in.max_condition >= 10.0 && in.max_condition <= 1e15))
    throw FieldError("max_condition", "expected 10 to 1e15");
  CompensateRun run;
  const bool program = !in.program.cl.empty() || !in.program.nc.empty();
  if (!in.table.empty()) {
    run.tables = runTables(in.machine, in.table_step, in.table);
    if (!program) return run;
  }
  if (in.output.empty())
    throw FieldError("output", "give the compensated program's path with " + inputName("output") +
                                   " (or only " + inputName("table") + ")");
  run.output = in.output;
  run.report = in.report.empty() ? replaceExtension(in.output, ".json") : in.report;
  run.joints = compensatedJointsPath(run.report);
  checkOutputDir(run.output, "output");
  checkOutputDir(run.report, "report");
  run.compensation = runCompensation(in, in.output, progress);
  if (progress) progress("writing and reading back", 1.0);
  const CompensationRun& c = *run.compensation;
  writeCompensation(c, in.output, run.report, in.report_dir);
  // The read-back check: a point further off after than before means the written program moves
  // where the original did not.
  for (size_t i = 0; i < c.tip_after_um.size() && i < c.tip_before_um.size(); ++i) {
    const double before = c.tip_before_um[i], after = c.tip_after_um[i];
    if (!(after <= before + std::max(1.0, 0.1 * before))) {
      if (run.worse_lines.empty() || run.worse_lines.back() != c.line[i])
        run.worse_lines.push_back(c.line[i]);
      run.worse_max_um = std::max(run.worse_max_um, after);
    }
  }
  if (!run.worse_lines.empty()) run.verdict = Verdict::NotMet;
  return run;
}

}  // namespace tolver
