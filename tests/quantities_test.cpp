// The range policy (core/numerics/quantities.h) and the number rule: a value refused on the
// command line is refused in a file and the other way round, each quantity at its bounds, through
// the library functions the CLI calls (pipeline) and the readers (io). The CLI's own number rule
// (no nan, inf or hex on the command line either) is tested in predict_cli_test.
#include "core/numerics/quantities.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <random>
#include <string>

#include "io/common/io_error.h"
#include "io/common/text_util.h"
#include "io/machine/ballbar_file.h"
#include "io/machine/machine_file.h"
#include "io/machine/zone_file.h"
#include "io/program/jobs_file.h"
#include "io/program/setup_file.h"
#include "pipeline/ballbar.h"
#include "pipeline/calibrate.h"
#include "pipeline/inputs.h"
#include "pipeline/setup.h"
#include "pipeline/verify.h"
#include "test_support.h"

namespace tolver {
namespace {

using test::sourcePath;

const char* kMachine = "resources/machines/matsuura_mc760vx.xml";

// The file's verdict on one set-up line: "" when accepted, else the error's text.
std::string setupFileSays(const std::string& line) {
  try {
    parseSetup(line + "\n", "setup.txt");
    return "";
  } catch (const InputError& e) {
    return e.what();
  }
}

// The library's verdict on the same value given as the option's field.
template <typename F>
std::string fieldSays(F&& f) {
  try {
    f();
    return "";
  } catch (const FieldError& e) {
    return e.field() + ": " + e.message();
  }
}

std::string loadSays(MachineOptions o) {
  o.machine = sourcePath(kMachine);
  return fieldSays([&] { loadMachine(o); });
}

TEST(Quantities, BoundsAreInclusiveOrOpenAsDeclaredAndNonFiniteIsRefused) {
  EXPECT_EQ(outOfRange(Quantity::Position, 1e5), "");
  EXPECT_EQ(outOfRange(Quantity::Position, -1e5), "");
  EXPECT_NE(outOfRange(Quantity::Position, 100000.001), "");
  EXPECT_EQ(outOfRange(Quantity::Length, 0.0), "");
  EXPECT_NE(outOfRange(Quantity::Length, -1e-9), "");
  EXPECT_NE(outOfRange(Quantity::BarLength, 0.0), "");  // a bar has a length
  EXPECT_EQ(outOfRange(Quantity::BarLength, 1e5), "");
  EXPECT_EQ(outOfRange(Quantity::PartRotation, -360.0), "");
  EXPECT_NE(outOfRange(Quantity::PartRotation, 360.5), "");
  EXPECT_EQ(outOfRange(Quantity::ProfileTolerance, 1.0), "");
  EXPECT_NE(outOfRange(Quantity::ProfileTolerance, 0.0), "");
  EXPECT_NE(outOfRange(Quantity::ProfileTolerance, 900.0), "");
  EXPECT_EQ(outOfRange(Quantity::ProfileTolerance, 900.0, /*confirmed=*/true), "");
  EXPECT_EQ(outOfRange(Quantity::SpindleTilt, 1e5), "");
  EXPECT_NE(outOfRange(Quantity::SpindleTilt, -1.0), "");
  for (Quantity q : {Quantity::Position, Quantity::Length, Quantity::BarLength,
                     Quantity::PartRotation, Quantity::ProfileTolerance, Quantity::SpindleTilt}) {
    EXPECT_NE(outOfRange(q, NAN), "");
    EXPECT_NE(outOfRange(q, INFINITY), "");
    EXPECT_NE(outOfRange(q, -INFINITY), "");
    EXPECT_NE(outOfRange(q, INFINITY, true), "");
  }
  // The message says what was expected and what was found, whole numbers written out.
  EXPECT_EQ(outOfRange(Quantity::Length, -3.0),
            "expected a gauge or tool length from 0 to 100000 mm, found -3");
  EXPECT_NE(outOfRange(Quantity::ProfileTolerance, 30.0).find("0.03 for 30 um"), std::string::npos);
}

TEST(Quantities, ASetUpValueIsRefusedInTheFileExactlyWhereTheOptionRefusesIt) {
  struct Case {
    std::string file_line;
    MachineOptions option;
    bool accepted;
  };
  auto zero = [](double y) {
    MachineOptions o;
    o.part_zero = {0.0, y, 0.0};
    return o;
  };
  auto rotation = [](double d) {
    MachineOptions o;
    o.part_rotation_deg = d;
    return o;
  };
  auto gauge = [](double l) {
    MachineOptions o;
    o.gauge_length = l;
    return o;
  };
  const Case cases[] = {
      {"part_zero_mm = 0, 100000, 0", zero(1e5), true},
      {"part_zero_mm = 0, 100000.5, 0", zero(100000.5), false},
      {"part_zero_mm = 0, -2e5, 0", zero(-2e5), false},
      {"part_rotation_deg = 360", rotation(360.0), true},
      {"part_rotation_deg = -361", rotation(-361.0), false},
      {"gauge_length_mm = 0", gauge(0.0), true},
      {"gauge_length_mm = 100000", gauge(1e5), true},
      {"gauge_length_mm = 1e5", gauge(1e5), true},  // an exponent reads the same everywhere
      {"gauge_length_mm = -3", gauge(-3.0), false},
      {"gauge_length_mm = 100001", gauge(100001.0), false},
  };
  for (const Case& c : cases) {
    const std::string file = setupFileSays(c.file_line);
    const std::string option = loadSays(c.option);
    EXPECT_EQ(file.empty(), c.accepted) << c.file_line << ": " << file;
    EXPECT_EQ(option.empty(), c.accepted) << c.file_line << ": " << option;
    if (!c.accepted) {
      // The same clause in both, the file's with its line.
      const std::string clause = option.substr(option.find(": ") + 2);
      EXPECT_NE(file.find(clause), std::string::npos) << file << " / " << option;
      EXPECT_NE(file.find("setup.txt:1"), std::string::npos) << file;
    }
  }
  // A tool length and a work offset follow the same quantities.
  EXPECT_EQ(setupFileSays("tool_h3_mm = 100000"), "");
  EXPECT_NE(setupFileSays("tool_h3_mm = -1"), "");
  EXPECT_NE(setupFileSays("g54_mm = 0, 0, 1e6"), "");
  EXPECT_EQ(setupFileSays("g54_mm = 0, 0, -1e5"), "");
  // And the set-up search's gauge lengths.
  SetupInputs s;
  s.machine.machine = sourcePath(kMachine);
  s.gauge_lengths = {100001.0};
  const std::string search = fieldSays([&] { proposeSetup(s); });
  EXPECT_NE(search.find("gauge_lengths: " + outOfRange(Quantity::Length, 100001.0)),
            std::string::npos)
      << search;
}

TEST(Quantities, AProfileToleranceIsRefusedInZoneAndJobsFilesAsOnTheCommandLine) {
  const std::string zones_900 = "region,tolerance\nall,900\n";
  const std::string jobs_900 = "name,machine,cl,tolerance\na,m.xml,p.apt,900\n";
  EXPECT_THROW(parseZoneCsv(zones_900, "zones.csv"), InputError);
  EXPECT_THROW(parseJobsCsv(jobs_900, "jobs.csv"), InputError);
  try {
    parseJobsCsv(jobs_900, "jobs.csv");
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("jobs.csv:2"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("0.9 for 900 um"), std::string::npos) << e.what();
  }
  VerifyInputs v;
  v.machine.machine = sourcePath(kMachine);
  v.program.cl = sourcePath("samples/nas979_cone.apt");
  v.tolerance_mm = 900.0;
  v.report_dir = ::testing::TempDir() + "/quantities_verify";
  const std::string option = fieldSays([&] { verifyPart(v); });
  EXPECT_NE(option.find("tolerance_mm: " + outOfRange(Quantity::ProfileTolerance, 900.0)),
            std::string::npos)
      << option;
  // Confirmed, all three take it; at the bound, all three take it unconfirmed.
  EXPECT_NO_THROW(parseZoneCsv(zones_900, "zones.csv", /*large_confirmed=*/true));
  EXPECT_NO_THROW(parseJobsCsv(jobs_900, "jobs.csv", /*large_confirmed=*/true));
  EXPECT_NO_THROW(parseZoneCsv("region,tolerance\nall,1\n", "zones.csv"));
  EXPECT_NO_THROW(parseJobsCsv("name,machine,cl,tolerance\na,m.xml,p.apt,1\n", "jobs.csv"));
  // Zero and negative tolerances: refused in both files.
  EXPECT_THROW(parseZoneCsv("region,tolerance\nall,0\n", "zones.csv"), InputError);
  EXPECT_THROW(parseJobsCsv("name,machine,cl,tolerance\na,m.xml,p.apt,-0.1\n", "jobs.csv"),
               InputError);
}

TEST(Quantities, ABarLengthIsRefusedInTheReadingsFileAsInThePlan) {
  const Machine m = readMachineFile(sourcePath(kMachine));
  std::string header =
      "setup,table_ball_x_mm,table_ball_y_mm,table_ball_z_mm,tool_ball_x_mm,"
      "tool_ball_y_mm,tool_ball_z_mm";
  std::string row = "1,0,0,0,0,0,100";
  for (const Axis& a : m.model.axes) {
    header += "," + toLower(a.name) + (a.isRotary() ? "_deg" : "_mm");
    row += ",0";
  }
  auto readings = [&](const std::string& length) {
    try {
      parseBallbarCsv(header + ",length_mm\n" + row + "," + length + "\n", "readings.csv", m.model,
                      true);
      return std::string();
    } catch (const InputError& e) {
      return std::string(e.what());
    }
  };
  // (planBallbar checks its lengths first: the refusals need no plan; the bound is the same
  // outOfRange the file's 100000 passes.)
  auto plan = [&](double length) {
    PlanBallbarInputs in;
    in.machine.machine = sourcePath(kMachine);
    in.lengths_mm = {length};
    return fieldSays([&] { planBallbar(in); });
  };
  EXPECT_EQ(readings("100000"), "");
  for (double bad : {0.0, -100.0, 200000.0}) {
    const std::string file = readings(formatNumber(bad));
    const std::string option = plan(bad);
    EXPECT_NE(file.find(outOfRange(Quantity::BarLength, bad)), std::string::npos) << file;
    EXPECT_NE(file.find("readings.csv:2"), std::string::npos) << file;
    EXPECT_NE(option.find("lengths_mm: " + outOfRange(Quantity::BarLength, bad)), std::string::npos)
        << option;
  }
  // A ball position beyond any machine, in the file: a position's range.
  std::string far = row;
  far.replace(far.find("0,0,0"), 5, "0,2e5,0");
  EXPECT_THROW(parseBallbarCsv(header + "\n" + far + "\n", "plan.csv", m.model, false), InputError);
}

TEST(Quantities, ASpindleTiltIsRefusedByCalibrateAsByTheMachineFile) {
  CalibrateInputs in;
  in.machine.machine = sourcePath(kMachine);
  in.spindle_tilt_urad = 2e5;
  const std::string option = fieldSays([&] { calibrateMachine(in); });
  EXPECT_NE(option.find("spindle_tilt_urad: " + outOfRange(Quantity::SpindleTilt, 2e5)),
            std::string::npos)
      << option;
}

TEST(Numbers, OneRuleForEveryReaderExponentsReadNoHexInfOrNan) {
  for (const char* good : {"1e5", "1E5", "-1.5e-3", "+2.", ".5", "100000"})
    EXPECT_TRUE(parseNumber(good).has_value()) << good;
  for (const char* bad :
       {"nan", "inf", "-inf", "0x10", "0x1p3", "1_0", "1,5", "1e", "e5", "--1", "1e400", ""})
    EXPECT_FALSE(parseNumber(bad).has_value()) << bad;
  EXPECT_EQ(*parseNumber("1e5"), 100000.0);
  EXPECT_EQ(*parseNumber("+1.5"), 1.5);
  EXPECT_EQ(*parseNumber("1e-400"), 0.0);  // below a double: 0, as strtod reads it
  EXPECT_FALSE(parseNumber("+-1").has_value());
  EXPECT_FALSE(parseNumber("-+1").has_value());
  // The same double as strtod (correctly rounded both) on random decimal texts.
  std::mt19937 rng(5);
  std::uniform_int_distribution<int> digit(0, 9), length(1, 19), exponent(-30, 30), coin(0, 1);
  for (int k = 0; k < 100000; ++k) {
    std::string t = coin(rng) ? "-" : "";
    const int n = length(rng), point = std::uniform_int_distribution<int>(0, n)(rng);
    for (int d = 0; d < n; ++d) {
      if (d == point) t += '.';
      t += static_cast<char>('0' + digit(rng));
    }
    if (coin(rng)) t += "e" + std::to_string(exponent(rng));
    const auto v = parseNumber(t);
    ASSERT_TRUE(v.has_value()) << t;
    const double want = std::strtod(t.c_str(), nullptr);
    EXPECT_EQ(*v, want) << t;
    EXPECT_EQ(std::signbit(*v), std::signbit(want)) << t;  // -0.000 reads as -0
  }
  // Where the plain-decimal fast path ends (io/common/text_util.cpp): 2^53 and one above, 22 and
  // 23 decimals, 19 and 20 digits.
  for (const char* t : {"9007199254740992", "9007199254740993", "-9007199254740993.0",
                        "0.0000000000000000000001", "0.00000000000000000000001",
                        "1234567890123456789", "12345678901234567890", "-0.000", "+0.5e0"}) {
    const auto v = parseNumber(t);
    ASSERT_TRUE(v.has_value()) << t;
    EXPECT_EQ(*v, std::strtod(t, nullptr)) << t;
    EXPECT_EQ(std::signbit(*v), std::signbit(std::strtod(t, nullptr))) << t;
  }
}

}  // namespace
}  // namespace tolver
