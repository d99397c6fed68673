#pragma once
// Reports of a tolerance allocation: a table like [Cai]'s Table 4, the Pareto front (CSV and
// PNG), JSON and a self-contained HTML page. All files are written atomically into a directory.
#include <string>
#include <vector>

#include "core/allocation/tolerance_allocation.h"

namespace tolver {

struct AllocationReportInputs {
  std::string machine_file, tolerance_file;
  double gauge_length = 0;
  int poses = 0;
  AllocationOptions options;
};

// Writes report.json, report.html, allocation.csv, pareto.csv and pareto.png into dir.
void writeAllocationReport(const std::string& dir, const MachineModel& m,
                           const std::vector<ToleranceTerm>& terms, const AllocationModel& a,
                           const AllocationResult& r, const AllocationReportInputs& in);

// A term's tolerance in the unit people quote it in: mm for lengths, mm/m for angles.
double displayValue(const MachineModel& m, const ToleranceTerm& t, double value);
const char* displayUnit(const MachineModel& m, const ToleranceTerm& t);

}  // namespace tolver
