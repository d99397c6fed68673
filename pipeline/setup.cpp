#include "pipeline/setup.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <stdexcept>

#include "core/numerics/quantities.h"
#include "core/numerics/units.h"
#include "io/common/io_error.h"
#include "io/common/text_util.h"

namespace tolver {
namespace {

// The set-up file's text for a proposed set-up (the format setup_file.h reads).
std::string setupFileText(const ClProgram& program, const MachineModel& model, const PartSetup& b,
                          double margin, const std::string& what) {
  // A set-up that is not a number is a defect upstream, never a file (it was written once, as
  // "-nan", for a program whose Z no point moved in the work offset).
  if (!b.part_zero_table.allFinite() || !std::isfinite(b.part_rotation) ||
      !std::isfinite(b.gauge_length))
    throw std::logic_error("setup: a proposed set-up that is not a number");
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

// The set-up file of the best single set-up, and one per piece of a split program.
void writeSetupFiles(const std::string& output, SetupRun& run) {
  const SetupSearchResult& r = run.search;
  OutputSet files;  // all the set-up files, or none
  files.add(output, setupFileText(run.program, run.model, r.setup, r.margin, ""));
  run.written.push_back({output, r.found ? "set-up file"
                                         : "set-up file: the best single set-up, which leaves "
                                           "points outside travel"});
  for (size_t k = 0; k < run.pieces.size(); ++k) {
    const SetupPiece& p = run.pieces[k];
    if (!p.result.found) continue;
    const std::string f = pieceFileName(output, k);
    const std::string what = ", lines " + std::to_string(run.path[p.first].line) + "-" +
                             std::to_string(run.path[p.last].line);
    files.add(f, setupFileText(run.program, run.model, p.result.setup, p.result.margin, what));
    run.written.push_back({f, "set-up file for piece " + std::to_string(k + 1) + what});
  }
  files.commit();
}

// A program posted outside TCP mode: the work offset that centres its joints, checked exactly by
// reading the program again with it.
void proposeWorkOffsetSetup(const SetupInputs& in, SetupRun& run) {
  const MachineModel& model = run.model;
  const ClProgram& program = run.program;
  run.mode = SetupMode::WorkOffset;
  run.path = program.path;
  for (char k : program.tcp) run.fixed_moves += k == ClProgram::kMachineCoordinates;
  run.offset = proposeWorkOffset(model, program.joints, program.tcp, program.fixed_axes);
  const WorkOffsetSetup& r = run.offset;
  for (int j = 0; j < 3; ++j)
    if (!r.placed[j])
      run.notes.push_back(std::string("the program moves ") + "XYZ"[j] +
                          " only in machine coordinates (G53, G28): it does not place the part "
                          "zero along it, which stays at the set-up's (" +
                          formatNumber(model.setup.part_zero_table[j]) + " mm)");
  if (!std::isfinite(r.margin)) {
    run.mode = SetupMode::Fixed;
    run.ranges_again =
        commandedJointRanges(model, program.joints, &run.margin_again, &run.limiting_axis);
    run.verdict = run.margin_again >= -1e-9 ? Verdict::Ok : Verdict::NotMet;
    return;
  }
  run.best = model;
  run.best.setup.part_zero_table = r.part_zero_table;
  const ClProgram again = loadProgram(in.program, run.best);
  run.ranges_again =
      commandedJointRanges(run.best, again.joints, &run.margin_again, &run.limiting_axis);
  if (r.found && run.margin_again >= -1e-9) {
    run.verdict = Verdict::Ok;
  } else {
    run.verdict = Verdict::NotMet;
    if (r.found) {
      const AxisRange& lr = run.ranges_again[run.limiting_axis];
      const Axis& ax = run.best.axes[run.limiting_axis];
      run.limiting_line =
          again.path[std::max(0, lr.min - ax.travel_min < 0 ? lr.min_index : lr.max_index)].line;
    }
  }
  if (in.output.empty() || (r.found && run.margin_again < -1e-9)) return;
  PartSetup b = model.setup;
  b.part_zero_table = r.part_zero_table;
  OutputSet files;
  std::string text = setupFileText(program, model, b, r.margin, "");
  text += "# at the control: G54 (and every work offset the program uses) = X" +
          formatNumber(r.work_offset_m.x()) + " Y" + formatNumber(r.work_offset_m.y()) + " Z" +
          formatNumber(r.work_offset_m.z()) + " (machine coordinates, mm)\n";
  files.add(in.output, text);
  files.commit();
  run.written.push_back({in.output, "set-up file"});
}

}  // namespace

SetupRun proposeSetup(const SetupInputs& in, const Progress& progress) {
  if (!(in.rotation_step_deg >= 0 && in.rotation_step_deg <= 180))
    throw FieldError("rotation_step_deg", "expected 0 to 180 deg");
  for (double L : in.gauge_lengths)
    if (const std::string problem = outOfRange(Quantity::Length, L); !problem.empty())
      throw FieldError("gauge_lengths", problem);
  SetupRun run;
  Machine machine = loadMachine(in.machine);
  // The search moves the part frame with the program in it: a posted program's work offsets
  // move with it (their origin at the part zero), so the set-up's are set aside here.
  const bool had_offsets = !machine.model.setup.work_offsets.empty();
  machine.model.setup.work_offsets.clear();
  run.model = machine.model;
  run.program = loadProgram(in.program, run.model);
  const MachineModel& model = run.model;
  const ClProgram& program = run.program;
  run.offsets_set_aside = had_offsets && program.dialect == "G-code";
  if (run.offsets_set_aside)
    run.notes.push_back(
        "the set-up's work offsets are set aside: the search puts G54... at the part zero it "
        "proposes");
  if (!in.output.empty()) checkOutputDir(in.output, "output");
  // Of the defaults setupWarnings names, only the gauge length is not what setup proposes.
  if (!model.setup.gauge_length_given && in.gauge_lengths.empty())
    run.warnings.push_back(
        "no gauge length given: 0 mm (the tool tip at the spindle gauge "
        "point) was used; give the tool's with " +
        inputName("gauge_length") + ", " + inputName("gauge_lengths") + " or " +
        inputName("setup"));
  for (const std::string& w : unitWarnings(program, model, in.program.units))
    run.warnings.push_back(w);
  for (const std::string& w : programNotes(program)) run.notes.push_back(program.file + ": " + w);

  // A posted program with no point in TCP mode: its words are joints in a work offset, and the
  // part zero (with the work offset at it) is proposed exactly, axis by axis.
  if (program.dialect == "G-code" &&
      std::none_of(program.tcp.begin(), program.tcp.end(),
                   [](char k) { return k == ClProgram::kTcpWords; })) {
    proposeWorkOffsetSetup(in, run);
    return run;
  }
  // Joint-mode G-code points are fixed in machine coordinates: the search moves the part under
  // the points given in the part frame (CL data, TCP G-code).
  std::vector<JointVector> commanded;
  run.path = partFramePoints(program, &commanded);
  const std::vector<JointVector>* cmd = commanded.empty() ? nullptr : &commanded;
  run.ranges_now = jointRanges(model, run.path, cmd, &run.unreachable, &run.first_unreachable);

  SetupSearchOptions so;
  so.rotation_step = degToRad(in.rotation_step_deg);
  // A posted program's rotary words assume the part as the post placed it: keep its rotation.
  if (program.dialect == "G-code") so.rotation_step = 0.0;
  so.gauge_lengths = in.gauge_lengths;
  so.max_seconds = in.max_seconds;
  if (progress) so.progress = [&progress](double f) { progress("searching set-ups", f); };
  const auto start = std::chrono::steady_clock::now();
  run.search = findSetup(model, run.path, cmd, so);
  if (progress) progress("searching set-ups", 1.0);
  const SetupSearchResult& r = run.search;
  if (!std::isfinite(r.margin)) {
    run.rotations_exhausted = true;
    run.verdict = Verdict::NotMet;
    return run;
  }
  run.best = model;
  run.best.setup.part_zero_table = r.setup.part_zero_table;
  run.best.setup.part_rotation = r.setup.part_rotation;
  run.best.setup.gauge_length = r.setup.gauge_length;
  if (r.found) {
    run.verdict = Verdict::Ok;
  } else {
    // The lines the best set-up leaves outside: where to split the program; and the pieces, each
    // with a set-up that reaches it.
    run.verdict = Verdict::NotMet;
    run.outside_lines = outsideLines(run.path, r.outside, &run.outside_runs);
    // --max-seconds bounds the whole command: the split gets what the search left.
    if (so.max_seconds > 0.0) {
      const std::chrono::duration<double> t = std::chrono::steady_clock::now() - start;
      so.max_seconds = std::max(so.max_seconds - t.count(), 1e-9);
    }
    if (progress) so.progress = [&progress](double f) { progress("splitting the program", f); };
    run.pieces = splitIntoSetups(model, run.path, cmd, so, 8, &run.split_budget_spent);
    if (progress) progress("splitting the program", 1.0);
  }
  if (!in.output.empty()) writeSetupFiles(in.output, run);
  return run;
}

}  // namespace tolver
