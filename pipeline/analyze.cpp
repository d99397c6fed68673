#include "pipeline/analyze.h"

#include "core/calibration/ballbar.h"
#include "core/calibration/calibration.h"
#include "io/common/io_error.h"
#include "io/machine/ballbar_file.h"

namespace tolver {

AnalysisRun analyze(const AnalyzeInputs& in) {
  if (in.model != "link" && in.model != "motion")
    throw FieldError("model", "expected link or motion");
  if (in.degree > 20) throw FieldError("degree", "expected a degree from 0 to 20");
  if (in.poses < 0 || in.poses > 100000) throw FieldError("poses", "expected 1 to 100000 poses");
  AnalysisRun run;
  Machine machine = loadMachine(in.machine);
  run.model = in.degree >= 0 ? withMotionDegree(machine.model, in.degree) : machine.model;
  const MachineModel& m = run.model;
  run.poses = in.poses > 0 ? in.poses : (in.model == "link" ? 30 : 600);
  run.columns = modelColumns(m, in.model);
  auto pref = m.preferred.find(in.model);
  const std::vector<int> preferred = pref == m.preferred.end() ? std::vector<int>{} : pref->second;
  run.minimal = minimalSetForModel(m, randomPoses(m, run.poses, in.seed), run.columns, preferred);
  if (in.plan.empty()) return run;

  run.with_plan = true;
  PlanIdentifiability& p = run.plan;
  const BallbarFile plan = readBallbarFile(in.plan, machine.model, false);
  const std::vector<int> unknowns = defaultCalibrationUnknowns(machine.model);
  const ForwardKinematics fk(machine.model, machine.params);
  const int np = static_cast<int>(unknowns.size());
  const int n = np + 6 * static_cast<int>(plan.test.setups.size());
  const Eigen::MatrixXd J = identificationJacobian(
      fk, plan.test, std::vector<BallErrors>(plan.test.setups.size()), unknowns);
  std::vector<int> idx(n);
  std::vector<bool> protect(n);
  for (int c = 0; c < n; ++c) {
    idx[c] = c;
    protect[c] = c >= np;
  }
  p.file = in.plan;
  p.readings = plan.test.readings.size();
  p.setups = plan.test.setups.size();
  p.unknowns = n;
  p.machine_unknowns = np;
  p.minimal = selectMinimalSet(J, idx, protect, {});
  for (int c : p.minimal.removed)
    p.unobservable.push_back(c < np ? machine.model.parameters[unknowns[c]].iso_code : "ball");
  return run;
}

}  // namespace tolver
