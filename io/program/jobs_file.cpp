#include "io/program/jobs_file.h"

#include <algorithm>
#include <filesystem>

#include "io/common/io_error.h"
#include "io/common/text_util.h"
#include "io/machine/zone_file.h"

namespace tolver {

std::vector<VerifyJob> parseJobsCsv(const std::string& text, const std::string& file,
                                    bool large_confirmed) {
  namespace fs = std::filesystem;
  const fs::path root = fs::path(file).parent_path();
  auto resolve = [&](const std::string& p) {
    if (p.empty() || fs::path(p).is_absolute()) return p;
    return (root / p).string();
  };
  std::vector<VerifyJob> jobs;
  forEachCsvRow(
      text, file, {"name", "machine", "cl", "tolerance"},
      "missing column (name,machine,cl,part,tolerance[,setup,zones,probed])",
      [&](const CsvRow& row) {
        VerifyJob j;
        j.line = row.line;
        j.machine = resolve(row.cell("machine"));
        j.setup = resolve(row.cell("setup"));
        j.probed = resolve(row.cell("probed"));
        j.cl = resolve(row.cell("cl"));
        j.part = resolve(row.cell("part"));
        j.zones = resolve(row.cell("zones"));
        const auto tol = parseNumber(row.cell("tolerance"));
        if (!tol && j.zones.empty())
          throw InputError(file, row.line, row.column("tolerance"), "tolerance",
                           "'" + row.cell("tolerance") + "' is not a number");
        if (tol) checkToleranceSize(*tol, large_confirmed, file, row.line, row.column("tolerance"));
        j.tolerance_mm = tol ? *tol : NAN;
        j.name = row.cell("name");
        if (j.name.empty() || j.name.find('/') != std::string::npos || j.name == "." ||
            j.name == "..")
          throw InputError(file, row.line, row.column("name"), "name",
                           "a job name is a plain file name");
        // Two jobs of one name would write one directory, one report lost.
        if (std::any_of(jobs.begin(), jobs.end(),
                        [&](const VerifyJob& o) { return o.name == j.name; }))
          throw InputError(file, row.line, row.column("name"), "name",
                           "job '" + j.name + "' is named twice: each job needs its own name");
        jobs.push_back(j);
      });
  if (jobs.empty()) throw InputError(file, 0, 0, "jobs", "the file lists no job");
  return jobs;
}

std::vector<VerifyJob> readJobsFile(const std::string& path, bool large_confirmed) {
  return parseJobsCsv(readFile(path), path, large_confirmed);
}

}  // namespace tolver
