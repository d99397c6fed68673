#include "io/program/setup_file.h"

#include <gtest/gtest.h>

#include "io/common/io_error.h"

namespace tolver {
namespace {

TEST(SetupFile, ReadsKeysAndKeepsDefaults) {
  PartSetup base;
  base.gauge_length = 99;
  const PartSetup s = parseSetup(
      "# part on the table\npart_zero_mm = 1, 2.5, -3\n"
      "part_rotation_deg = 90  # turned\n",
      "s.txt", base);
  EXPECT_EQ(s.part_zero_table, Eigen::Vector3d(1, 2.5, -3));
  EXPECT_NEAR(s.part_rotation, M_PI / 2, 1e-15);
  EXPECT_EQ(s.gauge_length, 99);
  // A UTF-8 byte-order mark (issue 37: refused with the invisible mark inside the key) is read
  // past.
  const PartSetup b = parseSetup("\xEF\xBB\xBFpart_zero_mm = 1, 2, 3\n", "bom.txt");
  EXPECT_EQ(b.part_zero_table, Eigen::Vector3d(1, 2, 3));
}

TEST(SetupFile, BadLinesAreNamed) {
  // The last: an H number of 1e40 (found by the fuzzer: it was cast to int).
  const char* bad[] = {"part_zero_mm = 1, 2\n",
                       "gauge_length_mm = 1O0\n",
                       "tool = 3\n",
                       "\n\nnonsense\n",
                       "gauge_length_mm = -5\n",
                       "# x\ntool_h10000000000000000000000000000000000000000_mm = 5\n"};
  const int lines[] = {1, 1, 1, 3, 1, 2};
  for (int i = 0; i < 6; ++i) {
    try {
      parseSetup(bad[i], "s.txt");
      ADD_FAILURE() << bad[i];
    } catch (const InputError& e) {
      EXPECT_EQ(e.line(), lines[i]) << e.what();
    }
  }
}

}  // namespace
}  // namespace tolver
