#pragma once
// tolver analyze as a library function: identifiability of a machine's error model ([AM01] 3.6,
// 4.7; Tables 3.2-3.4, 4.1-4.3), and of a ball-bar plan's identification Jacobian.
#include <string>
#include <vector>

#include "core/calibration/identifiability.h"
#include "pipeline/command.h"
#include "pipeline/inputs.h"

namespace tolver {

struct AnalyzeInputs {
  MachineOptions machine;
  std::string model =
      "motion";     // "link" (thesis ch. 3) or "motion" (Chebyshev motion errors, ch. 4)
  int degree = -1;  // Chebyshev degree of every motion error; < 0: the file's
  int poses = 0;    // random poses; 0: 30 for link, 600 for motion
  unsigned seed = 1;
  std::string plan;  // a ball-bar plan or readings (CSV) to analyse as well, or empty
};

struct PlanIdentifiability {
  std::string file;
  size_t readings = 0, setups = 0;
  int unknowns = 0, machine_unknowns = 0;  // machine + 6 per set-up
  MinimalSet minimal;                      // of the identification Jacobian's columns
  std::vector<std::string> unobservable;   // ISO codes ("ball" for a ball coordinate)
};

struct AnalysisRun {
  MachineModel model;  // at the asked degree
  int poses = 0;
  std::vector<int> columns;  // the parameters of the asked model
  MinimalSet minimal;        // confounded groups, removals, the minimal-complete set
  bool with_plan = false;
  PlanIdentifiability plan;
  Verdict verdict = Verdict::Ok;
};

// Throws InputError (FieldError "model", "degree", "poses").
AnalysisRun analyze(const AnalyzeInputs& in);

}  // namespace tolver
