// The files a calibration writes predict what its report says: on every shipped machine and
// both set-up styles (tool balls off the spindle axis, all tool balls on it), the machine file
// and the ball positions, written and read back, reproduce the in-memory fit's residuals of the
// fitted and the held-out readings to 1e-6 mm.
#include <gtest/gtest.h>

#include <random>

#include "core/calibration/ballbar_plan.h"
#include "core/calibration/calibration.h"
#include "io/common/io_error.h"
#include "io/machine/ballbar_file.h"
#include "io/machine/machine_file.h"
#include "io/report/calibration_report.h"
#include "test_support.h"

namespace tolver {
namespace {

class WrittenFiles : public test::TempDirTest,
                     public ::testing::WithParamInterface<std::tuple<const char*, bool>> {};

TEST_P(WrittenFiles, ReproduceTheFitAndTheHeldOutReadings) {
  const auto [machine_file, on_axis] = GetParam();
  const Machine m = readMachineFile(test::sourcePath(machine_file));
  const std::vector<int> unknowns = defaultCalibrationUnknowns(m.model);
  BallbarPlanOptions o;
  o.poses = static_cast<int>(3 * (unknowns.size() + 18) + 60);
  o.seed = 11;
  o.geometry = defaultBallbarSetups(3);
  if (on_axis)
    for (BallbarSetup& s : o.geometry) s.tool_ball_t = Eigen::Vector3d(0, 0, 0);
  BallbarTest all = planBallbarTest(m.model, unknowns, o).test;
  ASSERT_GT(all.readings.size(), 100u);
  // A truth with every parameter a few um / urad, and ball errors of 10 um.
  std::mt19937 rng(5);
  std::normal_distribution<double> n(0.0, 1.0);
  Eigen::VectorXd truth(m.model.parameterCount());
  for (int p = 0; p < truth.size(); ++p)
    truth[p] = n(rng) * (m.model.parameters[p].angular ? 5e-6 : 3e-3);
  std::vector<BallErrors> balls(3);
  for (BallErrors& b : balls) {
    b.table_w = Eigen::Vector3d(n(rng), n(rng), n(rng)) * 0.01;
    b.tool_t = Eigen::Vector3d(n(rng), n(rng), n(rng)) * 0.01;
  }
  const ForwardKinematics fk(m.model, truth);
  for (BallbarReading& r : all.readings)
    r.length =
        ballbarLength(fk, r.q, all.setups[r.setup], balls[r.setup], &r.context) + 0.5e-3 * n(rng);
  // Every fifth reading held out.
  BallbarTest fit = all, held = all;
  fit.readings.clear();
  held.readings.clear();
  for (size_t i = 0; i < all.readings.size(); ++i)
    (i % 5 == 4 ? held : fit).readings.push_back(all.readings[i]);
  const CalibrationResult r = calibrate(m.model, m.params, fit, unknowns);
  ASSERT_TRUE(r.status == CalibrationStatus::Converged) << r.message;
  if (on_axis) EXPECT_FALSE(r.held.empty());  // the spindle's roll is not seen

  Machine identified = m;
  identified.params = r.params;
  writeFileAtomically(path("m.xml"), formatMachineXml(identified, "test"));
  writeFileAtomically(path("b.csv"),
                      formatBallPositionsCsv(fit, r.ball_errors, &r.ball_uncertainty, {"test"}));
  const WrittenCheck c = checkWrittenFiles(path("m.xml"), path("b.csv"), fit, held);
  const ForwardKinematics fk_mem(m.model, r.params);
  const Eigen::VectorXd held_mem = ballbarResiduals(fk_mem, held, r.ball_errors);
  EXPECT_NEAR(c.fit.rms, r.rms_residual, 1e-6);
  EXPECT_NEAR(c.fit.max, r.max_residual, 1e-6);
  EXPECT_NEAR(c.heldout.rms, residualStats(held_mem).rms, 1e-6);
  // Per reading, too.
  const Machine back = readMachineFile(path("m.xml"));
  const std::vector<BallErrors> b_back = readBallPositionsFile(path("b.csv"), fit);
  const Eigen::VectorXd fit_back =
      ballbarResiduals(ForwardKinematics(back.model, back.params), fit, b_back);
  EXPECT_LT((fit_back - r.residuals).cwiseAbs().maxCoeff(), 1e-6);
  // And the held-out readings are predicted near the noise (the fit generalises), not at the
  // machine's error.
  EXPECT_LT(c.heldout.rms, 3 * 0.5e-3) << machine_file;
}

INSTANTIATE_TEST_SUITE_P(ShippedMachines, WrittenFiles,
                         ::testing::Combine(::testing::ValuesIn(test::shippedMachines()),
                                            ::testing::Bool()),
                         [](const auto& info) {
                           std::string s = std::get<0>(info.param);
                           s = s.substr(s.rfind('/') + 1);
                           s = s.substr(0, s.find('.'));
                           return s + (std::get<1>(info.param) ? "_tool_balls_on_axis"
                                                               : "_tool_balls_off_axis");
                         });

}  // namespace
}  // namespace tolver
