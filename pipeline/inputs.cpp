#include "pipeline/inputs.h"

#include <unistd.h>

#include <cstdio>
#include <filesystem>

#include "core/numerics/quantities.h"
#include "core/numerics/units.h"
#include "core/path/tool_path_prediction.h"
#include "io/common/io_error.h"
#include "io/common/line_source.h"
#include "io/common/text_util.h"
#include "io/machine/machine_file.h"
#include "io/program/gcode_reader.h"
#include "io/program/probe_file.h"
#include "io/program/setup_file.h"
#include "io/program/tool_table.h"
#include "pipeline/parallel_prediction.h"

namespace tolver {

Machine loadMachine(const MachineOptions& o) {
  Machine machine = readMachineFile(o.machine);
  PartSetup setup;
  if (!o.setup.empty()) setup = readSetupFile(o.setup);
  if (!o.part_zero.empty()) {
    if (o.part_zero.size() != 3) throw FieldError("part_zero", "expected x,y,z in mm");
    for (double v : o.part_zero)
      if (const std::string problem = outOfRange(Quantity::Position, v); !problem.empty())
        throw FieldError("part_zero", problem);
    setup.part_zero_table = Eigen::Vector3d(o.part_zero[0], o.part_zero[1], o.part_zero[2]);
  }
  if (!o.part_zero.empty()) setup.part_zero_given = true;
  if (!std::isnan(o.part_rotation_deg)) {
    if (const std::string problem = outOfRange(Quantity::PartRotation, o.part_rotation_deg);
        !problem.empty())
      throw FieldError("part_rotation_deg", problem);
    setup.part_rotation = degToRad(o.part_rotation_deg);
    setup.part_rotation_given = true;
  }
  if (!std::isnan(o.gauge_length)) {
    if (const std::string problem = outOfRange(Quantity::Length, o.gauge_length); !problem.empty())
      throw FieldError("gauge_length", problem);
    setup.gauge_length = o.gauge_length;
    setup.gauge_length_given = true;
  }
  machine.model.setup = setup;
  return machine;
}

std::vector<std::string> setupWarnings(const MachineModel& model) {
  std::vector<std::string> w;
  const PartSetup& s = model.setup;
  std::string missing;
  if (!s.part_zero_given) missing += "part zero (0, 0, 0) in the table frame";
  if (!s.part_rotation_given)
    missing += std::string(missing.empty() ? "" : ", ") + "part rotation 0 deg";
  if (!s.gauge_length_given)
    missing += std::string(missing.empty() ? "" : ", ") +
               "gauge length 0 mm (the tool tip at the spindle gauge point)";
  if (!missing.empty())
    w.push_back("no set-up given for " + missing + ": the defaults were used (" +
                inputName("setup") + ", " + inputName("part_zero") + ", " +
                inputName("part_rotation_deg") + ", " + inputName("gauge_length") + ")");
  return w;
}

std::string machineErrorsStatement(const Machine& machine, bool* none) {
  bool any = false;
  for (int i = 0; i < machine.params.size(); ++i) any = any || machine.params[i] != 0.0;
  *none = !any;
  if (!any)
    return "the machine file carries no errors (" +
           std::string(machine.model.errors_source.empty()
                           ? "nominal geometry"
                           : "errors: " + machine.model.errors_source) +
           "): the machine's share is zero by construction; give a measured or identified "
           "machine file (tolver calibrate) to predict the machine's errors";
  return "errors: " + (machine.model.errors_source.empty() ? std::string("given, source not stated")
                                                           : machine.model.errors_source);
}

namespace {

// The line range of --lines ("first-last").
struct LineRange {
  int first = 0, last = 0;
};
LineRange lineRange(const std::string& spec) {
  const size_t dash = spec.find('-', 1);
  const auto a = dash == std::string::npos ? std::nullopt : parseNumber(spec.substr(0, dash));
  const auto b = dash == std::string::npos ? std::nullopt : parseNumber(spec.substr(dash + 1));
  if (!a || !b || *a < 1 || *b < *a || *a != std::floor(*a) || *b != std::floor(*b) || *b > 2e9)
    throw FieldError("lines", "expected 'first-last', e.g. 11-578");
  return {static_cast<int>(*a), static_cast<int>(*b)};
}

// Keeps the points of source lines r.first..r.last (and their parallel per-point data); returns
// how many.
size_t keepLines(ClProgram& p, const LineRange& r) {
  size_t k = 0;
  std::vector<int> kept_index(p.path.size(), -1);  // old point -> new point
  for (size_t i = 0; i < p.path.size(); ++i) {
    if (p.path[i].line < r.first || p.path[i].line > r.last) continue;
    kept_index[i] = static_cast<int>(k);
    p.path[k] = p.path[i];
    if (i < p.point_frame.size()) p.point_frame[k] = p.point_frame[i];
    if (i < p.joints.size()) p.joints[k] = p.joints[i];
    if (i < p.tcp.size()) p.tcp[k] = p.tcp[i];
    if (i < p.fixed_axes.size()) p.fixed_axes[k] = p.fixed_axes[i];
    if (i < p.cycle_orientation.size()) p.cycle_orientation[k] = p.cycle_orientation[i];
    ++k;
  }
  // The statements own the kept points only (writers index the path through them).
  for (AptStatement& st : p.statements) {
    int first = -1, count = 0;
    for (int i = st.first_point; st.point_count > 0 && i < st.first_point + st.point_count; ++i)
      if (kept_index[i] >= 0) {
        if (first < 0) first = kept_index[i];
        ++count;
      }
    st.first_point = first;
    st.point_count = count;
  }
  p.path.resize(k);
  if (p.point_frame.size() > k) p.point_frame.resize(k);
  if (p.joints.size() > k) p.joints.resize(k);
  if (p.tcp.size() > k) p.tcp.resize(k);
  if (p.fixed_axes.size() > k) p.fixed_axes.resize(k);
  if (p.cycle_orientation.size() > k) p.cycle_orientation.resize(k);
  return k;
}

bool hasGcodeExtension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext == ".nc" || ext == ".ngc" || ext == ".tap" || ext == ".gcode" || ext == ".mpf" ||
         ext == ".cnc" || ext == ".iso" || ext == ".eia";
}

}  // namespace

