#pragma once
// Command-line options shared by the commands (CLI11), and the progress bar. The work behind
// them is in pipeline/.
#include <CLI/CLI.hpp>
#include <chrono>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "pipeline/command.h"
#include "pipeline/inputs.h"

namespace tolver::app {

void addMachineOptions(CLI::App* cmd, MachineOptions& o, const char* machine_help);
void addProgramOptions(CLI::App* cmd, ProgramOptions& o);
// --probed FILE (predict, verify, compensate).
void addProbedOption(CLI::App* cmd, std::string& path);

// The option that sets an input field of a command's Inputs (pipeline/command.h): "--" and the
// field with dashes, unless the option is spelled otherwise (tolerance_mm: --tolerance). The
// command's own spellings (plan-ballbar: cl is --for) come first.
std::string optionForField(const std::string& field);
// Registers the command's spellings with the library (setInputNamer), before it runs.
void useOptionNames(const std::map<std::string, std::string>& command_spellings = {});

// Every number option of app and its subcommands read by the files' rule (parseNumber: digits,
// one point, an optional sign and exponent; no hex, inf or nan), so that a number the files
// refuse is refused on the command line. Call once the commands are registered.
void useFileNumberRule(CLI::App* app);

// A run's warnings and notes to stderr, one line each ("tolver: warning: ...", "tolver: note:").
void printWarnings(const std::vector<std::string>& warnings);
void printNotes(const std::vector<std::string>& notes);

// Progress on stderr (when enabled): on a terminal, a bar per phase with its fraction and the
// time left (from the phase's rate so far, once 2 % is done and a second has passed); elsewhere
// (a log, a script), one line per phase that took 2 s or more (TOLVER_PROGRESS_SECONDS in the
// environment sets another bound; 0: every phase), when it ends: "tolver: <phase>: 12.3 s".
class ProgressBar {
 public:
  explicit ProgressBar(bool enabled);
  ~ProgressBar();
  ProgressBar(const ProgressBar&) = delete;
  ProgressBar& operator=(const ProgressBar&) = delete;
  void operator()(const std::string& what, double fraction);

 private:
  void endPhase();
  bool enabled_, tty_;
  double line_seconds_ = 2.0;
  std::string phase_;
  std::chrono::steady_clock::time_point start_;
  bool open_ = false, drawn_ = false;
};

// --quiet (no progress bar) on a command: its value, read in the command's callback.
std::shared_ptr<bool> addQuietFlag(CLI::App* cmd);
// The bar as a library function's progress callback (pipeline/command.h).
Progress progressOf(ProgressBar& bar);

}  // namespace tolver::app
