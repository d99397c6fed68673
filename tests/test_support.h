#pragma once
// Helpers shared by the tests: paths to fixtures and shipped files, running the CLI.
#include <array>
#include <cstdio>
#include <string>
#include <sys/wait.h>

namespace tolver::test {

inline std::string sourcePath(const std::string& rel) {
  return std::string(TOLVER_SOURCE_DIR) + "/" + rel;
}

inline const std::array<const char*, 3>& shippedMachines() {
  static const std::array<const char*, 3> m = {"resources/machines/matsuura_mc760vx.xml",
                                               "resources/machines/xkh800.xml",
                                               "resources/machines/trunnion_ac_trt.xml"};
  return m;
}

struct RunResult {
  int exit_code = -1;
  std::string output;  // stdout and stderr together
};

// Runs the tolver binary with the given arguments (a shell-quoted string).
inline RunResult runTolver(const std::string& args) {
  RunResult r;
  const std::string cmd = std::string(TOLVER_BINARY) + " " + args + " 2>&1";
  FILE* p = popen(cmd.c_str(), "r");
  if (!p) return r;
  char buf[4096];
  size_t n;
  while ((n = fread(buf, 1, sizeof buf, p)) > 0) r.output.append(buf, n);
  const int status = pclose(p);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

}  // namespace tolver::test