namespace {

// Reads the program whole, or in blocks (blocks given): the line range kept block by block.
ClProgram readProgram(LineSource& source, const std::string& path, bool gcode,
                      const ProgramOptions& o, const MachineModel& model,
                      const ProgramBlocks* blocks = nullptr) {
  const std::optional<LineRange> range =
      o.lines.empty() ? std::nullopt : std::optional<LineRange>(lineRange(o.lines));
  size_t kept = 0;
  ProgramBlocks ranged;
  if (blocks) {
    ranged.points = blocks->points;
    ranged.sink = [&](ClProgram& p, bool last) {
      if (range) {
        // The block's points renumbered from the kept ones before it.
        const size_t before = kept;
        kept += keepLines(p, *range);
        p.first_point = before;
      }
      blocks->sink(p, last);
    };
  }
  ClProgram program;
  if (gcode) {
    GcodeReadOptions go;
    go.chordal_tolerance_mm = o.chordal_tolerance;
    if (o.units == "inch") go.unit_mm = 25.4;
    if (o.units == "mm") go.unit_mm = 1.0;
    go.cutter_comp_wear = o.cutter_comp == "wear";
    if (!o.tool_table.empty()) {
      // Only a LinuxCNC control's G41/G42 are carried out (io/program/gcode_reader.h): on another
      // the table would be read and nothing done with it.
      if (model.control.dialect != "linuxcnc")
        throw FieldError("tool_table",
                         "LinuxCNC's tool table, for its cutter radius compensation, on a "
                         "machine whose control is not dialect=\"linuxcnc\" (there G41/G42 "
                         "are refused, or read with " +
                             inputName("cutter_comp") + " wear)");
      go.tool_diameter_mm = readLinuxCncToolTable(o.tool_table, model.control.default_unit_mm);
    }
    program =
        blocks ? readGcode(source, path, model, go, ranged) : readGcode(source, path, model, go);
  } else {
    AptReadOptions ro;
    ro.chordal_tolerance_mm = o.chordal_tolerance;
    ro.keep_motion_text = o.keep_motion_text;
    ro.absolute_msys = o.absolute_msys;
    if (o.units == "inch") ro.unit_mm = 25.4;
    ro.unit_given = !o.units.empty();
    program = blocks ? readApt(source, path, ro, ranged) : readApt(source, path, ro);
    if (program.pointsRead() == 0)
      throw InputError(path, 0, 0, "GOTO", "the program has no tool positions");
  }
  if (range && !blocks) kept = keepLines(program, *range);
  if (range && kept == 0)
    throw FieldError("lines", program.file + " has no tool position on lines " + o.lines);
  return program;
}

}  // namespace

