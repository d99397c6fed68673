#pragma once
// Command-line options shared by the commands (CLI11), and the progress bar. The work behind
// them is in pipeline/.
#include <CLI/CLI.hpp>
#include <string>

#include "pipeline/inputs.h"

namespace tolver::app {

void addMachineOptions(CLI::App* cmd, MachineOptions& o, const char* machine_help);
void addProgramOptions(CLI::App* cmd, ProgramOptions& o);
// --probed FILE (predict, verify, compensate).
void addProbedOption(CLI::App* cmd, std::string& path);

// A progress bar on stderr when it is a terminal (and enabled).
class ProgressBar {
 public:
  explicit ProgressBar(bool enabled);
  void operator()(const std::string& what, double fraction);

 private:
  bool enabled_;
};

}  // namespace tolver::app
