#pragma once
// The jobs file of `tolver verify --batch` (CSV, io/common/text_util's policy):
//   name,machine,cl,part,tolerance[,setup,zones,probed]
// one job per row; name a plain file name, unique (it names the job's report directory);
// tolerance in mm (may be empty when the row gives zones); paths relative to the jobs file's
// folder. The tolerance is checked as --tolerance is (checkToleranceSize; large_confirmed: the
// user confirmed that tolerances above 1 mm are meant). Throws InputError naming file, line and
// column.
#include <cmath>
#include <string>
#include <vector>

namespace tolver {

struct VerifyJob {
  int line = 0;  // row in the jobs file
  std::string name;
  std::string machine, setup, probed, cl, part, zones;  // resolved paths ("" when not given)
  double tolerance_mm = NAN;
};

std::vector<VerifyJob> parseJobsCsv(const std::string& text, const std::string& file,
                                    bool large_confirmed = false);
std::vector<VerifyJob> readJobsFile(const std::string& path, bool large_confirmed = false);

}  // namespace tolver