// The dialect from the option, the extension, or the first statements (looksLikeGcode reads
// twenty non-blank lines; 64 kB hold them in any real program).
bool readsAsGcode(const ProgramOptions& o) {
  if (o.cl.empty() == o.nc.empty())
    throw FieldError("cl", "give the program with " + inputName("cl") + " (CL data) or " +
                               inputName("nc") + " (G-code), one of them");
  const std::string& path = o.nc.empty() ? o.cl : o.nc;
  const std::string prefix = readFilePrefix(path, 65536);
  refuseUnreadLanguage(prefix, path);
  return !o.nc.empty() || hasGcodeExtension(path) || looksLikeGcode(prefix);
}

ClProgram loadProgram(const ProgramOptions& o, const MachineModel& model) {
  const bool gcode = readsAsGcode(o);
  const std::string& path = o.nc.empty() ? o.cl : o.nc;
  LineSource source = LineSource::file(path);
  return readProgram(source, path, gcode, o, model);
}

ClProgram streamProgram(const ProgramOptions& o, const MachineModel& model,
                        const ProgramBlocks& blocks,
                        const std::function<void(double)>& fraction_read,
                        const std::string& read_from) {
  const std::string& path = o.nc.empty() ? o.cl : o.nc;
  // As parseProgram chooses, for a text read back.
  const bool gcode = read_from.empty() ? readsAsGcode(o)
                                       : !o.nc.empty() || hasGcodeExtension(path) ||
                                             looksLikeGcode(readFilePrefix(read_from, 65536));
  LineSource source = LineSource::file(read_from.empty() ? path : read_from);
  ProgramBlocks told = blocks;
  if (fraction_read && source.sizeHint() > 0)
    told.sink = [&](ClProgram& p, bool last) {
      blocks.sink(p, last);
      fraction_read(std::min(
          1.0, static_cast<double>(source.bytesRead()) / static_cast<double>(source.sizeHint())));
    };
  return readProgram(source, path, gcode, o, model, &told);
}

ClProgram parseProgram(const std::string& text, const std::string& path, const ProgramOptions& o,
                       const MachineModel& model) {
  refuseUnreadLanguage(text, path);
  const bool gcode = !o.nc.empty() || hasGcodeExtension(path) || looksLikeGcode(text);
  LineSource source(text);
  return readProgram(source, path, gcode, o, model);
}

std::vector<std::string> unitWarnings(const ClProgram& program, const MachineModel& model,
                                      const std::string& units_option) {
  if (program.path.empty()) return {};
  Eigen::Vector3d lo = program.path[0].p_w, hi = lo;
  for (const ClPoint& c : program.path) {
    lo = lo.cwiseMin(c.p_w);
    hi = hi.cwiseMax(c.p_w);
  }
  return unitWarnings(program, model, units_option, lo, hi);
}

