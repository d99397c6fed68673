#include "app/common.h"

#include <unistd.h>

#include <cstdio>

#include <filesystem>

#include "io/io_error.h"
#include "io/machine_file.h"
#include "io/setup_file.h"

namespace tolver::app {

void addMachineOptions(CLI::App* cmd, MachineOptions& o, const char* machine_help) {
  cmd->add_option("--machine", o.machine, machine_help)->required();
  cmd->add_option("--setup", o.setup, "set-up file (part zero, part rotation, gauge length)");
  cmd->add_option("--part-zero", o.part_zero, "part zero in the table frame, mm (x,y,z)")
      ->delimiter(',')
      ->expected(3);
  cmd->add_option("--part-rotation-deg", o.part_rotation_deg,
                  "rotation of the part about the table z axis, deg");
  cmd->add_option("--gauge-length", o.gauge_length, "tool gauge length, mm");
}

Machine loadMachine(const MachineOptions& o) {
  Machine machine = readMachineFile(o.machine);
  PartSetup setup;
  if (!o.setup.empty()) setup = readSetupFile(o.setup);
  if (!o.part_zero.empty()) {
    if (o.part_zero.size() != 3)
      throw InputError("--part-zero", 0, 0, "part zero", "expected x,y,z in mm");
    setup.part_zero_table = Eigen::Vector3d(o.part_zero[0], o.part_zero[1], o.part_zero[2]);
  }
  if (!std::isnan(o.part_rotation_deg)) setup.part_rotation = o.part_rotation_deg * M_PI / 180.0;
  if (!std::isnan(o.gauge_length)) setup.gauge_length = o.gauge_length;
  machine.model.setup = setup;
  return machine;
}

void checkOutputDir(const std::string& path, const char* option) {
  const auto dir = std::filesystem::path(path).parent_path();
  if (!dir.empty() && !std::filesystem::is_directory(dir))
    throw InputError(path, 0, 0, option, "directory " + dir.string() + " does not exist");
}

std::string replaceExtension(const std::string& path, const std::string& ext) {
  std::filesystem::path p(path);
  const std::filesystem::path original = p;
  p.replace_extension(ext);
  if (p == original) p += ".out" + ext;
  return p.string();
}

ProgressBar::ProgressBar(bool enabled) : enabled_(enabled && isatty(2)) {}

void ProgressBar::operator()(const std::string& what, double f) {
  if (!enabled_) return;
  const int width = 40, filled = static_cast<int>(f * width + 0.5);
  std::fprintf(stderr, "\r  %-24s [%s%s] %3d%%", what.c_str(), std::string(filled, '#').c_str(),
               std::string(width - filled, '.').c_str(), static_cast<int>(f * 100 + 0.5));
  if (f >= 1.0) std::fprintf(stderr, "\n");
  std::fflush(stderr);
}

}  // namespace tolver::app
