// The verify jobs file (io/program/jobs_file.h): paths resolved against the file's folder, the
// one CSV policy (quoting, comments, any header case), and its errors naming line and column.
#include "io/program/jobs_file.h"

#include <gtest/gtest.h>

#include "io/common/io_error.h"

namespace tolver {
namespace {

TEST(JobsFile, RowsResolveAgainstTheFilesFolder) {
  const std::string text =
      "# jobs\nName,Machine,CL,Part,Tolerance,Zones\n"
      "a,m.xml,progs/a.apt,/abs/a.stl,0.03,\n"
      "\"b, the second\",m.xml,b.nc,,,zones.csv\n";
  const std::vector<VerifyJob> jobs = parseJobsCsv(text, "/work/cell/jobs.csv");
  ASSERT_EQ(jobs.size(), 2u);
  EXPECT_EQ(jobs[0].name, "a");
  EXPECT_EQ(jobs[0].machine, "/work/cell/m.xml");
  EXPECT_EQ(jobs[0].cl, "/work/cell/progs/a.apt");
  EXPECT_EQ(jobs[0].part, "/abs/a.stl");  // absolute paths stay
  EXPECT_DOUBLE_EQ(jobs[0].tolerance_mm, 0.03);
  EXPECT_EQ(jobs[0].line, 3);
  EXPECT_EQ(jobs[1].name, "b, the second");
  EXPECT_TRUE(std::isnan(jobs[1].tolerance_mm));  // zones instead
  EXPECT_EQ(jobs[1].zones, "/work/cell/zones.csv");
}

TEST(JobsFile, BadRowsNameLineAndColumn) {
  auto error = [](const std::string& text) {
    try {
      parseJobsCsv(text, "jobs.csv");
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(error("name,machine,cl,tolerance\na,m,c,0.1\na,m,c,0.1\n").find("jobs.csv:3:1"),
            std::string::npos)
      << error("name,machine,cl,tolerance\na,m,c,0.1\na,m,c,0.1\n");
  EXPECT_NE(error("name,machine,cl,tolerance\na,m,c,x\n").find("not a number"), std::string::npos);
  EXPECT_NE(error("name,machine,cl,tolerance\n../up,m,c,0.1\n").find("plain file name"),
            std::string::npos);
  EXPECT_NE(error("name,machine,tolerance\na,m,0.1\n").find("cl"), std::string::npos);
  EXPECT_NE(error("name,machine,cl,tolerance\n").find("no job"), std::string::npos);
  // A row with more cells than the header (issue 37: accepted): named with its line; a trailing
  // comma is not a cell.
  EXPECT_NE(error("name,machine,cl,tolerance\na,m,c,0.1,extra\n").find("jobs.csv:2:5"),
            std::string::npos)
      << error("name,machine,cl,tolerance\na,m,c,0.1,extra\n");
  EXPECT_EQ(parseJobsCsv("name,machine,cl,tolerance\na,m,c,0.1,\n", "jobs.csv").size(), 1u);
  // A byte-order mark before the header is not part of the first column's name.
  EXPECT_EQ(parseJobsCsv("\xEF\xBB\xBFname,machine,cl,tolerance\na,m,c,0.1\n", "jobs.csv").size(),
            1u);
}

}  // namespace
}  // namespace tolver