std::vector<std::string> unitWarnings(const ClProgram& program, const MachineModel& model,
                                      const std::string& units_option, const Eigen::Vector3d& lo,
                                      const Eigen::Vector3d& hi) {
  std::vector<std::string> w;
  if (program.pointsRead() == 0 || program.dialect == "G-code")
    return w;  // the G-code reader says which default it used; the control obeys G20/G21
  const double extent = (hi - lo).norm();
  double travel = 0.0;
  for (const Axis& a : model.axes)
    if (!a.isRotary()) travel += (a.travel_max - a.travel_min) * (a.travel_max - a.travel_min);
  travel = std::sqrt(travel);
  char buf[400];
  if (!program.units_in_file.empty()) {
    std::snprintf(
        buf, sizeof buf, "%s declares UNITS/%s at line %d: read in %s, as %s says (extent %.1f mm)",
        program.file.c_str(), program.units_in_file == "INCH" ? "INCHES" : "MM", program.units_line,
        program.units == "INCH" ? "inches" : "mm", inputName("units").c_str(), extent);
    w.push_back(buf);
    return w;
  }
  // A CAM that labels millimetres as inches (Creo's UNITS / INCHES over a 6 mm cutter at
  // 7958 rpm: 4r19415/5-axis-Rotation-tool-center-point-RTCP-, assets/finition.ncl) gives a
  // program 25.4 times too large: say so when the machine could not hold it and could in mm.
  if (program.units_declared && units_option.empty() && program.units == "INCH" &&
      extent > travel && extent / 25.4 < travel) {
    std::snprintf(buf, sizeof buf,
                  "%s declares UNITS/INCHES at line %d and spans %.0f mm, more than this "
                  "machine's travel (%.0f mm across); read as mm it would span %.1f mm: if the "
                  "CAM wrote millimetres under an inch label, give %s mm",
                  program.file.c_str(), program.units_line, extent, travel, extent / 25.4,
                  inputName("units").c_str());
    w.push_back(buf);
  }
  if (program.units_declared || !units_option.empty()) return w;
  double tool_d = 0.0;
  if (!program.cutters.empty() && !program.cutters.back().values.empty())
    tool_d = program.cutters.back().values[0];
  const bool inch_fits = extent * 25.4 < travel;
  const bool small_tool = tool_d > 0.0 && tool_d < 1.0;
  const bool small_part = extent < 30.0;
  if (inch_fits && (small_tool || (small_part && tool_d < 3.0))) {
    std::snprintf(buf, sizeof buf,
                  "%s declares no units and looks like inches (extent %.3f, tool diameter %.3f, "
                  "read as mm): use %s inch if it is",
                  program.file.c_str(), extent, tool_d, inputName("units").c_str());
    w.push_back(buf);
  } else {
    std::snprintf(
        buf, sizeof buf, "%s declares no units: read as %s (extent %.1f mm%s)",
        program.file.c_str(), program.units == "INCH" ? "inches" : "mm", extent,
        inch_fits ? ("; " + inputName("units") + " inch if it is in inches").c_str() : "");
    w.push_back(buf);
  }
  return w;
}

std::string describeUnreachable(const MachineModel& model, const PredictionResult& r) {
  const PredictionFailure& f = r.failures.front();
  std::string msg = f.message;
  if (r.failed_points > 1) {
    std::string per_axis;
    for (size_t a = 0; a < r.failures_per_axis.size(); ++a) {
      if (r.failures_per_axis[a] == 0) continue;
      per_axis += (per_axis.empty() ? "" : ", ") +
                  (a < model.axes.size() ? model.axes[a].name : std::string("orientation")) + " " +
                  std::to_string(r.failures_per_axis[a]);
    }
    msg += "; " + std::to_string(r.failed_points) +
           " points fail (first axis to break: " + per_axis +
           "): run 'tolver setup' to find a set-up that reaches the whole program";
  }
  return msg;
}

PredictionResult predictProgram(const Machine& machine, const ClProgram& program) {
  PredictionResult r = predictToolPathParallel(machine.model, machine.params, program.path, 20,
                                               program.joints.empty() ? nullptr : &program.joints);
  if (!r.ok())
    throw InputError(program.file, r.failures.front().line, 0, "unreachable",
                     describeUnreachable(machine.model, r));
  return r;
}

std::vector<std::string> programNotes(const ClProgram& program) {
  ProgramNotes notes;
  notes.add(program);
  return notes.notes(program);
}

void ProgramNotes::add(const ClProgram& block) {
  if (!frame_note_.empty()) return;
  for (const AptStatement& st : block.statements)
    if (st.major == "MSYS" || st.major == "CSYS" || st.major == "$$*CATIA0") pending_.push_back(st);
  // A coordinate system statement moves the points out of the file's own frame: say where. The
  // frame in force at the first point after the statement (a CSYS that names only a tool plane
  // leaves it at the identity).
  size_t k = 0, resolved = 0;
  for (const AptStatement& st : pending_) {
    while (k < block.path.size() && block.path[k].line <= st.first_line) ++k;
    if (k == block.path.size() || k >= block.point_frame.size()) break;  // in a later block
    ++resolved;
    const ClFrame& f = block.frames[block.point_frame[k]];
    if (f.T.isApprox(Eigen::Isometry3d::Identity())) continue;
    const Eigen::Vector3d o = f.scale * f.T.translation();
    char buf[300];
    std::snprintf(buf, sizeof buf,
                  "%s at line %d applied: the points after it are moved into the part frame "
                  "(that system's origin is at (%.3f, %.3f, %.3f) mm in it)",
                  st.major.c_str(), st.first_line, o.x(), o.y(), o.z());
    frame_note_ = buf;
    pending_.clear();
    return;
  }
  pending_.erase(pending_.begin(), pending_.begin() + static_cast<std::ptrdiff_t>(resolved));
}

