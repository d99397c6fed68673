#pragma once
// The allocate pipeline as library functions: tolerances of the machine's geometric errors at
// least cost under an accuracy limit (Cai et al. [Cai], NSGA-II over cost + quality loss and
// tolerance spread), and the report directory. `tolver allocate` parses and prints.
#include <cmath>
#include <string>
#include <vector>

#include "core/allocation/tolerance_allocation.h"
#include "pipeline/command.h"
#include "pipeline/inputs.h"

namespace tolver {

struct AllocateInputs {
  MachineOptions machine;
  std::string tolerances;                              // tolerance file (CSV)
  std::vector<double> limits_mm{0.015, 0.015, 0.010};  // allowed |dx|, |dy|, |dz| of the tool tip
  std::vector<double> cost{3, 4, 5, 2};                // h_p, h_a, h_d, r of the cost model
  bool rss = false;          // errors combined root-sum-square (else worst case)
  bool loss_normal = false;  // quality loss for t = 3 sigma (else uniform)
  double loss_weight = 1.0;
  double lower_factor = NAN, upper_factor = NAN;  // bounds = factor x standard (NAN: the file's)
  int grid = 3, rotary_grid = 5, groups = 4;      // workspace grid, correlation groups
  AllocationOptions opt;                          // NSGA-II population, generations, seed
  std::string report_dir;                         // where allocate() writes the reports
};

struct AllocationRun {
  Machine machine;
  std::vector<ToleranceTerm> terms;
  AllocationModel model;
  AccuracyModel accuracy;
  CorrelationAnalysis correlation;
  AllocationResult result;
  // The published allocation (every term's reference given): its cost and worst deviation.
  bool reference_complete = false;
  double reference_cost = 0;
  Eigen::Vector3d reference_worst = Eigen::Vector3d::Zero();
  Verdict verdict = Verdict::Ok;  // NotMet: no allocation within the bounds meets the limits
};

// tolver allocate: allocates and writes the report directory. Throws InputError.
AllocationRun allocate(const AllocateInputs& in);

// Reads the machine and the tolerance file and allocates. Throws InputError.
AllocationRun runAllocation(const AllocateInputs& in);
// Writes report.json, report.html, allocation.csv, pareto.csv and pareto.png into report_dir,
// staged and swapped in as a whole.
void writeAllocation(const AllocationRun& run, const AllocateInputs& in,
                     const std::string& report_dir);

}  // namespace tolver
