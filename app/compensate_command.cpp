// tolver compensate: a corrected program that the machine, errors included, runs onto the
// nominal path; the predicted error before and after (the after measured on the written file).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <set>

#include "app/commands.h"
#include "app/common.h"
#include "core/path/compensation.h"
#include "core/path/prediction_uncertainty.h"
#include "io/program/compensated_program.h"
#include "io/report/compensation_report.h"
#include "io/common/io_error.h"
#include "io/common/text_util.h"
#include "core/numerics/units.h"

namespace tolver::app {
namespace {

struct CompensateOptions {
  MachineOptions machine;
  ProgramOptions program;
  std::string output, report, probed;
  bool absolute = false;
  double max_condition = 1e6;
  std::string report_dir;     // --report-dir: report.json, report.html, charts
  std::string table;          // --table: linear-axis compensation tables
  double table_step = 10.0;   // mm
};

// --table: one CSV per linear axis, and what such tables leave.
void writeTables(const CompensateOptions& o, const Machine& machine) {
  const MachineModel& model = machine.model;
  JointVector q_ref = JointVector::Zero(static_cast<int>(model.axes.size()));
  for (size_t a = 0; a < model.axes.size(); ++a)
    q_ref[a] = std::clamp(0.0, model.axes[a].travel_min, model.axes[a].travel_max);
  const std::vector<AxisTable> tables = linearAxisTables(model, machine.params, q_ref, o.table_step);
  std::vector<std::string> names;
  if (!tables.empty())
    for (int a : tables[0].prismatic) names.push_back(model.axes[a].name);
  std::string ref_text;
  char buf[160];
  for (size_t a = 0; a < model.axes.size(); ++a) {
    const bool rot = model.axes[a].isRotary();
    std::snprintf(buf, sizeof buf, "%s%s=%g %s", a ? " " : "", model.axes[a].name.c_str(),
                  rot ? radToDeg(q_ref[a]) : q_ref[a], rot ? "deg" : "mm");
    ref_text += buf;
  }
  OutputSet outputs;
  std::vector<std::string> written;
  const std::string stem = replaceExtension(o.table, "");
  for (size_t k = 0; k < tables.size(); ++k) {
    const AxisTable& t = tables[k];
    std::vector<std::vector<double>> um;
    for (const Eigen::Vector3d& d : t.correction) {
      std::vector<double> row;
      for (size_t j = 0; j < names.size(); ++j) row.push_back(mmToUm(d[static_cast<Eigen::Index>(j)]));
      um.push_back(row);
    }
    std::snprintf(buf, sizeof buf, "grid: %s from %.3f mm, step %.3f mm, %zu points", names[k].c_str(), t.start,
                  t.step, t.position.size());
    const std::vector<std::string> header = {
        "tolver compensate --table: " + model.name + " (" + o.machine.machine + "), axis " + names[k] +
            " (pitch and straightness)",
        buf,
        "corrections: the joint changes to command (machine-file joint convention; NC values: times nc_sign), "
        "um, added to those of the other axes' tables",
        "zero at the reference pose " + ref_text + "; tool tip " + formatNumber(model.setup.gauge_length) +
            " mm below the gauge point (the constant goes into the work offset)"};
    const std::string file = stem + "_" + names[k] + ".csv";
    checkOutputDir(file, "--table");
    outputs.add(file, formatAxisTableCsv(names, static_cast<int>(k), t.position, um, header));
    written.push_back(file);
  }
  outputs.commit();
  const TableEffect flat = tableEffect(model, machine.params, tables, q_ref, false);
  const TableEffect full = tableEffect(model, machine.params, tables, q_ref, true);
  std::printf("tolver compensate --table\n");
  std::printf("  machine    %s (%s)\n", model.name.c_str(), o.machine.machine.c_str());
  std::printf("  tables     %zu linear axes, step %.3f mm, zero at %s\n", tables.size(), o.table_step, ref_text.c_str());
  std::printf("  effect     tool-tip error over the linear travel (relative to the reference pose, whose constant "
              "the work offset takes), rotary axes at the reference: RMS %.3f -> %.3f um\n",
              mmToUm(flat.before_rms), mmToUm(flat.after_rms));
  std::printf("             over the whole travel, rotary axes moving: RMS %.3f -> %.3f um (what linear tables cannot "
              "carry: the rotary axes' errors and the angular errors seen through the other axes' offsets)\n",
              mmToUm(full.before_rms), mmToUm(full.after_rms));
  // The rotary axes' non-zero error terms: a linear table has no place for them.
  std::string rotary;
  int count = 0;
  for (const ParameterBlock& b : model.blocks) {
    if (b.axis < 0 || !model.axes[b.axis].isRotary()) continue;
    for (int k = 0; k < b.size; ++k) {
      const int idx = b.offset + k;
      if (machine.params[idx] == 0.0) continue;
      if (count++ < 8) rotary += (rotary.empty() ? "" : ", ") + model.parameters[idx].iso_code;
    }
  }
  if (count > 0)
    std::printf("  not carried %d error terms of the rotary axes (%s%s): a five-axis volumetric "
                "compensation of the control is needed for them\n",
                count, rotary.c_str(), count > 8 ? ", ..." : "");
  for (const std::string& f : written) std::printf("  wrote      %s\n", f.c_str());
}

double angle(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b));
}

