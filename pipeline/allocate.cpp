// The allocate pipeline: see pipeline/allocate.h.
#include "pipeline/allocate.h"

#include "io/common/io_error.h"
#include "io/machine/tolerance_file.h"
#include "io/report/allocation_report.h"

namespace tolver {

AllocationRun runAllocation(const AllocateInputs& in) {
  AllocationRun run;
  run.machine = loadMachine(in.machine);
  const MachineModel& m = run.machine.model;
  run.terms = readToleranceFile(in.tolerances, m);
  for (auto& t : run.terms) {
    if (!std::isnan(in.lower_factor)) t.lower = in.lower_factor * t.standard;
    if (!std::isnan(in.upper_factor)) t.upper = in.upper_factor * t.standard;
    if (t.lower > t.upper)
      throw InputError(in.tolerances, 0, 0, "bounds", t.name + ": lower bound above upper bound");
  }
  const std::vector<double>& l = in.limits_mm;
  if (l.size() != 3 || !(l[0] > 0 && l[1] > 0 && l[2] > 0))
    throw FieldError("limits_mm", "expected three positive values dx,dy,dz in mm");
  if (in.cost.size() != 4) throw FieldError("cost", "expected h_p,h_a,h_d,r");
  AllocationModel& a = run.model;
  a.limits = Eigen::Vector3d(l[0], l[1], l[2]);
  a.h_p = in.cost[0];
  a.h_a = in.cost[1];
  a.h_d = in.cost[2];
  a.r = in.cost[3];
  a.rss = in.rss;
  a.loss_weight = in.loss_weight;
  a.loss_normal = in.loss_normal;
  run.accuracy = buildAccuracyModel(m, run.terms, workspaceGrid(m, in.grid, in.rotary_grid));
  run.correlation = correlateTerms(run.accuracy, in.groups);
  run.result = allocateTolerances(m, run.terms, a, run.accuracy, run.correlation, in.opt);
  Eigen::VectorXd t_ref(run.terms.size());
  run.reference_complete = !run.terms.empty();
  for (size_t i = 0; i < run.terms.size(); ++i) {
    t_ref[i] = run.terms[i].reference;
    run.reference_complete &= !std::isnan(t_ref[i]);
  }
  if (run.reference_complete) {
    run.reference_worst = verifyAccuracy(m, run.terms, run.accuracy, t_ref, a.rss);
    run.reference_cost = manufacturingCost(m, run.terms, t_ref, a);
  }
  return run;
}

AllocationRun allocate(const AllocateInputs& in) {
  if (in.report_dir.empty()) throw FieldError("report_dir", "give the report directory");
  AllocationRun run = runAllocation(in);
  writeAllocation(run, in, in.report_dir);
  run.verdict = run.result.chosen >= 0 ? Verdict::Ok : Verdict::NotMet;
  return run;
}

void writeAllocation(const AllocationRun& run, const AllocateInputs& in,
                     const std::string& report_dir_path) {
  const MachineModel& m = run.machine.model;
  ReportDirectory report_dir(report_dir_path);  // written as a whole, swapped in at the end
  writeAllocationReport(report_dir.staging(), m, run.terms, run.model, run.result,
                        {in.machine.machine, in.tolerances, m.setup.gauge_length,
                         static_cast<int>(run.accuracy.poses.size()), in.opt});
  report_dir.commit();
}

}  // namespace tolver
