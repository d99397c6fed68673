#include "core/kinematics/sensitivity_jacobian.h"

#include <gtest/gtest.h>

#include <random>

#include "io/machine/machine_file.h"
#include "test_support.h"
#include "twist_support.h"

namespace tolver {
namespace {

using test::twistBetween;

class EveryMachine : public ::testing::TestWithParam<const char*> {};

// Each column against central finite differences of the exact forward model, at random poses
// and random non-zero parameters (so the exact parametrisation map M(v) is exercised).
TEST_P(EveryMachine, MatchesCentralFiniteDifferences) {
  Machine m = readMachineFile(test::sourcePath(GetParam()));
  m.model.setup.gauge_length = 120;
  m.model.setup.part_zero_table = Eigen::Vector3d(20, -10, 40);
  std::mt19937 rng(17);
  std::normal_distribution<double> n(0.0, 1.0);
  for (int i = 0; i < m.model.parameterCount(); ++i)
    m.params[i] = n(rng) * (m.model.parameters[i].angular ? 2e-3 : 0.05);
  const int np = m.model.parameterCount();
  Eigen::MatrixXd J(6, np);
  for (int pose = 0; pose < 20; ++pose) {
    JointVector q(m.model.axes.size());
    for (size_t a = 0; a < m.model.axes.size(); ++a) {
      std::uniform_real_distribution<double> u(m.model.axes[a].travel_min,
                                               m.model.axes[a].travel_max);
      q[a] = u(rng);
    }
    const ForwardKinematics fk(m.model, m.params);
    sensitivityJacobian(fk, q, J);
    const Eigen::Isometry3d T0 = fk.w_T_t(q);
    for (int i = 0; i < np; ++i) {
      const double h = m.model.parameters[i].angular ? 1e-6 : 1e-5;
      Eigen::VectorXd pp = m.params, pm = m.params;
      pp[i] += h;
      pm[i] -= h;
      const Vector6d fd = (twistBetween(T0, ForwardKinematics(m.model, pp).w_T_t(q)) -
                           twistBetween(T0, ForwardKinematics(m.model, pm).w_T_t(q))) /
                          (2 * h);
      EXPECT_LT((fd - J.col(i)).norm(), 1e-5 * (1.0 + J.col(i).norm()))
          << GetParam() << " " << m.model.parameters[i].iso_code << "\n"
          << fd.transpose() << "\n"
          << J.col(i).transpose();
    }
  }
}

// The row form (what a ball-bar reading uses) is w times the Jacobian, column for column, for
// random rows w, poses and non-zero parameters.
TEST_P(EveryMachine, RowIsTheJacobianContracted) {
  Machine m = readMachineFile(test::sourcePath(GetParam()));
  std::mt19937 rng(23);
  std::normal_distribution<double> n(0.0, 1.0);
  for (int i = 0; i < m.model.parameterCount(); ++i)
    m.params[i] = n(rng) * (m.model.parameters[i].angular ? 2e-3 : 0.05);
  const ForwardKinematics fk(m.model, m.params);
  const int np = m.model.parameterCount();
  Eigen::MatrixXd J(6, np);
  Eigen::RowVectorXd row(np);
  for (int pose = 0; pose < 20; ++pose) {
    JointVector q(m.model.axes.size());
    for (size_t a = 0; a < m.model.axes.size(); ++a) {
      std::uniform_real_distribution<double> u(m.model.axes[a].travel_min,
                                               m.model.axes[a].travel_max);
      q[a] = u(rng);
    }
    Eigen::Matrix<double, 1, 6> w;
    for (int k = 0; k < 6; ++k) w[k] = n(rng);
    sensitivityJacobian(fk, q, J);
    sensitivityRow(fk, q, w, row);
    const Eigen::RowVectorXd truth = w * J;
    EXPECT_LT((row - truth).cwiseAbs().maxCoeff(), 1e-12 * (1.0 + truth.cwiseAbs().maxCoeff()))
        << GetParam();
  }
}

INSTANTIATE_TEST_SUITE_P(Shipped, EveryMachine, ::testing::ValuesIn(test::shippedMachines()));

TEST(SensitivityJacobian, LinkTwistMapIsTheIdentityAtZero) {
  EXPECT_TRUE(linkTwistMap(Vector6d::Zero()).isIdentity(0.0));
}

}  // namespace
}  // namespace tolver