// Figures over points [from, to): tip deviations (mm) and axis angles (rad).
PathFigures figuresOf(const std::vector<Eigen::Vector3d>& dev, const std::vector<double>& ang,
                      const std::vector<ClPoint>& path, size_t from, size_t to) {
  PathFigures f;
  double st = 0, sa = 0;
  for (size_t i = from; i < to; ++i) {
    const double t = mmToUm(dev[i].norm()), a = radToUrad(ang[i]);
    st += t * t;
    sa += a * a;
    if (t > f.tip_max_um) f.tip_max_um = t, f.tip_max_line = path[i].line;
    f.axis_max_urad = std::max(f.axis_max_urad, a);
  }
  const double n = std::max<size_t>(1, to - from);
  f.tip_rms_um = std::sqrt(st / n);
  f.axis_rms_urad = std::sqrt(sa / n);
  return f;
}

void runCompensate(const CompensateOptions& o, int* exit_code) {
  if (!o.table.empty()) {
    writeTables(o, loadMachine(o.machine));
    *exit_code = 0;
    if (o.program.cl.empty() && o.program.nc.empty()) return;
  }
  if (o.output.empty())
    throw InputError("-o", 0, 0, "-o", "give the compensated program's path with -o (or only --table)");
  Machine machine = loadMachine(o.machine);
  const ClProgram program = loadProgram(o.program, machine.model);
  const std::string report = o.report.empty() ? replaceExtension(o.output, ".json") : o.report;
  checkOutputDir(o.output, "-o");
  checkOutputDir(report, "--report");
  PredictionResult pred = predictProgram(machine, program);
  // A calibrated machine: its share after the set-up the shop measures (the calibration cannot
  // see the rest), as predict takes it.
  const std::vector<ProbedPoint> probed = loadProbed(o.probed, machine.model);
  const CalibratedPrediction cal = applyCalibration(machine, program, pred, o.absolute, probed);
  std::vector<std::string> warnings;
  std::string setup_note;
  if (cal.probed)
    setup_note = describeProbedSetup(o.probed, cal.probe, probed, &warnings);
  else if (!machine.identification.empty())
    setup_note = o.absolute ? "absolute (--absolute): what probing and presetting would take up is compensated too"
                            : "after the set-up a shop measures (part probed, tool preset), which the calibration cannot see";

  const bool gcode = program.dialect == "G-code";
  const bool orientation = gcode ? gcodeGivesRotaryWords(program, machine.model) : program.multiax;
  std::vector<JointVector> q0(pred.points.size());
  for (size_t i = 0; i < q0.size(); ++i) q0[i] = pred.points[i].q;
  CompensationOptions co;
  co.max_condition = o.max_condition;
  const CompensationResult comp = compensateToolPath(machine.model, machine.params, program.path, q0, orientation, co,
                                                       &pred.points);

  // The corrected program, in the source's dialect.
  const std::vector<std::string> header = {
      "tolver compensate: " + program.file + " for " + machine.model.name + " (" + o.machine.machine +
      "): the machine with its errors runs this program onto the original's nominal path"};
  CompensatedProgramText text;
  if (gcode) {
    std::vector<JointVector> q(comp.points.size());
    std::vector<Eigen::Vector3d> p(comp.points.size());
    for (size_t i = 0; i < q.size(); ++i) {
      q[i] = comp.points[i].q;
      p[i] = comp.points[i].nominal_p_w;
    }
    text = formatCompensatedGcode(program, machine.model, program.joints, q, p, header);
  } else {
    std::vector<ClPoint> corrected = program.path;
    for (size_t i = 0; i < corrected.size(); ++i) {
      corrected[i].p_w = comp.points[i].nominal_p_w;
      corrected[i].u_w = comp.points[i].nominal_u_w;
    }
    text = formatCompensatedApt(program, corrected, header);
  }
  // The source's byte-order mark and line endings.
  {
    const std::string raw = readFile(o.program.nc.empty() ? o.program.cl : o.program.nc);
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
  }
  // The after, measured on the file as written: read back, predicted on the machine.
  // Read back whole, then the points of the source lines compensated (--lines).
  ProgramOptions whole = o.program;
  whole.lines.clear();
  ClProgram back = parseProgram(text.text, o.output, whole, machine.model);
  if (!o.program.lines.empty()) {
    std::set<int> lines;
    for (const ClPoint& c : program.path) lines.insert(c.line);
    size_t k = 0;
    for (size_t i = 0; i < back.path.size(); ++i) {
      const int l = back.path[i].line;
      const int src = l >= 1 && l <= static_cast<int>(text.source_line.size()) ? text.source_line[l - 1] : 0;
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
    throw std::runtime_error("the compensated program reads back with " + std::to_string(back.path.size()) +
                             " points instead of " + std::to_string(program.path.size()) + " (from line " +
                             std::to_string(k < program.path.size() ? program.path[k].line : 0) + ")");
  }
  const PredictionResult after = predictToolPath(machine.model, machine.params, back.path, 20,
                                                 back.joints.empty() ? nullptr : &back.joints);
  if (!after.ok())
    throw std::runtime_error("the compensated program does not predict: " + after.failures.front().message);
  const size_t n = program.path.size();
  std::vector<Eigen::Vector3d> dev_before(n), dev_after(n);
  std::vector<double> ang_before(n), ang_after(n);
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d u_t = program.path[i].u_w.normalized();
    dev_before[i] = pred.points[i].p_pred_w - program.path[i].p_w;
    ang_before[i] = angle(pred.points[i].u_pred_w, u_t);
    dev_after[i] = after.points[i].p_pred_w - program.path[i].p_w;
    ang_after[i] = orientation ? angle(after.points[i].u_pred_w, u_t) : ang_before[i];
  }
  CompensationReport rep;
  rep.machine = o.machine.machine;
  rep.program = program.file;
  rep.dialect = program.dialect;
  rep.output = o.output;
  rep.points = static_cast<int>(n);
  rep.before = figuresOf(dev_before, ang_before, program.path, 0, n);
  rep.after = figuresOf(dev_after, ang_after, program.path, 0, n);
  {
    std::vector<Eigen::Vector3d> d;
    std::vector<double> g;
    std::vector<ClPoint> at;
    for (size_t i = 0; i < n; ++i)
      if (text.written[i] && (comp.points[i].status == CompensationStatus::Compensated ||
                              comp.points[i].status == CompensationStatus::IllConditioned)) {
        d.push_back(dev_after[i]);
        g.push_back(ang_after[i]);
        at.push_back(program.path[i]);
      }
    rep.compensated_points = static_cast<int>(d.size());
    rep.after_compensated = figuresOf(d, g, at, 0, d.size());
  }
  rep.setup_note = setup_note;
  rep.notes = text.notes;
  for (size_t a = 0; a < machine.model.axes.size(); ++a) {
    double m = 0;
    for (const CompensatedPoint& c : comp.points) m = std::max(m, std::abs(c.q[a] - c.q0[a]));
    const bool rot = machine.model.axes[a].isRotary();
    rep.joint_correction_max.push_back({machine.model.axes[a].name, m * (rot ? 1e6 : 1e3)});
    rep.joint_rotary.push_back(rot);
  }
  rep.ill_conditioned = comp.ill_conditioned;
  rep.out_of_travel = comp.out_of_travel;
  rep.not_converged = comp.not_converged;
  for (size_t i = 0; i < n; ++i) {
    if (comp.points[i].status == CompensationStatus::IllConditioned) rep.ill_conditioned_lines.push_back(program.path[i].line);
    if (comp.points[i].status == CompensationStatus::OutOfTravel) rep.out_of_travel_lines.push_back(program.path[i].line);
    rep.left_by_writer += !text.written[i] && comp.points[i].status != CompensationStatus::OutOfTravel &&
                          comp.points[i].status != CompensationStatus::NotConverged;
  }
  // Segments: runs of cutting moves between rapids.
  for (size_t i = 0; i < n;) {
    if (program.path[i].rapid) {
      ++i;
      continue;
    }
    size_t j = i;
    while (j < n && !program.path[j].rapid) ++j;
    SegmentFigures s;
    s.first_line = program.path[i].line;
    s.last_line = program.path[j - 1].line;
    s.points = static_cast<int>(j - i);
    s.before = figuresOf(dev_before, ang_before, program.path, i, j);
    s.after = figuresOf(dev_after, ang_after, program.path, i, j);
    rep.segments.push_back(s);
    i = j;
  }
  // The model's own uncertainty of the after (a calibrated machine).
  if (!cal.uncertainty.empty()) {
    PredictionUncertainty pu(machine);
    if (cal.probed)
      pu.setupModuloProbed(probed);
    else if (!o.absolute) {
      std::vector<JointVector> sub;
      const size_t step = std::max<size_t>(1, n / 2000);
      for (size_t i = 0; i < n; i += step) sub.push_back(after.points[i].q);
      pu.setupModulo(sub);
    }
    std::vector<double> band(n);
    for (size_t i = 0; i < n; ++i) band[i] = 1.96 * mmToUm(pu.at(after.points[i].q).tip);
    rep.after_band95_max_um = *std::max_element(band.begin(), band.end());
    std::nth_element(band.begin(), band.begin() + n / 2, band.end());
    rep.after_band95_median_um = band[n / 2];
  }
  OutputSet outputs;
  outputs.add(o.output, text.text);
  outputs.add(report, formatCompensationJson(rep));
  outputs.commit();
  if (!o.report_dir.empty()) {
    ReportDirectory report_dir(o.report_dir);  // written as a whole, swapped in at the end
    std::vector<int> line(n);
    std::vector<double> tb(n), ta(n), ab(n), aa(n);
    for (size_t i = 0; i < n; ++i) {
      line[i] = program.path[i].line;
      tb[i] = mmToUm(dev_before[i].norm());
      ta[i] = mmToUm(dev_after[i].norm());
      ab[i] = radToUrad(ang_before[i]);
      aa[i] = radToUrad(ang_after[i]);
    }
    writeCompensationReport(report_dir.staging(), rep, line, tb, ta, ab, aa);
    report_dir.commit();
  }

  std::printf("tolver compensate\n");
  std::printf("  machine    %s (%s)\n", machine.model.name.c_str(), o.machine.machine.c_str());
  std::printf("  program    %s (%s): %zu tool positions%s, %s\n", program.file.c_str(), program.dialect.c_str(), n,
              o.program.lines.empty() ? "" : (" of lines " + o.program.lines + " (the other lines written as they are)").c_str(),
              orientation ? "tool tip and tool axis compensated" : "3-axis: the tool tip compensated by the linear axes");
  if (!setup_note.empty()) std::printf("  set-up     %s\n", setup_note.c_str());
  std::printf("  before     tip max %.3f um (line %d), RMS %.3f um; tool axis max %.2f urad, RMS %.2f urad\n",
              rep.before.tip_max_um, rep.before.tip_max_line, rep.before.tip_rms_um, rep.before.axis_max_urad,
              rep.before.axis_rms_urad);
  std::printf("  after      tip max %.4f um (line %d), RMS %.4f um; tool axis max %.3f urad, RMS %.3f urad "
              "(the written program, read back and predicted)\n",
              rep.after.tip_max_um, rep.after.tip_max_line, rep.after.tip_rms_um, rep.after.axis_max_urad,
              rep.after.axis_rms_urad);
  if (rep.compensated_points < static_cast<int>(n))
    std::printf("             on the %d points the file compensates (the others are listed below): tip max "
                "%.4f um, RMS %.4f um; tool axis max %.3f urad\n",
                rep.compensated_points, rep.after_compensated.tip_max_um, rep.after_compensated.tip_rms_um,
                rep.after_compensated.axis_max_urad);
  if (rep.after_band95_max_um >= 0)
    std::printf("  model      the after is zero only to within the calibration's uncertainty: 95 %% band median "
                "%.3f um, max %.3f um (compensation removes what the model knows, not what it does not)\n",
                rep.after_band95_median_um, rep.after_band95_max_um);
  std::string jc;
  char buf[96];
  for (size_t a = 0; a < rep.joint_correction_max.size(); ++a) {
    std::snprintf(buf, sizeof buf, "%s%s %.3f %s", a ? ", " : "", rep.joint_correction_max[a].first.c_str(),
                  rep.joint_correction_max[a].second, rep.joint_rotary[a] ? "urad" : "um");
    jc += buf;
  }
  std::printf("  joints     largest corrections: %s\n", jc.c_str());
  if (rep.segments.size() > 1) {
    std::vector<const SegmentFigures*> worst;
    for (const SegmentFigures& s : rep.segments) worst.push_back(&s);
    std::sort(worst.begin(), worst.end(), [](auto* a, auto* b) { return a->before.tip_max_um > b->before.tip_max_um; });
    std::printf("  segments   %zu (cutting runs between rapids); the worst before:", rep.segments.size());
    for (size_t k = 0; k < worst.size() && k < 3; ++k)
      std::printf("%s lines %d-%d %.2f -> %.4f um", k ? "," : "", worst[k]->first_line, worst[k]->last_line,
                  worst[k]->before.tip_max_um, worst[k]->after.tip_max_um);
    std::printf("\n");
  }
  auto lines = [](const std::vector<int>& v) {
    std::string s;
    for (size_t k = 0; k < v.size() && k < 6; ++k) s += (k ? ", " : "") + std::to_string(v[k]);
    return s + (v.size() > 6 ? ", ..." : "");
  };
  if (rep.out_of_travel > 0)
    std::printf("  travel     %d points would need joints beyond travel: left uncompensated (lines %s)\n",
                rep.out_of_travel, lines(rep.out_of_travel_lines).c_str());
  if (rep.not_converged > 0) std::printf("  warning    %d points did not converge: left uncompensated\n", rep.not_converged);
  if (rep.ill_conditioned > 0)
    std::printf("  singular   %d points near a singular pose (condition above %.0e): the tool tip "
                "compensated, the tool axis left as programmed (correcting it would swing a rotary axis) "
                "(lines %s)\n",
                rep.ill_conditioned, o.max_condition, lines(rep.ill_conditioned_lines).c_str());
  for (const std::string& note : text.notes) std::printf("  note       %s\n", note.c_str());
  for (const std::string& w : warnings) std::fprintf(stderr, "tolver: warning: %s\n", w.c_str());
  for (const std::string& w : setupWarnings(machine.model)) std::fprintf(stderr, "tolver: warning: %s\n", w.c_str());
  std::printf("  wrote      %s (compensated program), %s (report)\n", o.output.c_str(), report.c_str());
  if (!o.report_dir.empty())
    std::printf("  report     %s/report.html (and report.json, tip_deviation.png, tool_axis.png)\n", o.report_dir.c_str());
  *exit_code = 0;
}

}  // namespace

