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
#include "pipeline/setup.h"

namespace tolver::app {
namespace {

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

// The pieces a split program runs in, each with its set-up.
void printPieces(const std::vector<ClPoint>& path, const std::vector<SetupPiece>& pieces,
                 bool budget_spent, double max_seconds) {
  const bool all = !pieces.empty() && pieces.back().last == static_cast<int>(path.size()) - 1;
  bool each = true;
  for (const SetupPiece& p : pieces) each = each && p.result.found;
  if (budget_spent && !all) {
    const int done = pieces.empty() ? 0 : pieces.back().last + 1;
    std::printf(
        "  split      --max-seconds %g ran out while splitting the program: %zu piece(s) found, "
        "covering %d of %zu points%s; the rest is not split (a longer budget may split it)\n",
        max_seconds, pieces.size(), done, path.size(),
        done > 0 ? (" (to line " + std::to_string(path[done - 1].line) + ")").c_str() : "");
    if (pieces.empty()) return;
  } else if (all && each)
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

// What the search starts from: the machine, the program's extent in the part frame, the set-up.
void printSetupHeader(const SetupInputs& o, const SetupRun& run) {
  const ClProgram& program = run.program;
  const MachineModel& model = run.model;
  const std::vector<ClPoint>& path = run.path;
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
  printWarnings(run.warnings);
  printNotes(run.notes);
}

// A program posted outside TCP mode: the work offset that centres its joints.
void printWorkOffset(const SetupInputs& o, const SetupRun& run) {
  const MachineModel& model = run.model;
  const ClProgram& program = run.program;
  const WorkOffsetSetup& r = run.offset;
  printSetupHeader(o, run);
  std::printf(
      "  mode       every move in joint words: %zu in the work offset, %d in machine "
      "coordinates (G53/G28/SUPA, fixed)\n",
      program.path.size() - run.fixed_moves, run.fixed_moves);
  if (run.mode == SetupMode::Fixed) {
    printRanges(model, program, run.ranges_again);
    std::printf(
        "  result     every move is in machine coordinates or in a work offset the program "
        "sets itself (G10): the set-up does not change where the machine goes; %s\n",
        run.margin_again >= -1e-9 ? "every point is inside travel" : "points are outside travel");
    if (!o.output.empty())
      std::printf(
          "  wrote      nothing: there is no part zero to propose (%s not written: the "
          "program places every point itself)\n",
          o.output.c_str());
    return;
  }
  std::printf("  proposed   part_zero_mm = %.3f, %.3f, %.3f (the program's origin)\n",
              r.part_zero_table.x(), r.part_zero_table.y(), r.part_zero_table.z());
  std::printf(
      "             work offset at the control (G54..., machine coordinates): X%.3f "
      "Y%.3f Z%.3f\n",
      r.work_offset_m.x(), r.work_offset_m.y(), r.work_offset_m.z());
  std::printf("             gauge_length_mm = %.3f (tool length when the set-up gives none)\n",
              model.setup.gauge_length);
  printRanges(run.best, program, run.ranges_again);
  if (r.found && run.margin_again >= -1e-9 && r.limited_by_machine_coordinates) {
    // A G28/G53 move at a home position sits at the end of travel whatever the offset.
    std::printf(
        "  result     every point inside travel; the work-offset moves at least %.3f mm from "
        "the travel's ends (exact: each axis's range centred), the %d move(s) in machine "
        "coordinates (G53/G28/SUPA) where the control puts them, %.3f mm from %s's end\n",
        r.work_offset_margin, run.fixed_moves, std::max(0.0, r.margin),
        model.axes[r.limiting_axis].name.c_str());
  } else if (r.found && run.margin_again >= -1e-9) {
    std::printf(
        "  result     every point inside travel, smallest margin %.3f mm (exact: each "
        "axis's range centred)\n",
        r.margin);
  } else if (r.found) {
    std::printf(
        "  result     the program read again with this work offset leaves %s outside "
        "travel (at line %d): not proposed\n",
        model.axes[run.limiting_axis].name.c_str(), run.limiting_line);
  } else {
    const char* axis = r.limiting_axis >= 0 ? model.axes[r.limiting_axis].name.c_str() : "-";
    if (r.limited_by_machine_coordinates)
      std::printf(
          "  result     a move in machine coordinates (G53/G28/SUPA) is outside %s's travel "
          "by %.3f mm: no work offset moves it; the program was posted for another "
          "machine's home or travel\n",
          axis, -r.margin);
    else
      std::printf(
          "  result     the program does not fit this machine's travel with any work "
          "offset: %s needs %.3f mm more\n",
          axis, -r.margin);
  }
}

// A program in the part frame: the search and, when no single set-up reaches it, the split.
void printSearch(const SetupInputs& o, const SetupRun& run) {
  const MachineModel& model = run.model;
  const ClProgram& program = run.program;
  const SetupSearchResult& r = run.search;
  printSetupHeader(o, run);
  printRanges(model, program, run.ranges_now);
  if (run.unreachable > 0)
    std::printf("  rotary     %d points need rotary angles outside travel (first at line %d)\n",
                run.unreachable, run.path[run.first_unreachable].line);
  std::printf("  searched   %d part rotations (%d rejected: rotary travel)%s\n", r.rotations_tried,
              r.rotations_rejected,
              o.gauge_lengths.size() > 1 ? ", gauge lengths given with --gauge-lengths" : "");
  if (r.budget_spent)
    std::printf(
        "  budget     --max-seconds %g ran out after %d part rotation(s): the set-up below is the "
        "best of those tried, not of all (a longer budget may find a larger margin)\n",
        o.max_seconds, r.rotations_tried);
  if (run.rotations_exhausted) {
    std::printf(
        "  result     no rotation keeps the rotary axes inside travel: the program cannot "
        "run on this machine in one set-up\n");
    return;
  }
  const PartSetup& b = r.setup;
  std::printf("  proposed   part_zero_mm = %.3f, %.3f, %.3f\n", b.part_zero_table.x(),
              b.part_zero_table.y(), b.part_zero_table.z());
  std::printf("             part_rotation_deg = %.3f\n", radToDeg(b.part_rotation));
  std::printf("             gauge_length_mm = %.3f\n", b.gauge_length);
  printRanges(run.best, program, r.ranges);
  if (r.found)
    std::printf("  result     every point inside travel, smallest margin %.3f mm\n", r.margin);
  else
    std::printf(
        "  result     no single set-up reaches the whole program; the best leaves %zu points "
        "outside travel, at lines %s%s: split the program there\n",
        r.outside.size(), run.outside_lines.c_str(), run.outside_runs >= 8 ? ", ..." : "");
  if (!r.found) printPieces(run.path, run.pieces, run.split_budget_spent, o.max_seconds);
}

void printSetupRun(const SetupInputs& o, const SetupRun& run) {
  if (run.mode == SetupMode::PartFrame)
    printSearch(o, run);
  else
    printWorkOffset(o, run);
  for (const auto& [path, what] : run.written)
    std::printf("  wrote      %s (%s)\n", path.c_str(), what.c_str());
}

}  // namespace

void registerSetup(CLI::App& app, Verdict* verdict) {
  auto o = std::make_shared<SetupInputs>();
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
  cmd->add_option("--max-seconds", o->max_seconds,
                  "time budget of the search, s (default 0: none); when it runs out, the best "
                  "set-up of the part rotations tried, said so")
      ->check(CLI::Range(0.0, 1e6));
  cmd->callback([o, verdict] {
    ProgressBar bar(true);  // a bar on a terminal, a line per long phase elsewhere (stderr)
    const SetupRun run = proposeSetup(*o, progressOf(bar));
    printSetupRun(*o, run);
    *verdict = run.verdict;
  });
}

}  // namespace tolver::app
