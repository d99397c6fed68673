// The compensate pipeline: see pipeline/compensate.h.
#include "pipeline/compensate.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>
#include <set>
#include <stdexcept>

#include "core/numerics/statistics.h"
#include "core/numerics/units.h"
#include "core/path/prediction_uncertainty.h"
#include "core/path/tool_motion.h"
#include "io/common/io_error.h"
#include "io/common/line_source.h"
#include "io/common/text_util.h"
#include "pipeline/block_predictor.h"
#include "pipeline/parallel_prediction.h"

namespace tolver {
namespace {

double angle(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b));
}

// Running figures over points added one at a time: tip deviations (um), axis angles (urad).
class FigureSum {
 public:
  void add(double tip_um, double axis_urad, int line) {
    st_ += tip_um * tip_um;
    sa_ += axis_urad * axis_urad;
    ++n_;
    if (tip_um > f_.tip_max_um) f_.tip_max_um = tip_um, f_.tip_max_line = line;
    f_.axis_max_urad = std::max(f_.axis_max_urad, axis_urad);
  }
  PathFigures figures() const {
    PathFigures f = f_;
    const double n = static_cast<double>(std::max<size_t>(1, n_));
    f.tip_rms_um = std::sqrt(st_ / n);
    f.axis_rms_urad = std::sqrt(sa_ / n);
    return f;
  }
  size_t count() const { return n_; }

 private:
  PathFigures f_;
  double st_ = 0, sa_ = 0;
  size_t n_ = 0;
};

// One program point as the report counts it: before and after (um, urad), its status, whether
// the written text commands its compensation, its joints (program's q0 and compensating q).
struct TalliedPoint {
  int line = 0;
  bool rapid = false, written = false;
  CompensationStatus status = CompensationStatus::Compensated;
  double tip_before_um = 0, axis_before_urad = 0, tip_after_um = 0, axis_after_urad = 0;
  const double* q0 = nullptr;
  const double* q = nullptr;
};

// The report's figures over a program's points in order, one at a time: a whole program's
// arrays or a program streamed block by block alike, in memory independent of its length (the
// band's medians within 1.6e-5, StreamQuantiles).
class CompensationTally {
 public:
  explicit CompensationTally(const MachineModel& model)
      : model_(model), correction_(model.axes.size(), 0.0) {}

  void add(const TalliedPoint& p) {
    before_.add(p.tip_before_um, p.axis_before_urad, p.line);
    after_.add(p.tip_after_um, p.axis_after_urad, p.line);
    const bool compensated = p.status == CompensationStatus::Compensated ||
                             p.status == CompensationStatus::IllConditioned;
    if (p.written && compensated) compensated_.add(p.tip_after_um, p.axis_after_urad, p.line);
    for (size_t a = 0; a < correction_.size(); ++a)
      correction_[a] = std::max(correction_[a], std::abs(p.q[a] - p.q0[a]));
    switch (p.status) {
      case CompensationStatus::IllConditioned:
        ++rep_.ill_conditioned;
        rep_.ill_conditioned_lines.push_back(p.line);
        break;
      case CompensationStatus::OutOfTravel:
        ++rep_.out_of_travel;
        rep_.out_of_travel_lines.push_back(p.line);
        break;
      case CompensationStatus::NotConverged:
        ++rep_.not_converged;
        break;
      case CompensationStatus::Compensated:
        break;
    }
    rep_.left_by_writer += !p.written && p.status != CompensationStatus::OutOfTravel &&
                           p.status != CompensationStatus::NotConverged;
    // Segments: runs of cutting moves between rapids.
    if (p.rapid) {
      closeSegment();
    } else {
      if (!in_segment_) {
        in_segment_ = true;
        segment_ = SegmentFigures{};
        segment_.first_line = p.line;
        seg_before_ = seg_after_ = FigureSum{};
      }
      segment_.last_line = p.line;
      ++segment_.points;
      seg_before_.add(p.tip_before_um, p.axis_before_urad, p.line);
      seg_after_.add(p.tip_after_um, p.axis_after_urad, p.line);
    }
    // The read-back check: further off after than before (by more than 1 um and 10 %).
    if (!(p.tip_after_um <= p.tip_before_um + std::max(1.0, 0.1 * p.tip_before_um))) {
      if (worse_lines.empty() || worse_lines.back() != p.line) worse_lines.push_back(p.line);
      worse_max_um = std::max(worse_max_um, p.tip_after_um);
    }
  }

