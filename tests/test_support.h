#pragma once
// Helpers shared by the tests: paths to fixtures and shipped files, running the CLI.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

namespace tolver::test {

inline std::string sourcePath(const std::string& rel) {
  return std::string(TOLVER_SOURCE_DIR) + "/" + rel;
}

inline const std::array<const char*, 6>& shippedMachines() {
  static const std::array<const char*, 6> m = {
      "resources/machines/matsuura_mc760vx.xml",   "resources/machines/xkh800.xml",
      "resources/machines/trunnion_ac_trt.xml",    "resources/machines/linuxcnc_xyzac_trt.xml",
      "resources/machines/linuxcnc_xyzbc_trt.xml", "resources/machines/umc_bc_trunnion.xml"};
  return m;
}

// The shipped machines and the test fixtures for what they do not cover (a rotary axis along
// no coordinate axis, rotated links, one and no rotary axis): for the kinematics tests.
inline const std::array<const char*, 9>& kinematicsTestMachines() {
  static const std::array<const char*, 9> m = {shippedMachines()[0],
                                               shippedMachines()[1],
                                               shippedMachines()[2],
                                               shippedMachines()[3],
                                               shippedMachines()[4],
                                               shippedMachines()[5],
                                               "tests/fixtures/machines/nutating_head_bc.xml",
                                               "tests/fixtures/machines/four_axis_a_table.xml",
                                               "tests/fixtures/machines/three_axis.xml"};
  return m;
}

inline std::string readText(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
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

// A test with a fresh temporary directory of its own, removed afterwards.
class TempDirTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = std::filesystem::temp_directory_path() /
           (std::string("tolver_") + info->test_suite_name() + "_" + info->name() + "_" +
            std::to_string(::getpid()));  // unique per process: suites may run concurrently
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  std::string write(const std::string& name, const std::string& text) const {
    std::ofstream(path(name)) << text;
    return path(name);
  }
  std::filesystem::path dir_;
};

}  // namespace tolver::test