std::vector<std::string> ProgramNotes::notes(const ClProgram& program) const {
  std::vector<std::string> w = program.notes;
  if (!frame_note_.empty()) w.push_back(frame_note_);
  if (program.cycle_holes > 0)
    w.push_back(std::to_string(program.cycles) + " drilling cycle(s) expanded at " +
                std::to_string(program.cycle_holes) + " holes (in, out along the tool axis)");
  if (program.unknown_count > 0) {
    std::string names;
    for (const auto& n : program.unknown_names) names += (names.empty() ? "" : ", ") + n;
    w.push_back("skipped " + std::to_string(program.unknown_count) + " unknown statements (" +
                names + ")");
  }
  return w;
}

void EvenPoses::add(size_t index, const JointVector& q_i, const Eigen::Vector3d& d) {
  if (!wants(index)) return;
  q.push_back(q_i);
  deviation_w.push_back(d);
  index_.push_back(index);
  if (q.size() <= 2 * kFew) return;
  step_ *= 2;
  size_t k = 0;
  for (size_t i = 0; i < q.size(); ++i) {
    if (index_[i] % step_ != 0) continue;
    q[k] = q[i];
    deviation_w[k] = deviation_w[i];
    index_[k] = index_[i];
    ++k;
  }
  q.resize(k);
  deviation_w.resize(k);
  index_.resize(k);
}

void checkOutputDir(const std::string& path, const char* field) {
  const auto dir = std::filesystem::path(path).parent_path();
  if (!dir.empty() && !std::filesystem::is_directory(dir))
    throw FieldError(field, path + ": directory " + dir.string() + " does not exist");
}

CalibratedPrediction applyCalibration(Machine& machine, const ClProgram& program,
                                      PredictionResult& pred, bool absolute,
                                      const std::vector<ProbedPoint>& probed) {
  CalibratedPrediction out;
  const std::vector<JointVector>* commanded = program.joints.empty() ? nullptr : &program.joints;
  if (!probed.empty()) {
    out.probed = true;
    out.probe = fitProbedSetup(machine, probed);
    pred = PredictionResult{};  // one path's points in memory at a time
    pred = predictToolPathParallel(machine.model, machine.params, program.path, 20, commanded);
    if (machine.identification.empty()) return out;
    PredictionUncertainty pu(machine);
    pu.setupModuloProbed(probed);
    out.uncertainty.reserve(pred.points.size());
    for (const PredictedPoint& p : pred.points) out.uncertainty.push_back(pu.at(p.q));
    return out;
  }
  if (machine.identification.empty()) return out;
  // The set-up is fitted, and taken modulo, over evenly spaced poses (EvenPoses).
  EvenPoses even;
  for (size_t i = 0; i < pred.points.size(); ++i)
    if (even.wants(i)) even.add(i, pred.points[i].q, pred.points[i].deviation_w);
  const std::vector<JointVector>& sub = even.q;
  if (!absolute) {
    out.measured_setup = applyMeasuredSetup(machine, sub, even.deviation_w, sub.size());
    pred = PredictionResult{};  // one path's points in memory at a time
    pred = predictToolPathParallel(machine.model, machine.params, program.path, 20, commanded);
  }
  PredictionUncertainty pu(machine);
  if (!absolute) pu.setupModulo(sub);
  out.uncertainty.reserve(pred.points.size());
  for (const PredictedPoint& p : pred.points) out.uncertainty.push_back(pu.at(p.q));
  return out;
}

std::vector<ProbedPoint> loadProbed(const std::string& path, const MachineModel& model) {
  if (path.empty()) return {};
  return readProbeFile(path, model);
}