  // The model's 95 % radii of the after at a point (calibrated machine; um, urad).
  void addBand(double tip_um, double axis_urad) {
    band_tip_.add(tip_um);
    band_axis_.add(axis_urad);
    band_tip_max_ = std::max(band_tip_max_, tip_um);
    band_axis_max_ = std::max(band_axis_max_, axis_urad);
  }

  // The figures into rep (its other fields as they were).
  void finish(CompensationReport& rep) {
    closeSegment();
    rep.points = static_cast<int>(before_.count());
    rep.before = before_.figures();
    rep.after = after_.figures();
    rep.compensated_points = static_cast<int>(compensated_.count());
    rep.after_compensated = compensated_.figures();
    // The counts and lists gathered point by point.
    for (int CompensationReport::*count :
         {&CompensationReport::ill_conditioned, &CompensationReport::out_of_travel,
          &CompensationReport::not_converged, &CompensationReport::left_by_writer})
      rep.*count = rep_.*count;
    for (std::vector<int> CompensationReport::*lines :
         {&CompensationReport::ill_conditioned_lines, &CompensationReport::out_of_travel_lines})
      rep.*lines = rep_.*lines;
    rep.segments = std::move(rep_.segments);
    rep.joint_correction_max.clear();
    rep.joint_rotary.clear();
    for (size_t k = 0; k < model_.axes.size(); ++k) {
      const bool rot = model_.axes[k].isRotary();
      rep.joint_correction_max.push_back(
          {model_.axes[k].name, rot ? radToUrad(correction_[k]) : mmToUm(correction_[k])});
      rep.joint_rotary.push_back(rot);
    }
    if (band_tip_.count() > 0) {
      const size_t mid = band_tip_.count() / 2;
      rep.after_band95_median_um = band_tip_.ranked(mid);
      rep.after_band95_max_um = band_tip_max_;
      rep.after_axis_band95_median_urad = band_axis_.ranked(mid);
      rep.after_axis_band95_max_urad = band_axis_max_;
    }
  }

  std::vector<int> worse_lines;
  double worse_max_um = 0.0;

 private:
  void closeSegment() {
    if (!in_segment_) return;
    in_segment_ = false;
    segment_.before = seg_before_.figures();
    segment_.after = seg_after_.figures();
    rep_.segments.push_back(segment_);
  }

  const MachineModel& model_;
  FigureSum before_, after_, compensated_, seg_before_, seg_after_;
  std::vector<double> correction_;  // per axis, max |q - q0| (mm, rad)
  CompensationReport rep_;          // the counts, lines and segments gathered
  bool in_segment_ = false;
  SegmentFigures segment_;
  StreamQuantiles band_tip_, band_axis_;
  double band_tip_max_ = 0, band_axis_max_ = 0;
};

// The comment at the top of a compensated program.
std::vector<std::string> compensatedHeader(const CompensateInputs& in, const ClProgram& program,
                                           const std::string& machine_name) {
  std::vector<std::string> h = {
      "tolver compensate: " + program.file + " for " + machine_name + " (" + in.machine.machine +
      "): the machine with its errors runs this program onto the original's nominal path"};
  // The user's unit over the file's UNITS (--cl-units): the statement is copied as it stands,
  // the numbers are in the user's unit (as the predicted CL says it, io/program/apt_writer.cpp).
  if (program.dialect != "G-code" && !program.units_in_file.empty()) {
    const bool inch = program.units == "INCH";
    h.push_back(std::string("the numbers are in ") + (inch ? "inches" : "mm") +
                ", not as UNITS at line " + std::to_string(program.units_line) +
                " declares: read this file with --cl-units " + (inch ? "inch" : "mm"));
  }
  return h;
}

// The source's byte-order mark and line endings (from its first line), which the compensated
// program keeps.
struct SourceEncoding {
  bool bom = false, crlf = false;
  explicit SourceEncoding(const std::string& path) {
    const std::string head = readFilePrefix(path, 65536);
    const size_t eol = head.find('\n');
    crlf = eol != std::string::npos && eol > 0 && head[eol - 1] == '\r';
    bom = head.rfind("\xEF\xBB\xBF", 0) == 0;
  }
  // text with the source's line endings.
  void apply(std::string& text) const {
    if (!crlf) return;
    std::string out;
    out.reserve(text.size() + text.size() / 30);
    for (char ch : text) {
      if (ch == '\n') out += '\r';
      out += ch;
    }
    text = std::move(out);
  }
};