void registerCompensate(CLI::App& app, int* exit_code) {
  auto o = std::make_shared<CompensateOptions>();
  CLI::App* cmd = app.add_subcommand(
      "compensate",
      "Write the program that the machine, errors included, runs onto the nominal path: joints by "
      "Newton on the full error model, written back in the program's own dialect, with the "
      "predicted error before and after.");
  addMachineOptions(cmd, o->machine, "machine file (XML) with the errors to compensate");
  addProgramOptions(cmd, o->program);
  cmd->add_option("-o,--output", o->output, "compensated program to write (same dialect as the input)");
  cmd->add_option("--table", o->table,
                  "also (or only) write pitch and straightness tables for the linear axes: "
                  "<stem>_<axis>.csv per axis");
  cmd->add_option("--table-step", o->table_step, "grid step of the tables, mm (default 10)")
      ->check(CLI::Range(0.1, 1000.0));
  cmd->add_option("--report", o->report, "JSON report (default: the output path with .json)");
  cmd->add_option("--report-dir", o->report_dir,
                  "also write report.html with before/after charts (and report.json) in this directory");
  cmd->add_option("--max-condition", o->max_condition,
                  "condition number beyond which a point counts as near a singular pose (default 1e6)")
      ->check(CLI::Range(10.0, 1e15));
  cmd->add_flag("--absolute", o->absolute,
                "a calibrated machine: compensate its raw prediction, with what probing and presetting "
                "would take up");
  addProbedOption(cmd, o->probed);
  cmd->callback([o, exit_code] { runCompensate(*o, exit_code); });
}

}  // namespace tolver::app
