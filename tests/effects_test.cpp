// Effects (core/model/effects.h) in the forward model, the sensitivity Jacobian, the ball-bar
// model, prediction and machine files: analytic cases, finite differences and round trips.
#include "core/model/effects.h"

#include <gtest/gtest.h>

#include <random>

#include "core/calibration/ballbar.h"
#include "core/kinematics/sensitivity_jacobian.h"
#include "core/path/tool_path_prediction.h"
#include "io/common/io_error.h"
#include "io/machine/machine_file.h"
#include "test_support.h"
#include "twist_support.h"

namespace tolver {
namespace {

using test::twistBetween;

Machine matsuura() {
  return readMachineFile(test::sourcePath("resources/machines/matsuura_mc760vx.xml"));
}

int addEffect(Machine& m, const EffectSpec& e, const std::vector<double>& values) {
  const int first = m.model.parameterCount();
  m.model.addEffect(e);
  m.params.conservativeResize(m.model.parameterCount());
  for (int k = first; k < m.model.parameterCount(); ++k) m.params[k] = values.at(k - first);
  return first;
}

EffectSpec spec(EffectType t, int axis, int component) {
  EffectSpec e;
  e.type = t;
  e.axis = axis;
  e.component = component;
  return e;
}

// One effect of every type, with non-zero values.
Machine withEveryEffect() {
  Machine m = matsuura();
  EffectSpec cheb = spec(EffectType::Chebyshev, 1, 0);
  cheb.first_order = 4;
  cheb.last_order = 5;
  addEffect(m, cheb, {3e-3, -2e-3});
  EffectSpec rev = spec(EffectType::Reversal, 0, 0);
  rev.varying = true;
  addEffect(m, rev, {4e-3, 1e-3});
  EffectSpec per = spec(EffectType::Periodic, 1, 1);
  per.period = 10;
  addEffect(m, per, {1.5e-3, -2e-3});
  EffectSpec harm = spec(EffectType::Harmonics, 4, 5);
  harm.first_order = 2;
  harm.last_order = 4;
  addEffect(m, harm, {30e-6, -20e-6, 12e-6, 1e-6, -2e-6, 3e-6});
  addEffect(m, spec(EffectType::Drift, 2, 2), {2e-3});
  EffectSpec warm = spec(EffectType::Warmup, 2, 1);
  warm.tau = 1500;
  addEffect(m, warm, {5e-3});
  addEffect(m, spec(EffectType::BarLength, -1, -1), {3e-3});
  return m;
}

TEST(Effects, ReversalShiftsTheToolByHalfTheValueAgainstTheApproach) {
  Machine m = matsuura();
  const double B = 4e-3;
  addEffect(m, spec(EffectType::Reversal, 0, 0), {B});  // X positioning
  const ForwardKinematics fk(m.model, m.params),
      nominal(m.model, Eigen::VectorXd::Zero(m.params.size()));
  JointVector q = JointVector::Zero(5);
  q << 100, -50, 30, 0, 0;
  for (int d : {1, -1, 0}) {
    MotionContext ctx;
    ctx.direction[0] = static_cast<signed char>(d);
    const Eigen::Vector3d dp = fk.w_T_t(q, &ctx).translation() - nominal.w_T_t(q).translation();
    // X moves the table: a table offset +B/2 d in x moves the tool -B/2 d relative to the part.
    EXPECT_NEAR(dp.x(), -0.5 * B * d, 1e-12);
    EXPECT_NEAR(dp.y(), 0.0, 1e-12);
    EXPECT_NEAR(dp.z(), 0.0, 1e-12);
  }
}

TEST(Effects, TimeEffectsFollowTheirLaws) {
  Machine m = matsuura();
  addEffect(m, spec(EffectType::Drift, 2, 2), {2e-3});  // Z, ez: 2 um per hour
  EffectSpec warm = spec(EffectType::Warmup, 2, 2);
  warm.tau = 1200;
  addEffect(m, warm, {5e-3});
  const ForwardKinematics fk(m.model, m.params),
      nominal(m.model, Eigen::VectorXd::Zero(m.params.size()));
  const JointVector q = JointVector::Zero(5);
  for (double t : {0.0, 600.0, 3600.0, 7200.0}) {
    MotionContext ctx;
    ctx.time_s = t;
    const double dz = fk.w_T_t(q, &ctx).translation().z() - nominal.w_T_t(q).translation().z();
    EXPECT_NEAR(dz, 2e-3 * t / 3600 + 5e-3 * (1 - std::exp(-t / 1200)),
                1e-12);  // Z on the tool branch
  }
  MotionContext unknown;  // no time: nothing
  EXPECT_NEAR((fk.w_T_t(q, &unknown).translation() - nominal.w_T_t(q).translation()).norm(), 0,
              1e-15);
}

TEST(Effects, HarmonicsAndPeriodicBasesAreTheirFourierTerms) {
  EffectSpec h = spec(EffectType::Harmonics, 4, 5);
  h.first_order = 2;
  h.last_order = 3;
  double phi[8];
  traitsOf(h.type).basis(h, 0.7, 0.0, nullptr, phi);
  EXPECT_DOUBLE_EQ(phi[0], std::cos(1.4));
  EXPECT_DOUBLE_EQ(phi[1], std::sin(1.4));
  EXPECT_DOUBLE_EQ(phi[2], std::cos(2.1));
  EXPECT_DOUBLE_EQ(phi[3], std::sin(2.1));
  EffectSpec p = spec(EffectType::Periodic, 0, 0);
  p.period = 16;
  traitsOf(p.type).basis(p, 4.0, 0.0, nullptr, phi);  // a quarter period
  EXPECT_NEAR(phi[0], 1.0, 1e-15);
  EXPECT_NEAR(phi[1], 0.0, 1e-15);
  EffectSpec c = spec(EffectType::Chebyshev, 0, 0);
  c.first_order = 4;
  c.last_order = 5;
  traitsOf(c.type).basis(c, 0.0, 0.5, nullptr, phi);
  EXPECT_NEAR(phi[0], 8 * std::pow(0.5, 4) - 8 * 0.25 + 1, 1e-15);                      // T4(x)
  EXPECT_NEAR(phi[1], 16 * std::pow(0.5, 5) - 20 * std::pow(0.5, 3) + 5 * 0.5, 1e-15);  // T5(x)
}

// Effect columns of the sensitivity Jacobian against central finite differences.
TEST(Effects, JacobianColumnsMatchFiniteDifferences) {
  const Machine m = withEveryEffect();
  std::mt19937 rng(3);
  Eigen::MatrixXd J(6, m.model.parameterCount());
  for (int pose = 0; pose < 10; ++pose) {
    JointVector q(5);
    for (int a = 0; a < 5; ++a)
      q[a] = std::uniform_real_distribution<double>(m.model.axes[a].travel_min,
                                                    m.model.axes[a].travel_max)(rng);
    MotionContext ctx;
    for (int a = 0; a < 5; ++a) ctx.direction[a] = static_cast<signed char>(pose % 2 ? 1 : -1);
    ctx.time_s = 500.0 * pose;
    const ForwardKinematics fk(m.model, m.params);
    sensitivityJacobian(fk, q, J, &ctx);
    const Eigen::Isometry3d T0 = fk.w_T_t(q, &ctx);
    for (const ParameterBlock& b : m.model.blocks) {
      if (b.kind != BlockKind::Effect) continue;
      for (int i = b.offset; i < b.offset + b.size; ++i) {
        const double h = m.model.parameters[i].angular ? 1e-6 : 1e-5;
        Eigen::VectorXd pp = m.params, pm = m.params;
        pp[i] += h;
        pm[i] -= h;
        const Vector6d fd = (twistBetween(T0, ForwardKinematics(m.model, pp).w_T_t(q, &ctx)) -
                             twistBetween(T0, ForwardKinematics(m.model, pm).w_T_t(q, &ctx))) /
                            (2 * h);
        EXPECT_LT((fd - J.col(i)).norm(), 1e-6 * (1.0 + J.col(i).norm()))
            << m.model.parameters[i].iso_code;
      }
    }
  }
}

// The ball-bar gradient: the bar length adds 1 mm per mm; every effect column matches finite
// differences of the reading; the component gradient times the basis is the effect's column.
TEST(Effects, BallbarGradientMatchesFiniteDifferences) {
  const Machine m = withEveryEffect();
  BallbarSetup s;
  s.table_ball_w = Eigen::Vector3d(80, 0, 20);
  s.tool_ball_t = Eigen::Vector3d(12.5, 21.6, 0);
  JointVector q(5);
  q << 20, 70, 60, -0.3, 1.2;
  MotionContext ctx;
  ctx.direction.fill(-1);
  ctx.time_s = 2000;
  const ForwardKinematics fk(m.model, m.params);
  Eigen::RowVectorXd row(m.model.parameterCount()), comp(30);
  Eigen::MatrixXd scratch2;
  ballbarGradient(fk, q, s, {}, row, nullptr, nullptr, &ctx);
  ballbarComponentGradient(fk, q, s, {}, comp, scratch2, &ctx);
  for (const ParameterBlock& b : m.model.blocks) {
    if (b.kind != BlockKind::Effect) continue;
    const EffectSpec& e = m.model.effects[b.effect];
    double phi[8];
    const Axis* ax = e.axis >= 0 ? &m.model.axes[e.axis] : nullptr;
    if (ax)
      traitsOf(e.type).basis(e, q[e.axis],
                             2 * (q[e.axis] - 0.5 * (ax->travel_min + ax->travel_max)) /
                                 (ax->travel_max - ax->travel_min),
                             &ctx, phi);
    for (int i = b.offset; i < b.offset + b.size; ++i) {
      const double h = 1e-6;
      Eigen::VectorXd pp = m.params, pm = m.params;
      pp[i] += h;
      pm[i] -= h;
      const double fd = (ballbarLength(ForwardKinematics(m.model, pp), q, s, {}, &ctx) -
                         ballbarLength(ForwardKinematics(m.model, pm), q, s, {}, &ctx)) /
                        (2 * h);
      EXPECT_NEAR(row[i], fd, 1e-7) << m.model.parameters[i].iso_code;
      if (ax)
        EXPECT_NEAR(comp[6 * e.axis + e.component] * phi[i - b.offset], row[i], 1e-12);
      else
        EXPECT_EQ(row[i], 1.0);
    }
  }
}

TEST(Effects, MachineFileRoundTripKeepsEveryEffect) {
  const Machine m = withEveryEffect();
  const Machine back = parseMachineXml(formatMachineXml(m), "round_trip.xml");
  ASSERT_EQ(back.model.parameterCount(), m.model.parameterCount());
  ASSERT_EQ(back.model.effects.size(), m.model.effects.size());
  for (int i = 0; i < m.model.parameterCount(); ++i) {
    EXPECT_EQ(back.model.parameters[i].iso_code, m.model.parameters[i].iso_code);
    EXPECT_NEAR(back.params[i], m.params[i], 1e-15);
  }
  for (size_t k = 0; k < m.model.effects.size(); ++k) {
    const EffectSpec &a = m.model.effects[k], &b = back.model.effects[k];
    EXPECT_EQ(a.type, b.type);
    EXPECT_EQ(a.axis, b.axis);
    EXPECT_EQ(a.component, b.component);
    EXPECT_EQ(a.varying, b.varying);
    EXPECT_EQ(a.first_order, b.first_order);
    EXPECT_EQ(a.last_order, b.last_order);
    EXPECT_EQ(a.period, b.period);
    EXPECT_EQ(a.tau, b.tau);
  }
  EXPECT_GE(back.model.findParameter("EXX.rev"), 0);
  EXPECT_GE(back.model.findParameter("EYY.cyc.sin"), 0);
  EXPECT_GE(back.model.findParameter("ECC.h2c"), 0);
  EXPECT_GE(back.model.findParameter("bar.L"), 0);
}

std::string machineWithEffect(const std::string& effect) {
  std::string xml = test::readText(test::sourcePath("resources/machines/matsuura_mc760vx.xml"));
  const std::string errors =
      "<errors source=\"none\" length_unit=\"um\" angle_unit=\"urad\" default_degree=\"3\"/>";
  const size_t at = xml.find(errors);
  EXPECT_NE(at, std::string::npos);
  return xml.replace(at, errors.size(),
                     "<errors length_unit=\"um\" angle_unit=\"urad\" default_degree=\"3\">\n" +
                         effect + "\n</errors>");
}

TEST(Effects, MalformedEffectElementsNameLineAndField) {
  const struct {
    const char* effect;
    const char* field;
  } cases[] = {
      {R"(<effect type="backlash" axis="X" component="ex" values="3"/>)", "effect.type"},
      {R"(<effect type="periodic" axis="X" component="ex" values="1 2"/>)", "effect.period_mm"},
      {R"(<effect type="periodic" axis="X" component="ex" period_mm="-4" values="1 2"/>)",
       "effect.period_mm"},
      {R"(<effect type="reversal" axis="X" component="ex" values="1 2"/>)", "effect.values"},
      {R"(<effect type="reversal" axis="W" component="ex" values="1"/>)", "effect.axis"},
      {R"(<effect type="warmup" axis="Z" component="ez" tau_s="x" values="1"/>)", "effect.tau_s"},
      {R"(<effect type="harmonics" axis="C" component="gz" orders="4 2" values="1 2"/>)",
       "effect.orders"},
      {R"(<effect type="reversal" axis="X" component="ex" varying="maybe" values="1"/>)",
       "effect.varying"},
  };
  for (const auto& c : cases) {
    try {
      parseMachineXml(machineWithEffect(c.effect), "m.xml");
      ADD_FAILURE() << c.effect << " accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(c.field), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("m.xml:"), std::string::npos) << e.what();
    }
  }
}

// Prediction sees the approach direction from the joint sequence: along a path that goes +x
// and comes back, a reversal error flips the deviation by its full value.
TEST(Effects, PredictionSeesTheApproachDirection) {
  Machine m = matsuura();
  m.model.setup.gauge_length = 100;
  const double B = 5e-3;
  addEffect(m, spec(EffectType::Reversal, 0, 0), {B});
  std::vector<ClPoint> path;
  for (int i = 0; i <= 20; ++i) {
    ClPoint p;
    p.p_w = Eigen::Vector3d(i < 10 ? 5.0 * i : 5.0 * (20 - i), 0, 0);
    path.push_back(p);
  }
  const PredictionResult r = predictToolPath(m.model, m.params, path);
  ASSERT_TRUE(r.ok());
  // Tool +x relative to the part means the table moves -x: approach -1 going out, +1 back.
  EXPECT_NEAR(r.points[5].deviation_w.x(), 0.5 * B, 1e-12);
  EXPECT_NEAR(r.points[15].deviation_w.x(), -0.5 * B, 1e-12);
}

}  // namespace
}  // namespace tolver
