#include "io/machine/ballbar_file.h"

#include <gtest/gtest.h>

#include "io/common/io_error.h"
#include "io/machine/machine_file.h"
#include "test_support.h"

namespace tolver {
namespace {

const MachineModel& matsuura() {
  static const Machine m = readMachineFile(test::sourcePath(test::shippedMachines()[0]));
  return m.model;
}

const char* kHeader =
    "setup,table_ball_x_mm,table_ball_y_mm,table_ball_z_mm,tool_ball_x_mm,tool_ball_y_mm,"
    "tool_ball_z_mm,x_mm,y_mm,z_mm,a_deg,c_deg,length_mm";

TEST(BallbarFile, ReadsReadingsWithCommentsDirectionsAndIgnoredColumns) {
  const std::string text = std::string("# a test\n") + kHeader +
                           ",time_s,operator\n"
                           "1,0,0,0,25,0,-80,10,20,30,-45,90,150.001,0,ann\n"
                           "1,0,0,0,25,0,-80,5,20,35,-45,90,149.999,20,ann\n"
                           "2,80,0,30,0,25,-80,5,20,35,-45,90,150.002,40,ann\n";
  const BallbarFile f = parseBallbarCsv(text, "r.csv", matsuura(), true);
  ASSERT_EQ(f.test.readings.size(), 3u);
  ASSERT_EQ(f.test.setups.size(), 2u);
  EXPECT_EQ(f.test.setups[1].table_ball_w, Eigen::Vector3d(80, 0, 30));
  EXPECT_NEAR(f.test.readings[0].q[3], -45 * M_PI / 180, 1e-15);
  EXPECT_DOUBLE_EQ(f.test.readings[2].context.time_s, 40);
  EXPECT_EQ(f.warnings, std::vector<std::string>{"ignored column 'operator'"});
  // Directions derived from the sequence: x decreased, z increased.
  EXPECT_EQ(f.test.readings[1].context.direction[0], -1);
  EXPECT_EQ(f.test.readings[1].context.direction[2], 1);
  EXPECT_EQ(f.test.readings[2].context.direction[0], -1);  // did not move: kept
}

TEST(BallbarFile, RoundTrip) {
  const std::string text = std::string(kHeader) + "\n3,1.5,2,3,4,5,6,-1,2.25,3,4,5,150\n";
  const BallbarFile f = parseBallbarCsv(text, "r.csv", matsuura(), true);
  const BallbarFile back =
      parseBallbarCsv(formatBallbarCsv(matsuura(), f.test, true, {"x"}), "b.csv", matsuura(), true);
  EXPECT_EQ(back.test.readings[0].q, f.test.readings[0].q);
  EXPECT_EQ(back.test.readings[0].length, 150);
  EXPECT_EQ(back.test.setups[0].id, 3);
}

TEST(BallbarFile, BadRowsNameTheLineAndColumn) {
  struct Case {
    std::string body;
    int line;
    std::string field;
  };
  const std::vector<Case> cases = {
      {"1,0,0,0,25,0,-80,10,20,30,-45,90\n", 2, "length_mm"},  // missing value
      {"1,0,0,0,25,0,-80,10,2O,30,-45,90,150\n", 2, "y_mm"},   // text in a number
      {"1,0,0,0,25,0,-80,10,20,nan,-45,90,150\n", 2, "z_mm"},  // NaN
      {"1,0,0,0,25,0,-80,10,20,30,-45,90,150\n1,9,0,0,25,0,-80,1,2,3,4,5,150\n", 3, "setup"},
      {"1.5,0,0,0,25,0,-80,10,20,30,-45,90,150\n", 2, "setup"},
      {"1,0,0,0,25,0,-80,10,20,30,-45,90,-3\n", 2, "length_mm"},
      // Out of the plausible range.
      {"1,0,0,0,25,0,-80,10,1e300,30,-45,90,150\n", 2, "y_mm"},
      {"1,0,0,0,25,0,-80,10,20,30,1e300,90,150\n", 2, "a_deg"},
      {"1,0,0,0,25,0,-80,10,20,30,-45,90,1e7\n", 2, "length_mm"},
  };
  for (const Case& c : cases) {
    try {
      parseBallbarCsv(std::string(kHeader) + "\n" + c.body, "r.csv", matsuura(), true);
      ADD_FAILURE() << c.body;
    } catch (const InputError& e) {
      EXPECT_EQ(e.line(), c.line) << e.what();
      EXPECT_EQ(e.field(), c.field) << e.what();
    }
  }
  EXPECT_THROW(parseBallbarCsv("setup,x_mm\n1,2\n", "r.csv", matsuura(), true), InputError);
  EXPECT_THROW(parseBallbarCsv("# only comments\n", "r.csv", matsuura(), true), InputError);
  EXPECT_THROW(parseBallbarCsv(std::string(kHeader) + "\n", "r.csv", matsuura(), true), InputError);
  // A plan needs no length column.
  EXPECT_NO_THROW(parseBallbarCsv(std::string(kHeader).substr(0, std::string(kHeader).size() - 10) +
                                      "\n1,0,0,0,25,0,-80,10,20,30,-45,90\n",
                                  "p.csv", matsuura(), false));
}

}  // namespace
}  // namespace tolver
