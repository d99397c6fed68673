#pragma once
// tolver setup as a library function: where to clamp the part. The program's joint ranges
// against the machine's travel, and a part zero, rotation and gauge length that keep it inside
// with the largest margin (core/path/setup_search.h); when no single set-up reaches it, where to
// split it. A program posted outside TCP mode gets the work offset that centres its joints.
#include <string>
#include <vector>

#include "core/path/setup_search.h"
#include "pipeline/command.h"
#include "pipeline/inputs.h"

namespace tolver {

struct SetupInputs {
  MachineOptions machine;
  ProgramOptions program;
  std::string output;                 // set-up file to write with the proposal, or empty
  double rotation_step_deg = 15.0;    // part rotations tried (0 keeps the given one)
  std::vector<double> gauge_lengths;  // gauge lengths to try, mm; empty: the set-up's
  // A time budget for the whole search, s (0: none): once spent, the best set-up of the
  // rotations tried (SetupSearchResult::budget_spent); the split of a program no set-up reaches
  // gets what is left, and stops with the pieces finished when it runs out
  // (SetupRun::split_budget_spent).
  double max_seconds = 0.0;
};

enum class SetupMode {
  PartFrame,   // points in the part frame (CL data, TCP G-code): the set-up is searched
  WorkOffset,  // posted joint words in a work offset: the work offset is proposed exactly
  Fixed,       // every move in machine coordinates or an offset the program sets (G10)
};

struct SetupRun {
  MachineModel model;  // as read (a posted program's work offsets set aside)
  ClProgram program;
  std::vector<ClPoint> path;       // the points the set-up moves (PartFrame: part-frame ones)
  bool offsets_set_aside = false;  // the set-up's work offsets were set aside (G-code)
  std::vector<std::string> warnings, notes;
  SetupMode mode = SetupMode::PartFrame;

  // PartFrame: the ranges with the given set-up, the search, and the split.
  std::vector<AxisRange> ranges_now;
  int unreachable = 0, first_unreachable = -1;  // points whose rotaries leave travel now
  SetupSearchResult search;
  bool rotations_exhausted = false;  // no rotation keeps the rotary axes inside travel
  MachineModel best;                 // the model with the proposed set-up
  std::string outside_lines;         // the best set-up's points outside travel, as line runs
  int outside_runs = 0;
  std::vector<SetupPiece> pieces;   // when no single set-up reaches the program
  bool split_budget_spent = false;  // --max-seconds ran out before the split was finished

  // WorkOffset and Fixed: the proposal, and the program read again with it (its joints against
  // travel).
  int fixed_moves = 0;  // moves in machine coordinates
  WorkOffsetSetup offset;
  std::vector<AxisRange> ranges_again;
  double margin_again = 0.0;
  int limiting_axis = -1, limiting_line = 0;

  // Written: the set-up file and one per piece (path, description).
  std::vector<std::pair<std::string, std::string>> written;
  Verdict verdict = Verdict::Ok;  // NotMet: no single set-up reaches the whole program
};

// Reads, searches or proposes, writes the set-up files (all or none) when an output is given.
// progress: "searching set-ups". Throws InputError.
SetupRun proposeSetup(const SetupInputs& in, const Progress& progress = {});

}  // namespace tolver
