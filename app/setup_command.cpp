// tolver setup: the program's extent and joint ranges against the machine's travel, and a part
// zero, rotation and gauge length that keep the whole program inside travel (core/setup_search).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

#include "app/commands.h"
#include "app/common.h"
#include "core/numerics/units.h"
#include "core/path/setup_search.h"
#include "io/common/io_error.h"
#include "io/common/text_util.h"

namespace tolver::app {
namespace {

struct SetupOptions {
  MachineOptions machine;
  ProgramOptions program;
  std::string output;
  double rotation_step_deg = 15.0;
  std::vector<double> gauge_lengths;
};

std::string axisValue(const Axis& a, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.3f", a.isRotary() ? radToDeg(v) : v);
  return buf;
}

void printRanges(const MachineModel& model, const ClProgram& program,
                 const std::vector<AxisRange>& ranges) {
  std::printf("  %-5s %-26s %-24s %s\n", "axis", "the program needs", "travel", "margin");
  for (size_t a = 0; a < model.axes.size(); ++a) {
    const Axis& ax = model.axes[a];
    const AxisRange& r = ranges[a];
    const char* unit = ax.isRotary() ? "deg" : "mm";
    if (!r.known) {
      std::printf("  %-5s (no point solved)\n", ax.name.c_str());
      continue;
    }
    const std::string needs = axisValue(ax, r.min) + " .. " + axisValue(ax, r.max) + " " + unit;
    const std::string travel =
        ax.endless ? std::string("endless")
                   : "[" + axisValue(ax, ax.travel_min) + ", " + axisValue(ax, ax.travel_max) + "]";
    std::string margin;
    if (ax.endless) {
      margin = "-";
    } else if (r.min < ax.travel_min - 1e-9) {
      margin = axisValue(ax, ax.travel_min - r.min) + " " + unit + " over at line " +
               std::to_string(program.path[r.min_index].line);
    } else if (r.max > ax.travel_max + 1e-9) {
      margin = axisValue(ax, r.max - ax.travel_max) + " " + unit + " over at line " +
               std::to_string(program.path[r.max_index].line);
    } else {
      margin = axisValue(ax, std::min(r.min - ax.travel_min, ax.travel_max - r.max)) + " " + unit;
    }
    std::printf("  %-5s %-26s %-24s %s\n", ax.name.c_str(), needs.c_str(), travel.c_str(),
                margin.c_str());
  }
}

// The set-up file for a proposal: what `--setup` reads.
// The set-up file's text for a proposed set-up (the format setup_file.h reads).
std::string setupFileText(const ClProgram& program, const MachineModel& model, const PartSetup& b, double margin,
                          const std::string& what) {
  char buf[768];
  std::snprintf(
      buf, sizeof buf,
      "# Set-up proposed by tolver setup for %s%s on %s (margin %.3f mm)\n"
      "part_zero_mm = %s, %s, %s\npart_rotation_deg = %s\ngauge_length_mm = %s\n",
      program.file.c_str(), what.c_str(), model.name.c_str(), margin,
      formatNumber(b.part_zero_table.x()).c_str(), formatNumber(b.part_zero_table.y()).c_str(),
      formatNumber(b.part_zero_table.z()).c_str(), formatNumber(radToDeg(b.part_rotation)).c_str(),
      formatNumber(b.gauge_length).c_str());
  std::string text = buf;
  // The proposal moves the part frame: the work offsets of a posted program go with it (a
  // work offset the set-up does not give has its origin at the part zero: touch off there).
  if (program.dialect == "G-code")
    text += "# work offsets: not given, so G54... are at the part zero above (touch off there)\n";
  else
    for (const auto& [name, off] : model.setup.work_offsets)
      text += toLower(name) + "_mm = " + formatNumber(off.x()) + ", " + formatNumber(off.y()) +
              ", " + formatNumber(off.z()) + "\n";
  for (const auto& [h, len] : model.setup.tool_lengths)
    text += "tool_h" + std::to_string(h) + "_mm = " + formatNumber(len) + "\n";
  return text;
}

// s.txt -> s_part2.txt
std::string pieceFileName(const std::string& output, size_t k) {
  const std::filesystem::path p(output);
  return (p.parent_path() /
          (p.stem().string() + "_part" + std::to_string(k + 1) + p.extension().string()))
      .string();
}

// The program's points given in the part frame (CL data, TCP G-code) and their commanded joints.
std::vector<ClPoint> partFramePoints(const ClProgram& program,
                                     std::vector<JointVector>* commanded) {
  std::vector<ClPoint> path;
  for (size_t i = 0; i < program.path.size(); ++i) {
    if (!program.tcp.empty() && program.tcp[i] != ClProgram::kTcpWords) continue;
    path.push_back(program.path[i]);
    if (!program.joints.empty()) commanded->push_back(program.joints[i]);
  }
  if (path.empty())
    throw InputError(program.file, 0, 0, "program",
                     "no point is given in the part frame (all G-code moves are joint words): "
                     "the set-up does not change where the machine goes");
  return path;
}

// The lines of the points outside travel, as runs ("12-40, 77"), at most 8 runs.
std::string outsideLines(const std::vector<ClPoint>& path, const std::vector<int>& outside,
                         int* runs) {
  std::string lines;
  *runs = 0;
  for (size_t k = 0; k < outside.size() && *runs < 8; ++k) {
    const int first = path[outside[k]].line;
    size_t e = k;
    while (e + 1 < outside.size() && outside[e + 1] == outside[e] + 1) ++e;
    const int last = path[outside[e]].line;
    lines += (lines.empty() ? "" : ", ") + std::to_string(first) +
             (last != first ? "-" + std::to_string(last) : "");
    k = e;
    ++*runs;
  }
  return lines;
}

// The pieces a split program runs in, each with its set-up.
void printPieces(const std::vector<ClPoint>& path, const std::vector<SetupPiece>& pieces) {
  const bool all = !pieces.empty() && pieces.back().last == static_cast<int>(path.size()) - 1;
  bool each = true;
  for (const SetupPiece& p : pieces) each = each && p.result.found;
  if (all && each)
    std::printf("  split      %zu set-ups reach the program, one piece each:\n", pieces.size());
  else
    std::printf("  split      no split into %zu pieces or fewer reaches every point:\n",
                pieces.size());
  for (size_t k = 0; k < pieces.size(); ++k) {
    const SetupPiece& p = pieces[k];
    const PartSetup& ps = p.result.setup;
    if (!p.result.found) {
      std::printf("    piece %zu  line %d: no set-up reaches this point\n", k + 1,
                  path[p.first].line);
      continue;
    }
    std::printf(
        "    piece %zu  lines %d-%d (%d points): part_zero_mm = %.3f, %.3f, %.3f; "
        "part_rotation_deg = %.3f; gauge_length_mm = %.3f; margin %.3f mm "
        "(predict or verify it with --lines and its set-up file)\n",
        k + 1, path[p.first].line, path[p.last].line, p.last - p.first + 1, ps.part_zero_table.x(),
        ps.part_zero_table.y(), ps.part_zero_table.z(), radToDeg(ps.part_rotation), ps.gauge_length,
        p.result.margin);
  }
}

// The set-up file of the best single set-up, and one per piece of a split program.
void writeSetupFiles(const std::string& output, const ClProgram& program, const MachineModel& model,
                     const std::vector<ClPoint>& path, const SetupSearchResult& r,
                     const std::vector<SetupPiece>& pieces) {
  OutputSet files;  // all the set-up files, or none
  files.add(output, setupFileText(program, model, r.setup, r.margin, ""));
  std::vector<std::string> written;
  for (size_t k = 0; k < pieces.size(); ++k) {
    if (!pieces[k].result.found) continue;
    const std::string f = pieceFileName(output, k);
    const std::string what = ", lines " + std::to_string(path[pieces[k].first].line) + "-" +
                             std::to_string(path[pieces[k].last].line);
    files.add(f, setupFileText(program, model, pieces[k].result.setup, pieces[k].result.margin, what));
    written.push_back("  wrote      " + f + " (set-up file for piece " + std::to_string(k + 1) + what + ")");
  }
  files.commit();
  std::printf("  wrote      %s (set-up file%s)\n", output.c_str(),
              r.found ? "" : ": the best single set-up, which leaves points outside travel");
  for (const std::string& line : written) std::printf("%s\n", line.c_str());
}

// What the search starts from: the machine, the program's extent in the part frame, the set-up.
void printSetupHeader(const SetupOptions& o, const ClProgram& program, const MachineModel& model,
                      const std::vector<ClPoint>& path) {
  Eigen::Vector3d lo = path[0].p_w, hi = lo;
  for (const ClPoint& c : path) {
    lo = lo.cwiseMin(c.p_w);
    hi = hi.cwiseMax(c.p_w);
  }
  std::printf("tolver setup\n");
  std::printf("  machine    %s (%s)\n", model.name.c_str(), o.machine.machine.c_str());
  std::printf("  program    %s (%s): %zu tool positions in the part frame, units %s\n",
              program.file.c_str(), program.dialect.c_str(), path.size(), program.units.c_str());
  std::printf("  extent     x %.3f .. %.3f, y %.3f .. %.3f, z %.3f .. %.3f mm (part frame)\n",
              lo.x(), hi.x(), lo.y(), hi.y(), lo.z(), hi.z());
  const PartSetup& s = model.setup;
  std::printf(
      "  set-up     part zero (%.3f, %.3f, %.3f) mm, rotation %.3f deg, gauge length "
      "%.3f mm%s\n",
      s.part_zero_table.x(), s.part_zero_table.y(), s.part_zero_table.z(),
      radToDeg(s.part_rotation), s.gauge_length,
      o.machine.setup.empty() ? " (defaults: no --setup)" : "");
  for (const std::string& w : setupWarnings(model))
    std::fprintf(stderr, "tolver: warning: %s\n", w.c_str());
  for (const std::string& w : unitWarnings(program, model, o.program.units))
    std::fprintf(stderr, "tolver: warning: %s\n", w.c_str());
  for (const std::string& w : programNotes(program))
    std::fprintf(stderr, "tolver: note: %s: %s\n", program.file.c_str(), w.c_str());
}

// Set-up of a program posted outside TCP mode: the work offset that centres its joints.
void runWorkOffsetSetup(const SetupOptions& o, const ClProgram& program, const MachineModel& model,
                        int* exit_code) {
  printSetupHeader(o, program, model, program.path);
  int fixed = 0;
  for (char k : program.tcp) fixed += k == ClProgram::kMachineCoordinates;
  std::printf("  mode       every move in joint words: %zu in the work offset, %d in machine "
              "coordinates (G53/G28/SUPA, fixed)\n",
              program.path.size() - fixed, fixed);
  const WorkOffsetSetup r =
      proposeWorkOffset(model, program.joints, program.tcp, program.fixed_axes);
  if (!std::isfinite(r.margin)) {
    double margin = 0.0;
    int limiting = -1;
    const std::vector<AxisRange> ranges =
        commandedJointRanges(model, program.joints, &margin, &limiting);
    printRanges(model, program, ranges);
    std::printf("  result     every move is in machine coordinates or in a work offset the program "
                "sets itself (G10): the set-up does not change where the machine goes; %s\n",
                margin >= -1e-9 ? "every point is inside travel" : "points are outside travel");
    *exit_code = margin >= -1e-9 ? 0 : 1;
    return;
  }
  std::printf("  proposed   part_zero_mm = %.3f, %.3f, %.3f (the program's origin)\n",
              r.part_zero_table.x(), r.part_zero_table.y(), r.part_zero_table.z());
  std::printf("             work offset at the control (G54..., machine coordinates): X%.3f "
              "Y%.3f Z%.3f\n",
              r.work_offset_m.x(), r.work_offset_m.y(), r.work_offset_m.z());
  std::printf("             gauge_length_mm = %.3f (tool length when the set-up gives none)\n",
              model.setup.gauge_length);
  // The reach check, exact: the program read again with the proposal, its joints against travel.
  MachineModel best = model;
  best.setup.part_zero_table = r.part_zero_table;
  const ClProgram again = loadProgram(o.program, best);
  double margin = 0.0;
  int limiting = -1;
  const std::vector<AxisRange> ranges = commandedJointRanges(best, again.joints, &margin, &limiting);
  printRanges(best, again, ranges);
  if (r.found && margin >= -1e-9) {
    std::printf("  result     every point inside travel, smallest margin %.3f mm (exact: each "
                "axis's range centred)\n", r.margin);
    *exit_code = 0;
  } else if (r.found) {
    std::printf("  result     the program read again with this work offset leaves %s outside "
                "travel (at line %d): not proposed\n",
                model.axes[limiting].name.c_str(),
                again.path[std::max(0, ranges[limiting].min - model.axes[limiting].travel_min < 0
                                           ? ranges[limiting].min_index
                                           : ranges[limiting].max_index)].line);
    *exit_code = 1;
    return;
  } else {
    const char* axis = r.limiting_axis >= 0 ? model.axes[r.limiting_axis].name.c_str() : "-";
    if (r.limited_by_machine_coordinates)
      std::printf("  result     a move in machine coordinates (G53/G28/SUPA) is outside %s's travel "
                  "by %.3f mm: no work offset moves it; the program was posted for another "
                  "machine's home or travel\n", axis, -r.margin);
    else
      std::printf("  result     the program does not fit this machine's travel with any work "
                  "offset: %s needs %.3f mm more\n", axis, -r.margin);
    *exit_code = 1;
  }
  if (o.output.empty()) return;
  PartSetup b = model.setup;
  b.part_zero_table = r.part_zero_table;
  OutputSet files;
  std::string text = setupFileText(program, model, b, r.margin, "");
  text += "# at the control: G54 (and every work offset the program uses) = X" +
          formatNumber(r.work_offset_m.x()) + " Y" + formatNumber(r.work_offset_m.y()) + " Z" +
          formatNumber(r.work_offset_m.z()) + " (machine coordinates, mm)\n";
  files.add(o.output, text);
  files.commit();
  std::printf("  wrote      %s (set-up file)\n", o.output.c_str());
}

void runSetup(const SetupOptions& o, int* exit_code) {
  Machine machine = loadMachine(o.machine);
  // The search moves the part frame with the program in it: a posted program's work offsets
  // move with it (their origin at the part zero), so the set-up's are set aside here.
  const bool had_offsets = !machine.model.setup.work_offsets.empty();
  machine.model.setup.work_offsets.clear();
  const ClProgram program = loadProgram(o.program, machine.model);
  if (had_offsets && program.dialect == "G-code")
    std::fprintf(stderr,
                 "tolver: note: the set-up's work offsets are set aside: the search puts "
                 "G54... at the part zero it proposes\n");
  if (!o.output.empty()) checkOutputDir(o.output, "-o");
  for (double L : o.gauge_lengths)
    if (!(L >= 0 && L < 1e5))
      throw InputError("--gauge-lengths", 0, 0, "gauge length",
                       "expected lengths from 0 to 1e5 mm");
  const MachineModel& model = machine.model;

  // A posted program with no point in TCP mode: its words are joints in a work offset, and the
  // part zero (with the work offset at it) is proposed exactly, axis by axis.
  if (program.dialect == "G-code" &&
      std::none_of(program.tcp.begin(), program.tcp.end(),
                   [](char k) { return k == ClProgram::kTcpWords; })) {
    runWorkOffsetSetup(o, program, model, exit_code);
    return;
  }
  // Joint-mode G-code points are fixed in machine coordinates: the search moves the part under
  // the points given in the part frame (CL data, TCP G-code).
  std::vector<JointVector> commanded;
  const std::vector<ClPoint> path = partFramePoints(program, &commanded);
  const std::vector<JointVector>* cmd = commanded.empty() ? nullptr : &commanded;

  printSetupHeader(o, program, model, path);
  int failed = 0, first_failed = -1;
  const std::vector<AxisRange> now = jointRanges(model, path, cmd, &failed, &first_failed);
  printRanges(model, program, now);
  if (failed > 0)
    std::printf("  rotary     %d points need rotary angles outside travel (first at line %d)\n",
                failed, path[first_failed].line);

  SetupSearchOptions so;
  so.rotation_step = degToRad(o.rotation_step_deg);
  // A posted program's rotary words assume the part as the post placed it: keep its rotation.
  if (program.dialect == "G-code") so.rotation_step = 0.0;
  so.gauge_lengths = o.gauge_lengths;
  ProgressBar bar(true);  // on a terminal only (stderr)
  so.progress = [&bar](double f) { bar("searching set-ups", f); };
  const SetupSearchResult r = findSetup(model, path, cmd, so);
  bar("searching set-ups", 1.0);
  const PartSetup& b = r.setup;
  std::printf("  searched   %d part rotations (%d rejected: rotary travel)%s\n", r.rotations_tried,
              r.rotations_rejected,
              o.gauge_lengths.size() > 1 ? ", gauge lengths given with --gauge-lengths" : "");
  if (!std::isfinite(r.margin)) {
    std::printf(
        "  result     no rotation keeps the rotary axes inside travel: the program cannot "
        "run on this machine in one set-up\n");
    *exit_code = 1;
    return;
  }
  std::printf("  proposed   part_zero_mm = %.3f, %.3f, %.3f\n", b.part_zero_table.x(),
              b.part_zero_table.y(), b.part_zero_table.z());
  std::printf("             part_rotation_deg = %.3f\n", radToDeg(b.part_rotation));
  std::printf("             gauge_length_mm = %.3f\n", b.gauge_length);
  MachineModel best = model;
  best.setup.part_zero_table = b.part_zero_table;
  best.setup.part_rotation = b.part_rotation;
  best.setup.gauge_length = b.gauge_length;
  printRanges(best, program, r.ranges);
  if (r.found) {
    std::printf("  result     every point inside travel, smallest margin %.3f mm\n", r.margin);
    *exit_code = 0;
  } else {
    // The lines the best set-up leaves outside: where to split the program.
    int runs = 0;
    const std::string lines = outsideLines(path, r.outside, &runs);
    std::printf(
        "  result     no single set-up reaches the whole program; the best leaves %zu points "
        "outside travel, at lines %s%s: split the program there\n",
        r.outside.size(), lines.c_str(), runs >= 8 ? ", ..." : "");
    *exit_code = 1;
  }
  std::vector<SetupPiece> pieces;
  if (!r.found) {
    // Where to split: consecutive pieces of the program, each with a set-up that reaches it.
    pieces = splitIntoSetups(model, path, cmd, so);
    printPieces(path, pieces);
  }
  if (!o.output.empty()) writeSetupFiles(o.output, program, model, path, r, pieces);
}

}  // namespace

void registerSetup(CLI::App& app, int* exit_code) {
  auto o = std::make_shared<SetupOptions>();
  CLI::App* cmd = app.add_subcommand(
      "setup",
      "Where to clamp the part: the program's extent and joint ranges against the machine's "
      "travel, and a part zero, rotation and gauge length that keep it inside with the largest "
      "margin. Exit 1 when no single set-up reaches the whole program.");
  addMachineOptions(cmd, o->machine, "machine file (XML)");
  addProgramOptions(cmd, o->program);
  cmd->add_option("-o,--output", o->output, "set-up file to write with the proposal");
  cmd->add_option("--rotation-step-deg", o->rotation_step_deg,
                  "step of the part rotations tried, deg (default 15; 0 keeps the given rotation)")
      ->check(CLI::Range(0.0, 180.0));
  cmd->add_option("--gauge-lengths", o->gauge_lengths,
                  "gauge lengths to try, mm (default: the set-up's)")
      ->delimiter(',');
  cmd->callback([o, exit_code] { runSetup(*o, exit_code); });
}

}  // namespace tolver::app