// The corrected program in the source's dialect, with the source's byte-order mark and line
// endings.
CompensatedProgramText correctedText(const CompensateInputs& in, const CompensationRun& run) {
  const ClProgram& program = run.program;
  const std::vector<CompensatedPoint>& cp = run.compensation.points;
  const std::vector<std::string> header = compensatedHeader(in, program, run.machine.model.name);
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
  const SourceEncoding encoding(in.program.nc.empty() ? in.program.cl : in.program.nc);
  encoding.apply(text.text);
  if (encoding.bom) text.text.insert(0, "\xEF\xBB\xBF");
  return text;
}

// Whether the machine can turn the tool axis onto a program's: two rotary axes or more. With
// fewer, a multi-axis program's tip is compensated by the linear axes and said so (Newton on the
// axis rows would never converge: 3 or 4 joints for 5 conditions).
bool turnsToolAxis(const MachineModel& model) {
  return std::count_if(model.axes.begin(), model.axes.end(),
                       [](const Axis& a) { return a.isRotary(); }) >= 2;
}

std::string tipOnlyNote(const MachineModel& model) {
  const auto rotary = std::count_if(model.axes.begin(), model.axes.end(),
                                    [](const Axis& a) { return a.isRotary(); });
  return "the program gives tool axes and the machine has " + std::to_string(rotary) +
         (rotary == 1 ? " rotary axis" : " rotary axes") +
         ": the tool tip compensated by the linear axes, the tool axis left where the machine "
         "holds it";
}

// The report's note on points in a swivelled plane.
std::string cycleNote(size_t points) {
  return std::to_string(points) +
         " points in a swivelled plane (CYCLE800): the tip compensated by the linear axes, the "
         "tool axis left where the cycle puts it";
}

// A point's status in the joints file.
const char* statusWord(bool written, CompensationStatus status) {
  return !written                                       ? "kept"
         : status == CompensationStatus::Compensated    ? "compensated"
         : status == CompensationStatus::IllConditioned ? "ill_conditioned"
         : status == CompensationStatus::OutOfTravel    ? "out_of_travel"
                                                        : "not_converged";
}

// The joints file (<report>_joints.csv), written a point at a time: the header, then per point
// the program's joints and those the written file commands (the compensating ones where it
// compensates), mm or deg.
class JointsWriter {
 public:
  JointsWriter(const MachineModel& model, TextOut& out)
      : model_(model), out_(out), before_(model.axes.size()), after_(model.axes.size()) {
    std::vector<std::string> names;
    std::vector<bool> rotary;
    for (const Axis& ax : model.axes) {
      names.push_back(ax.name);
      rotary.push_back(ax.isRotary());
    }
    out_ += compensatedJointsCsvHeader(names, rotary);
  }
  void add(size_t index, int line, bool written, CompensationStatus status, const double* q0,
           const double* q, double tip_after_um, double axis_after_urad) {
    for (size_t a = 0; a < before_.size(); ++a) {
      const double k = model_.axes[a].isRotary() ? radToDeg(1.0) : 1.0;
      before_[a] = q0[a] * k;
      after_[a] = (written ? q[a] : q0[a]) * k;
    }
    writeCompensatedJointsRow(out_, index, line, statusWord(written, status), before_.data(),
                              after_.data(), before_.size(), tip_after_um, axis_after_urad);
  }

 private:
  const MachineModel& model_;
  TextOut& out_;
  std::vector<double> before_, after_;
};

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

// The model's own uncertainty of the after on a calibrated machine, per point: the 95 % radii
// of the tip's distance and the tool axis's angle.
void afterBand(const CompensateInputs& in, const std::vector<ProbedPoint>& probed, bool probed_fit,
               const CompensationRun& run, CompensationTally& tally) {
  const size_t n = run.program.path.size();
  PredictionUncertainty pu(run.machine);
  if (probed_fit) {
    pu.setupModuloProbed(probed);
  } else if (!in.absolute) {
    EvenPoses even;  // the poses a streamed program's band takes too
    for (size_t i = 0; i < n; ++i)
      if (even.wants(i)) even.add(i, run.after.points[i].q, Eigen::Vector3d::Zero());
    pu.setupModulo(even.q);
  }
  for (size_t i = 0; i < n; ++i) {
    const PoseUncertainty u = pu.at(run.after.points[i].q);
    tally.addBand(mmToUm(PredictionUncertainty::tipRadius95(u)),
                  radToUrad(PredictionUncertainty::axisRadius95(u)));
  }
}

// What the model's band leaves out, on a calibrated machine.
void bandSources(const Machine& machine, CompensationReport& rep) {
  rep.after_lack_of_fit_um = mmToUm(machine.identification.lack_of_fit_mm);
  rep.after_tilt_prior_urad = radToUrad(machine.identification.spindle_tilt_rad);
}