std::string describeProbedSetup(const std::string& path, const ProbedSetupFit& fit,
                                const std::vector<ProbedPoint>& points,
                                std::vector<std::string>* warnings) {
  size_t worst = 0, worst_tram = 0;
  for (size_t i = 0; i < fit.residual.size(); ++i) {
    size_t& w = points[i].tram ? worst_tram : worst;
    if (points[w].tram != points[i].tram || fit.residual[i] > fit.residual[w]) w = i;
  }
  char buf[640];
  std::snprintf(buf, sizeof buf,
                "part set-up fitted to %zu probed points (%s), %d of %d set-up values observed: "
                "part moved (%+.2f, %+.2f, %+.2f) um, rotated (%+.1f, %+.1f, %+.1f) urad, spindle "
                "offset (%+.2f, %+.2f, %+.2f) um; the points disagree with the file's set-up by "
                "%.2f um RMS before, %.2f um after (max %.2f um, line %d); the cutter's length "
                "relative to the probe is taken as preset",
                points.size() - fit.trams, path.c_str(), fit.observed, fit.columns,
                mmToUm(fit.change[0]), mmToUm(fit.change[1]), mmToUm(fit.change[2]),
                radToUrad(fit.change[3]), radToUrad(fit.change[4]), radToUrad(fit.change[5]),
                mmToUm(fit.spindle_change[0]), mmToUm(fit.spindle_change[1]),
                mmToUm(fit.spindle_change[2]), mmToUm(fit.rms_before), mmToUm(fit.rms),
                mmToUm(fit.max), points[worst].line);
  // Touches no rigid set-up explains to a millimetre belong to another part or set-up: refused
  // before anything is predicted or written (a fit on them moves the part by metres).
  if (fit.max > 1.0)
    throw InputError(path, points[worst].line, 0, "probed",
                     "the best set-up leaves this touch " + formatWith("%.3f", fit.max) +
                         " mm from its point: these touches do not belong to this part and set-up "
                         "(check the set-up file, the part frame and units)");
  std::string line = buf;
  if (fit.trams > 0) {
    std::snprintf(buf, sizeof buf,
                  "; spindle tilted (%+.1f, %+.1f) urad about x and y by %d tram%s, which disagree "
                  "with the file's spindle by %.1f urad before, %.1f urad after (line %d)",
                  radToUrad(fit.spindle_tilt_change[0]), radToUrad(fit.spindle_tilt_change[1]),
                  fit.trams, fit.trams > 1 ? "s" : "", radToUrad(fit.tram_before),
                  radToUrad(fit.tram_max), points[worst_tram].line);
    line += buf;
  } else {
    line +=
        "; no tram: the tool axis against the part keeps the machine file's spindle tilt, which "
        "a ball-bar cannot see (add a tram row)";
  }
  if (warnings) {
    if (!fit.unobserved.empty()) {
      std::string names;
      for (const std::string& n : fit.unobserved) names += (names.empty() ? "" : ", ") + n;
      warnings->push_back(path + ": the probed points do not determine the part's " + names +
                          "; the set-up file's value is kept for it (probe along more directions)");
    }
    if (fit.tram_max > uradToRad(20)) {
      std::snprintf(buf, sizeof buf,
                    "%s:%d: the fitted spindle tilt leaves %.1f urad at this tram: check its joint "
                    "values and signs (x and y of the tool axis in the table frame, urad)",
                    path.c_str(), points[worst_tram].line, radToUrad(fit.tram_max));
      warnings->push_back(buf);
    }
    // Touches a rigid set-up cannot explain: a wrong row, a wrong frame or a units slip.
    if (fit.max > 0.02) {
      std::snprintf(buf, sizeof buf,
                    "%s:%d: the fitted set-up leaves %.1f um at this point (RMS %.1f um): check "
                    "its part point, joint values, frame and units",
                    path.c_str(), points[worst].line, mmToUm(fit.max), mmToUm(fit.rms));
      warnings->push_back(buf);
    }
  }
  return line;
}

void makeReportDir(const std::string& dir, const char* field) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec || !std::filesystem::is_directory(dir, ec))
    throw FieldError(
        field, dir + ": cannot create the directory" + (ec ? ": " + ec.message() : std::string()));
}

std::string replaceExtension(const std::string& path, const std::string& ext) {
  std::filesystem::path p(path);
  const std::filesystem::path original = p;
  p.replace_extension(ext);
  if (p == original) p += ".out" + ext;
  return p.string();
}

}  // namespace tolver
