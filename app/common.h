#pragma once
// Options and helpers shared by the commands.
#include <CLI/CLI.hpp>
#include <cmath>
#include <string>
#include <vector>

#include "core/machine_model.h"

namespace tolver::app {

// Machine file plus the set-up options every command accepts.
struct MachineOptions {
  std::string machine;
  std::string setup;
  std::vector<double> part_zero;
  double part_rotation_deg = NAN;
  double gauge_length = NAN;
};

void addMachineOptions(CLI::App* cmd, MachineOptions& o, const char* machine_help);
// Reads the machine file and applies the set-up file and options. Throws InputError.
Machine loadMachine(const MachineOptions& o);
// Throws InputError when the directory of `path` does not exist.
void checkOutputDir(const std::string& path, const char* option);
// A progress bar on stderr when it is a terminal (and enabled).
class ProgressBar {
 public:
  explicit ProgressBar(bool enabled);
  void operator()(const std::string& what, double fraction);

 private:
  bool enabled_;
};

// `path` with its extension replaced (or `suffix` appended when it has none).
std::string replaceExtension(const std::string& path, const std::string& ext);

}  // namespace tolver::app