void fillReport(const CompensateInputs& in, const std::string& output, CompensationRun& run,
                CompensationTally& tally) {
  CompensationReport& rep = run.report;
  const ClProgram& program = run.program;
  const std::vector<CompensatedPoint>& cp = run.compensation.points;
  rep.machine = in.machine.machine;
  rep.program = program.file;
  rep.dialect = program.dialect;
  rep.output = output;
  for (size_t i = 0; i < program.path.size(); ++i) {
    TalliedPoint p;
    p.line = run.line[i];
    p.rapid = program.path[i].rapid;
    p.written = run.text.written[i] != 0;
    p.status = cp[i].status;
    p.tip_before_um = run.tip_before_um[i];
    p.axis_before_urad = run.axis_before_urad[i];
    p.tip_after_um = run.tip_after_um[i];
    p.axis_after_urad = run.axis_after_urad[i];
    p.q0 = cp[i].q0.data();
    p.q = cp[i].q.data();
    tally.add(p);
  }
  tally.finish(rep);
  run.worse_lines = tally.worse_lines;
  run.worse_max_um = tally.worse_max_um;
  rep.setup_note = run.setup_note;
  rep.notes = run.text.notes;
  if (const auto n =
          std::count(run.program.cycle_orientation.begin(), run.program.cycle_orientation.end(), 1))
    rep.notes.push_back(cycleNote(static_cast<size_t>(n)));
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
  const bool tip_only = run.orientation && !turnsToolAxis(run.machine.model);
  if (tip_only) run.orientation = false;
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
  if (tip_only) run.text.notes.push_back(tipOnlyNote(run.machine.model));
  // The after, measured on the file as written: read back, predicted on the machine.
  const ClProgram back = readBack(in, run, output);
  run.after = predictToolPathParallel(run.machine.model, run.machine.params, back.path, 20,
                                      back.joints.empty() ? nullptr : &back.joints);
  if (!run.after.ok())
    throw std::runtime_error("the compensated program does not predict: " +
                             run.after.failures.front().message);
  pointFigures(run);
  CompensationTally tally(run.machine.model);
  if (!cal.uncertainty.empty()) {
    afterBand(in, probed, cal.probed, run, tally);
    bandSources(run.machine, run.report);
  }
  fillReport(in, output, run, tally);
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
  outputs.addStreamed(compensatedJointsPath(report_json), [&run](TextOut& out) {
    JointsWriter joints(run.machine.model, out);
    const std::vector<CompensatedPoint>& cp = run.compensation.points;
    for (size_t i = 0; i < cp.size(); ++i)
      joints.add(i, run.line[i], i < run.text.written.size() && run.text.written[i], cp[i].status,
                 cp[i].q0.data(), cp[i].q.data(), run.tip_after_um[i], run.axis_after_urad[i]);
  });
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

namespace {

// Whether compensateProgram streams the program (pipeline/compensate.h).
bool streamsCompensation(const CompensateInputs& in) {
  return in.block_points > 0 && in.program.lines.empty() && in.process.empty();
}

// Fixed-width records of doubles in a temporary file (removed when done): a streamed program's
// per-point data between its compensating pass and its read-back.
class PointSpool {
 public:
  PointSpool(std::string path, size_t width) : path_(std::move(path)), width_(width) {
    file_ = std::fopen(path_.c_str(), "w+b");
    if (!file_)
      throw InputError(path_, 0, 0, "output",
                       std::string("cannot write a temporary file: ") + std::strerror(errno));
  }
  PointSpool(const PointSpool&) = delete;
  PointSpool& operator=(const PointSpool&) = delete;
  ~PointSpool() {
    std::fclose(file_);
    std::remove(path_.c_str());
  }
  size_t width() const { return width_; }
  size_t count() const { return count_; }
  void write(const std::vector<double>& records) {
    if (std::fwrite(records.data(), sizeof(double), records.size(), file_) != records.size())
      throw InputError(path_, 0, 0, "output", "cannot write a temporary file");
    count_ += records.size() / width_;
  }
  void rewind() {
    if (std::fflush(file_) != 0 || std::fseek(file_, 0, SEEK_SET) != 0)
      throw InputError(path_, 0, 0, "output", "cannot read back a temporary file");
  }
  // The next n records into `records`.
  void read(size_t n, std::vector<double>& records) {
    records.resize(n * width_);
    if (std::fread(records.data(), sizeof(double), records.size(), file_) != records.size())
      throw std::runtime_error("a temporary file of compensate reads back short: " + path_);
  }

 private:
  std::string path_;
  size_t width_;
  size_t count_ = 0;
  std::FILE* file_ = nullptr;
};

// A point's record: line, rapid, status, written, tip before (um), axis before (urad), the
// target p (3, mm) and u (3), q0 and q (axes each; mm, rad).
enum Field {
  kLine,
  kRapid,
  kStatus,
  kWritten,
  kTipBefore,
  kAxisBefore,
  kP,
  kU = kP + 3,
  kQ0 = kU + 3
};

// The charts' points of a long program: of every bin of consecutive points (bins of a size
// making at most 10 000 of them), the points of largest tip and axis error before and after.
class ChartPoints {
 public:
  explicit ChartPoints(size_t points) : bin_(std::max<size_t>(1, (points + 9999) / 10000)) {}
  void add(size_t index, int line, double tb, double ta, double ab, double aa) {
    if (index / bin_ != current_) flush(), current_ = index / bin_;
    const double v[4] = {tb, ta, ab, aa};
    for (int k = 0; k < 4; ++k)
      if (!have_[k] || v[k] > best_[k].v[k]) best_[k] = {line, {tb, ta, ab, aa}}, have_[k] = true;
  }
  void finish() { flush(); }
  std::vector<int> line;
  std::vector<double> tip_before, tip_after, axis_before, axis_after;

 private:
  struct Kept {
    int line;
    double v[4];
  };
  void flush() {
    for (int k = 0; k < 4; ++k) {
      if (!have_[k]) continue;
      bool seen = false;  // the same point kept for another figure
      for (int j = 0; j < k; ++j)
        seen = seen || (have_[j] && best_[j].line == best_[k].line &&
                        std::equal(best_[j].v, best_[j].v + 4, best_[k].v));
      if (!seen) {
        line.push_back(best_[k].line);
        tip_before.push_back(best_[k].v[0]);
        tip_after.push_back(best_[k].v[1]);
        axis_before.push_back(best_[k].v[2]);
        axis_after.push_back(best_[k].v[3]);
      }
    }
    for (bool& h : have_) h = false;
  }
  size_t bin_, current_ = 0;
  Kept best_[4] = {};
  bool have_[4] = {false, false, false, false};
};

// Point i's predicted tip and tool axis (w, mm), and its joints.
Eigen::Vector3d tipOf(const PredictedPoints& p, size_t i) {
  return {p.field(PredictedPoints::kTipX)[i], p.field(PredictedPoints::kTipY)[i],
          p.field(PredictedPoints::kTipZ)[i]};
}
Eigen::Vector3d axisOf(const PredictedPoints& p, size_t i) {
  return {p.field(PredictedPoints::kAxisX)[i], p.field(PredictedPoints::kAxisY)[i],
          p.field(PredictedPoints::kAxisZ)[i]};
}
void jointsOf(const PredictedPoints& p, size_t i, JointVector& q) {
  q.resize(p.axes());
  for (int a = 0; a < p.axes(); ++a) q[a] = p.q(a)[i];
}

// compensateProgram block by block (pipeline/compensate.h): a first pass reads the program (its
// flags; G-code: the blocks that start an arc, whether it gives rotary words; on a calibrated
// machine, the set-up fitted to its evenly spaced poses, as predict does); the second predicts,
// compensates and writes each block, its points' records to a temporary file; the third reads
// the written file back, predicts it and writes the joints.
CompensationRun compensateStreamed(const CompensateInputs& in, const std::string& report_json,
                                   const Progress& progress) {
  auto told = [&progress](const char* phase) {
    return [&progress, phase](double f) {
      if (progress) progress(phase, f);
    };
  };
  CompensationRun run;
  run.machine = loadMachine(in.machine);
  Machine& machine = run.machine;
  const MachineModel& model = machine.model;
  const size_t axes = model.axes.size();
  const std::vector<ProbedPoint> probed = loadProbed(in.probed, model);
  const bool calibrated = !machine.identification.empty();
  const bool fit_setup = probed.empty() && calibrated && !in.absolute;
  ProgramBlocks blocks;
  blocks.points = in.block_points;
  // A LinuxCNC O-word construct runs its lines other than once and its points are not on their
  // lines (io/program/gcode_reader.h): a compensated program cannot be written line by line.
  auto refuseControlFlow = [](const ClProgram& program) {
    if (program.flow_line > 0)
      throw InputError(program.file, program.flow_line, 0, "control flow",
                       "subprograms, loops and jumps (from this line: O-words, M98/M97, "
                       "Sinumerik GOTO/IF/WHILE...) run lines other than once, in another "
                       "order: a compensated program cannot be written line by line; expand "
                       "them in the post (predict and verify read it)");
    // The control offsets the programmed contour itself (LinuxCNC's G41/G42): a corrected
    // contour would be offset again, and its corners drawn back where the correction moves them.
    if (program.radius_comp_line > 0)
      throw InputError(program.file, program.radius_comp_line, 0, "cutter radius compensation",
                       "the points from this line on are the tool centre the control offsets "
                       "from the programmed contour: a compensated program cannot be written "
                       "for it; post the tool centre path (compensation in the CAM system; "
                       "predict and verify read it)");
  };
  auto unreachable = [&](const ClProgram& program, const PredictionResult& r) {
    if (!r.ok())
      throw InputError(program.file, r.failures.front().line, 0, "unreachable",
                       describeUnreachable(model, r));
  };

  // First pass: the whole program's flags (a multi-axis program's 3-value GOTOs get the axis)
  // and the set-up's poses.
  const bool gcode = readsAsGcode(in.program);
  ProgramOptions read_only = in.program;
  read_only.keep_motion_text = false;
  EvenPoses even;
  PredictedPoints pts;
  ClProgram whole;
  GcodeArcStarts arcs;        // G-code: the blocks that start an arc
  bool rotary_words = false;  // G-code: any block gives a rotary axis's word
  {
    BlockPredictor first(machine);
    whole = streamProgram(read_only, model,
                          ProgramBlocks{blocks.points,
                                        [&](ClProgram& block, bool last) {
                                          refuseControlFlow(block);
                                          if (gcode) {
                                            arcs.add(block);
                                            rotary_words =
                                                rotary_words || gcodeGivesRotaryWords(block, model);
                                          }
                                          if (!fit_setup) return;
                                          first.predict(block, last, pts);
                                          for (size_t i = 0; i < pts.size(); ++i) {
                                            const size_t at = block.first_point + i;
                                            if (even.wants(at))
                                              even.add(at, pts[i].q, pts[i].deviation_w);
                                          }
                                        }},
                          told(fit_setup ? "fitting the measured set-up" : "reading"));
    if (fit_setup) {
      unreachable(whole, first.result());
      applyMeasuredSetup(machine, even.q, even.deviation_w, even.q.size());
    }
  }
  std::unique_ptr<PredictionUncertainty> pu;
  if (!probed.empty()) {
    const ProbedSetupFit fit = fitProbedSetup(machine, probed);
    run.setup_note = describeProbedSetup(in.probed, fit, probed, &run.warnings);
  } else if (calibrated) {
    run.setup_note = in.absolute
                         ? "absolute (" + inputName("absolute") +
                               "): what probing and presetting would take up is compensated too"
                         : "after the set-up a shop measures (part probed, tool preset), which the "
                           "calibration cannot see";
  }
  if (calibrated) {
    pu = std::make_unique<PredictionUncertainty>(machine);
    if (!probed.empty())
      pu->setupModuloProbed(probed);
    else if (!in.absolute)
      pu->setupModulo(even.q);
  }
  for (const std::string& w : setupWarnings(model)) run.warnings.push_back(w);
  bool no_errors = false;
  const std::string errors = machineErrorsStatement(machine, &no_errors);
  if (no_errors) run.warnings.push_back(errors + "; the program is written as it came");
  const bool axes_given = gcode ? rotary_words : whole.multiax;
  run.orientation = axes_given && turnsToolAxis(model);

  // The report directory is taken before anything is written: one that cannot be written leaves
  // nothing written.
  std::unique_ptr<ReportDirectory> report_dir;
  if (!in.report_dir.empty()) report_dir = std::make_unique<ReportDirectory>(in.report_dir);

  // Second pass: predicted, compensated, written; the records spooled.
  OutputSet outputs;
  TextOut& cl_out = outputs.open(in.output);
  PointSpool spool(in.output + ".points.tmp-tolver", kQ0 + 2 * axes);
  const SourceEncoding encoding(in.program.nc.empty() ? in.program.cl : in.program.nc);
  CompensatedAptWriter writer(whole.multiax);
  CompensatedGcodeWriter gcode_writer(model, whole.units, arcs);
  std::vector<JointVector> q;
  std::vector<Eigen::Vector3d> corrected_p;
  size_t cycle_points = 0;  // in a swivelled plane (CYCLE800)
  BlockPredictor predictor(machine);
  CompensationOptions co;
  co.max_condition = in.max_condition;
  StreamCompensator compensator(model, machine.params, co);
  std::vector<JointVector> q0;
  std::vector<ClPoint> corrected;
  std::vector<char> written;
  std::vector<double> records;
  std::string text;
  bool started = false, failed = false;
  blocks.sink = [&](ClProgram& block, bool last) {
    text.clear();
    if (!started) {
      if (encoding.bom) cl_out += "\xEF\xBB\xBF";
      const std::vector<std::string> header = compensatedHeader(in, block, model.name);
      if (gcode)
        gcode_writer.start(block, header, text);
      else
        writer.start(header, text);
      started = true;
    }
    predictor.predict(block, last, pts);
    const size_t n = block.path.size();
    // A point the machine cannot reach (its numbers NaN; in the block's tail it reaches the
    // result with the next block): nothing more is made, the error at the end names the points.
    failed = failed || !predictor.result().ok();
    for (size_t i = 0; i < n && !failed; ++i)
      failed = !std::isfinite(pts.field(PredictedPoints::kTipX)[i]);
    if (failed) return;
    q0.resize(n);
    for (size_t i = 0; i < n; ++i) jointsOf(pts, i, q0[i]);
    const std::vector<char>* tip_only =
        block.cycle_orientation.empty() ? nullptr : &block.cycle_orientation;
    cycle_points += std::count(block.cycle_orientation.begin(), block.cycle_orientation.end(), 1);
    const CompensationResult c =
        compensator.compensate(block.path, q0, run.orientation, &pts, tip_only);
    if (gcode) {
      q.resize(n);
      corrected_p.resize(n);
      for (size_t i = 0; i < n; ++i) {
        q[i] = c.points[i].q;
        corrected_p[i] = c.points[i].nominal_p_w;
      }
      gcode_writer.lines(block, block.joints, q, corrected_p, text, written, nullptr);
    } else {
      corrected = block.path;
      for (size_t i = 0; i < n; ++i) {
        corrected[i].p_w = c.points[i].nominal_p_w;
        corrected[i].u_w = c.points[i].nominal_u_w;
      }
      writer.statements(block, corrected, text, written);
    }
    encoding.apply(text);
    cl_out += text;
    const size_t w = spool.width();
    records.assign(n * w, 0.0);
    for (size_t i = 0; i < n; ++i) {
      double* r = &records[i * w];
      const ClPoint& c_i = block.path[i];
      const CompensatedPoint& cp = c.points[i];
      r[kLine] = c_i.line;
      r[kRapid] = c_i.rapid;
      r[kStatus] = static_cast<double>(static_cast<int>(cp.status));
      r[kWritten] = written[i];
      r[kTipBefore] = mmToUm((tipOf(pts, i) - c_i.p_w).norm());
      r[kAxisBefore] = radToUrad(angle(axisOf(pts, i), c_i.u_w.normalized()));
      for (int k = 0; k < 3; ++k) r[kP + k] = c_i.p_w[k], r[kU + k] = c_i.u_w[k];
      for (size_t a = 0; a < axes; ++a)
        r[kQ0 + a] = cp.q0[static_cast<Eigen::Index>(a)],
                r[kQ0 + axes + a] = cp.q[static_cast<Eigen::Index>(a)];
    }
    spool.write(records);
  };
  ProgramOptions with_text = in.program;
  with_text.keep_motion_text = true;  // the in-place writer edits the GOTO statements
  run.program = streamProgram(with_text, model, blocks, told("compensating"));
  unreachable(run.program, predictor.takeResult());
  if (failed)  // a point without numbers that the prediction does not name: never written short
    throw std::runtime_error("a point of the program has no prediction and no failure");
  run.text.notes = gcode ? gcode_writer.notes() : writer.notes();
  if (axes_given && !run.orientation) run.text.notes.push_back(tipOnlyNote(model));
  const std::string written_file = outputs.close(in.output);

  // Third pass: the written file read back and predicted, against the records.
  spool.rewind();
  const std::string joints_path = compensatedJointsPath(report_json);
  JointsWriter joints(model, outputs.open(joints_path));
  const size_t total = spool.count();
  CompensationTally tally(model);
  ChartPoints chart(total);
  BlockPredictor after(machine);
  std::unique_ptr<tbb::enumerable_thread_specific<PredictionUncertainty>> per_thread;
  if (pu)
    per_thread = std::make_unique<tbb::enumerable_thread_specific<PredictionUncertainty>>(*pu);
  std::vector<double> band_tip, band_axis;
  size_t index = 0;
  ProgramOptions back = read_only;
  (gcode ? back.nc : back.cl) = in.output;
  (gcode ? back.cl : back.nc).clear();
  blocks.sink = [&](ClProgram& block, bool last) {
    after.predict(block, last, pts);
    if (!after.result().ok())
      throw std::runtime_error("the compensated program does not predict: " +
                               after.result().failures.front().message);
    const size_t n = block.path.size();
    if (index + n > total)
      throw std::runtime_error("the compensated program reads back with more than its " +
                               std::to_string(total) + " points");
    spool.read(n, records);
    if (pu) {
      band_tip.resize(n);
      band_axis.resize(n);
      tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 256),
                        [&](const tbb::blocked_range<size_t>& range) {
                          const PredictionUncertainty& u = per_thread->local();
                          JointVector q;
                          for (size_t i = range.begin(); i < range.end(); ++i) {
                            jointsOf(pts, i, q);
                            const PoseUncertainty b = u.at(q);
                            band_tip[i] = mmToUm(PredictionUncertainty::tipRadius95(b));
                            band_axis[i] = radToUrad(PredictionUncertainty::axisRadius95(b));
                          }
                        });
    }
    const size_t w = spool.width();
    for (size_t i = 0; i < n; ++i) {
      const double* r = &records[i * w];
      const Eigen::Vector3d p_t(r[kP], r[kP + 1], r[kP + 2]);
      const Eigen::Vector3d u_t = Eigen::Vector3d(r[kU], r[kU + 1], r[kU + 2]).normalized();
      TalliedPoint p;
      p.line = static_cast<int>(r[kLine]);
      p.rapid = r[kRapid] != 0;
      p.written = r[kWritten] != 0;
      p.status = static_cast<CompensationStatus>(static_cast<int>(r[kStatus]));
      p.tip_before_um = r[kTipBefore];
      p.axis_before_urad = r[kAxisBefore];
      p.tip_after_um = mmToUm((tipOf(pts, i) - p_t).norm());
      p.axis_after_urad =
          run.orientation ? radToUrad(angle(axisOf(pts, i), u_t)) : p.axis_before_urad;
      p.q0 = r + kQ0;
      p.q = r + kQ0 + axes;
      tally.add(p);
      if (pu) tally.addBand(band_tip[i], band_axis[i]);
      chart.add(index + i, p.line, p.tip_before_um, p.tip_after_um, p.axis_before_urad,
                p.axis_after_urad);
      joints.add(index + i, p.line, p.written, p.status, p.q0, p.q, p.tip_after_um,
                 p.axis_after_urad);
    }
    index += n;
  };
  streamProgram(back, model, blocks, told("reading back"), written_file);
  if (index != total)
    throw std::runtime_error("the compensated program reads back with " + std::to_string(index) +
                             " points instead of " + std::to_string(total));
  chart.finish();

  CompensationReport& rep = run.report;
  rep.machine = in.machine.machine;
  rep.program = run.program.file;
  rep.dialect = run.program.dialect;
  rep.output = in.output;
  tally.finish(rep);
  run.worse_lines = tally.worse_lines;
  run.worse_max_um = tally.worse_max_um;
  if (pu) bandSources(machine, rep);
  rep.setup_note = run.setup_note;
  rep.notes = run.text.notes;
  if (cycle_points > 0) rep.notes.push_back(cycleNote(cycle_points));
  rep.joints_file = joints_path;
  outputs.add(report_json, formatCompensationJson(rep));
  if (report_dir) {
    CompensationReport html = rep;
    html.joints_file.clear();
    writeCompensationReport(report_dir->staging(), html, chart.line, chart.tip_before,
                            chart.tip_after, chart.axis_before, chart.axis_after);
  }
  outputs.commit();
  if (report_dir) report_dir->commit();
  return run;
}

}  // namespace

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
  if (streamsCompensation(in)) {
    run.compensation = compensateStreamed(in, run.report, progress);
  } else {
    run.compensation = runCompensation(in, in.output, progress);
    if (progress) progress("writing and reading back", 1.0);
    writeCompensation(*run.compensation, in.output, run.report, in.report_dir);
  }
  // The read-back check: a point further off after than before means the written program moves
  // where the original did not.
  run.worse_lines = run.compensation->worse_lines;
  run.worse_max_um = run.compensation->worse_max_um;
  if (!run.worse_lines.empty()) run.verdict = Verdict::NotMet;
  return run;
}

}  // namespace tolver
