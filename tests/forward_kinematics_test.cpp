#include "core/kinematics/forward_kinematics.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "core/numerics/lanes.h"
#include "io/machine/machine_file.h"
#include "test_support.h"

namespace tolver {
namespace {

Machine matsuura() { return readMachineFile(test::sourcePath(test::shippedMachines()[0])); }

JointVector joints(double x, double y, double z, double a, double c) {
  JointVector q(5);
  q << x, y, z, a, c;  // file order: X Y Z A C
  return q;
}

// Nominal ZFYXAC chain written out by hand: F_T_w = trans(y) trans(x) rot_x(a) rot_z(c) T_w,
// F_T_t = trans(z) trans(-L k).
Eigen::Isometry3d handNominal(const JointVector& q, const PartSetup& s) {
  const Eigen::Vector3d i = Eigen::Vector3d::UnitX(), j = Eigen::Vector3d::UnitY(),
                        k = Eigen::Vector3d::UnitZ();
  Eigen::Isometry3d Tw = Eigen::Isometry3d::Identity();
  Tw.translation() = s.part_zero_table;
  Tw.linear() = Eigen::AngleAxisd(s.part_rotation, k).toRotationMatrix();
  const Eigen::Isometry3d F_T_w =
      translation(j, q[1]) * translation(i, q[0]) * rotation(i, q[3]) * rotation(k, q[4]) * Tw;
  const Eigen::Isometry3d F_T_t = translation(k, q[2]) * translation(k, -s.gauge_length);
  return F_T_w.inverse() * F_T_t;
}

TEST(ForwardKinematics, ZeroErrorsReproduceTheNominalPoseExactly) {
  Machine m = matsuura();
  m.model.setup.part_zero_table = Eigen::Vector3d(12.5, -30.0, 45.0);
  m.model.setup.part_rotation = 0.3;
  m.model.setup.gauge_length = 110.0;
  const ForwardKinematics fk(m.model, Eigen::VectorXd::Zero(m.model.parameterCount()));
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int n = 0; n < 500; ++n) {
    const JointVector q =
        joints(380 * u(rng), 255 * u(rng), 200 * u(rng), 1.5 * u(rng), 3 * u(rng));
    const Eigen::Isometry3d a = fk.w_T_t(q), b = handNominal(q, m.model.setup);
    EXPECT_LT((a.matrix() - b.matrix()).cwiseAbs().maxCoeff(), 1e-12);
  }
}

// The vector-carrying hot path agrees with the composed transform, for every shipped machine
// and the nutating-head fixture, with random errors everywhere.
TEST(ForwardKinematics, TipAndAxisMatchTheComposedPose) {
  std::mt19937 rng(8);
  std::normal_distribution<double> n(0.0, 1.0);
  for (const char* file : test::kinematicsTestMachines()) {
    Machine m = readMachineFile(test::sourcePath(file));
    for (int i = 0; i < m.model.parameterCount(); ++i)
      m.params[i] = n(rng) * (m.model.parameters[i].angular ? 1e-4 : 0.02);
    m.model.setup.gauge_length = 90;
    m.model.setup.part_zero_table = Eigen::Vector3d(5, 6, 7);
    const ForwardKinematics fk(m.model, m.params);
    for (int k = 0; k < 200; ++k) {
      JointVector q(m.model.axes.size());
      for (size_t a = 0; a < m.model.axes.size(); ++a) {
        std::uniform_real_distribution<double> u(m.model.axes[a].travel_min,
                                                 m.model.axes[a].travel_max);
        q[a] = u(rng);
      }
      Eigen::Vector3d p, u;
      fk.tipAndAxis(q, &p, &u);
      const Eigen::Isometry3d T = fk.w_T_t(q);
      EXPECT_LT((p - T.translation()).norm(), 1e-10) << file;
      EXPECT_LT((u - T.linear().col(2)).norm(), 1e-13) << file;
    }
  }
}

// The batch carry (four configurations side by side) gives tipAndAxis's bits, on every machine
// it applies to, for a count that is not a multiple of four, and with some error angles beyond
// the small-angle series (1 to 5 mrad: those lanes are recomputed one by one).
TEST(ForwardKinematics, BatchEqualsOneByOneBitForBit) {
  std::mt19937 rng(21);
  std::normal_distribution<double> n(0.0, 1.0);
  int batchable = 0;
  for (const char* file : test::kinematicsTestMachines()) {
    for (double angular : {20e-6, 2e-3}) {
      Machine m = readMachineFile(test::sourcePath(file));
      for (int i = 0; i < m.model.parameterCount(); ++i)
        m.params[i] = n(rng) * (m.model.parameters[i].angular ? angular : 0.02);
      m.model.setup.gauge_length = 90;
      const ForwardKinematics fk(m.model, m.params);
      if (!fk.batchable()) continue;
      ++batchable;
      const int count = 103, axes = static_cast<int>(m.model.axes.size());
      std::vector<std::vector<double>> q(axes, std::vector<double>(count)), c = q, s = q;
      std::vector<std::vector<double>> p(3, std::vector<double>(count)), u = p;
      for (int a = 0; a < axes; ++a) {
        std::uniform_real_distribution<double> d(m.model.axes[a].travel_min,
                                                 m.model.axes[a].travel_max);
        for (int i = 0; i < count; ++i) {
          q[a][i] = d(rng);
          c[a][i] = std::cos(q[a][i]);
          s[a][i] = std::sin(q[a][i]);
        }
      }
      std::vector<const double*> qp, cp, sp;
      for (int a = 0; a < axes; ++a) {
        qp.push_back(q[a].data());
        cp.push_back(c[a].data());
        sp.push_back(s[a].data());
      }
      double* pp[3] = {p[0].data(), p[1].data(), p[2].data()};
      double* up[3] = {u[0].data(), u[1].data(), u[2].data()};
      // Both lane widths where the processor runs the eight-lane (AVX-512) kernels.
      for (const bool wide : {false, true}) {
        lanes::setWideLanes(wide);
        if (wide && !lanes::wideLanes()) break;
        fk.tipAndAxisBatch(count, qp.data(), cp.data(), sp.data(), pp, up);
        lanes::setWideLanes(true);
        for (int i = 0; i < count; ++i) {
          JointVector qi(axes);
          double ci[kMaxAxes], si[kMaxAxes];
          for (int a = 0; a < axes; ++a) {
            qi[a] = q[a][i];
            ci[a] = c[a][i];
            si[a] = s[a][i];
          }
          Eigen::Vector3d p1, u1;
          fk.tipAndAxis(qi, &p1, &u1, ci, si);
          for (int k = 0; k < 3; ++k) {
            ASSERT_EQ(p[k][i], p1[k]) << file << (wide ? " wide" : " narrow") << " point " << i;
            ASSERT_EQ(u[k][i], u1[k]) << file << (wide ? " wide" : " narrow") << " point " << i;
          }
        }
      }
    }
  }
  EXPECT_GE(batchable, 14);  // every machine but the nutating head, at both error sizes
}

// Squareness of X to Y as the link error gamma_z,X: the X carriage (and the part on it) turns by
// gamma, so a y motion appears in the part frame as y (sin g, cos g): the tool tip moves off by
// dx = -y sin(gamma) exactly, independent of x.
TEST(ForwardKinematics, SquarenessErrorGivesItsAnalyticShift) {
  Machine m = matsuura();
  const double g = 50e-6;  // rad
  m.params[m.model.findParameter("COX")] = g;
  const ForwardKinematics fk(m.model, m.params);
  for (double x : {-300.0, 0.0, 250.0}) {
    for (double y : {-200.0, 0.0, 150.0}) {
      const Eigen::Vector3d p = fk.w_T_t(joints(x, y, 0, 0, 0)).translation();
      EXPECT_NEAR(p.x(), -x - y * std::sin(g), 1e-12);
      EXPECT_NEAR(p.y(), -y * std::cos(g), 1e-12);
      EXPECT_NEAR(p.z(), 0.0, 1e-12);
    }
  }
}

// Offset of the C axis from the A axis in y (e_y,C): the tool sees the offset turned by -c.
TEST(ForwardKinematics, RotaryAxisOffsetTurnsWithTheTable) {
  Machine m = matsuura();
  const double d = 0.015;  // mm
  m.params[m.model.findParameter("YOC")] = d;
  const ForwardKinematics fk(m.model, m.params);
  for (double c = -3.0; c <= 3.0; c += 0.5) {
    const Eigen::Vector3d p = fk.w_T_t(joints(0, 0, 0, 0, c)).translation();
    EXPECT_NEAR(p.x(), -d * std::sin(c), 1e-15);
    EXPECT_NEAR(p.y(), -d * std::cos(c), 1e-15);
  }
}

// A linear positioning error of X, e_x(X) = c1 T1(x_N): the table overshoots by c1 x / 380.
TEST(ForwardKinematics, ChebyshevMotionErrorEntersAtItsJointCoordinate) {
  Machine m = matsuura();
  const double c1 = 0.008, c3 = -0.002;
  m.params[m.model.findParameter("EXX.c1")] = c1;
  m.params[m.model.findParameter("EXX.c3")] = c3;
  const ForwardKinematics fk(m.model, m.params);
  for (double x = -380; x <= 380; x += 95) {
    const double xn = x / 380.0;
    const double e = c1 * xn + c3 * (4 * xn * xn * xn - 3 * xn);
    EXPECT_NEAR(fk.w_T_t(joints(x, 0, 0, 0, 0)).translation().x(), -(x + e), 1e-12);
    EXPECT_NEAR(fk.motionErrors(0, x)[0], e, 1e-15);
  }
}

// A rotation about the joint's own axis commutes with its motion: the link error gamma_x,A and
// the constant term of the motion error gamma_x(A) give the same pose.
TEST(ForwardKinematics, LinkAndConstantMotionErrorAboutTheJointAxisAgree) {
  Machine a = matsuura(), b = matsuura();
  a.params[a.model.findParameter("AOA")] = 30e-6;
  b.params[b.model.findParameter("EAA.c0")] = 30e-6;
  const ForwardKinematics fa(a.model, a.params), fb(b.model, b.params);
  for (double ang = -2.0; ang <= 0.5; ang += 0.25) {
    const JointVector q = joints(100, -50, 80, ang, 1.0);
    EXPECT_TRUE(fa.w_T_t(q).isApprox(fb.w_T_t(q), 1e-14));
  }
}

// Errors are exact: doubling a large angular error is not linear in the pose.
TEST(ForwardKinematics, NoSmallAngleShortcut) {
  Machine m = matsuura();
  const double g = 0.2;  // rad, deliberately large
  m.params[m.model.findParameter("COX")] = g;
  const ForwardKinematics fk(m.model, m.params);
  const Eigen::Vector3d p = fk.w_T_t(joints(0, 100, 0, 0, 0)).translation();
  EXPECT_NEAR(p.x(), -100 * std::sin(g), 1e-12);
  EXPECT_NEAR(p.y(), -100 * std::cos(g), 1e-12);
}

}  // namespace
}  // namespace tolver
