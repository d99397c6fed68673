// Report directories written as a whole (io/common/io_error.h ReportDirectory): a run killed with
// SIGKILL while writing leaves the previous report as it was; a second run on the same directory at
// the same time is refused (also a tolver verify started while one holds it: exit 2).
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "io/common/io_error.h"
#include "test_support.h"

namespace tolver {
namespace {

namespace fs = std::filesystem;

class ReportDirectoryTest : public test::TempDirTest {};

TEST_F(ReportDirectoryTest, CommitReplacesTheWholeDirectory) {
  const std::string dir = path("r");
  {
    ReportDirectory r(dir);
    writeFileAtomically(r.staging() + "/a.txt", "first");
    writeFileAtomically(r.staging() + "/old_only.txt", "x");
    r.commit();
  }
  EXPECT_EQ(test::readText(dir + "/a.txt"), "first");
  {
    ReportDirectory r(dir);
    writeFileAtomically(r.staging() + "/a.txt", "second");
    r.commit();
  }
  EXPECT_EQ(test::readText(dir + "/a.txt"), "second");
  EXPECT_FALSE(fs::exists(dir + "/old_only.txt"));  // the report is the new run's, whole
  for (const auto& e : fs::directory_iterator(path("")))
    EXPECT_EQ(e.path().filename().string().find(".tmp-"), std::string::npos) << e.path();
}

TEST_F(ReportDirectoryTest, ARunKilledWhileWritingLeavesThePreviousReport) {
  const std::string dir = path("r");
  {
    ReportDirectory r(dir);
    writeFileAtomically(r.staging() + "/report.json", "{\"run\": 1}");
    r.commit();
  }
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    ReportDirectory r(dir);
    writeFileAtomically(r.staging() + "/report.json", "{\"run\": 2, \"half");
    raise(SIGKILL);  // killed while writing: no destructor, no commit
    _exit(0);
  }
  int status = 0;
  waitpid(child, &status, 0);
  ASSERT_TRUE(WIFSIGNALED(status));
  EXPECT_EQ(WTERMSIG(status), SIGKILL);
  EXPECT_EQ(test::readText(dir + "/report.json"), "{\"run\": 1}");
  // The next run takes over (the lock died with the killed process) and cleans up after itself.
  ReportDirectory again(dir);
  writeFileAtomically(again.staging() + "/report.json", "{\"run\": 3}");
  again.commit();
  EXPECT_EQ(test::readText(dir + "/report.json"), "{\"run\": 3}");
  for (const auto& e : fs::directory_iterator(path("")))  // the killed run's staging is gone
    EXPECT_EQ(e.path().filename().string().find(".tmp-"), std::string::npos) << e.path();
}

TEST_F(ReportDirectoryTest, ASecondRunOnTheSameDirectoryIsRefused) {
  const std::string dir = path("r");
  ReportDirectory held(dir);
  EXPECT_THROW(ReportDirectory second(dir), InputError);
  const auto r = test::runTolver(
      "verify --machine " + test::sourcePath("samples/machines/matsuura_mc760vx_measured.xml") +
      " --setup " + test::sourcePath("samples/matsuura_setup.txt") + " --cl " +
      test::sourcePath("samples/nas979_cone.apt") + " --tolerance 0.02 --no-images --report-dir " +
      dir);
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("another tolver run is writing this report directory"), std::string::npos)
      << r.output;
  EXPECT_FALSE(fs::exists(dir + "/report.json"));
}

}  // namespace
}  // namespace tolver
