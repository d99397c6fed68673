// The independent ball-bar simulator (tests/independent_ballbar.h) against tolver's model: with
// cubic motion errors only, written into a tolver machine file as the equivalent Chebyshev
// coefficients, both give the same readings; so the simulator's frames and signs agree with
// tolver's, and what diagnose finds on its data is the undeclared effect, not a convention.
// Then diagnose on its data: clean data adds nothing, an undeclared effect is named, and the
// written files predict the held-out readings as the report says.
#include <gtest/gtest.h>

#include "independent_diagnosis.h"

namespace tolver {
namespace {

TEST(IndependentSimulator, AgreesWithTolversModelOnCubicErrors) {
  Machine m = readMachineFile(test::sourcePath("resources/machines/matsuura_mc760vx.xml"));
  indep::Machine sim(42);
  // a0 + a1 u + a2 u^2 + a3 u^3 = (a0 + a2/2) T0 + (a1 + 3 a3/4) T1 + a2/2 T2 + a3/4 T3.
  const char* axes = "XYZAC";
  const char* comps = "XYZABC";
  for (int a = 0; a < 5; ++a)
    for (int c = 0; c < 6; ++c) {
      indep::Pose p0;
      double coeffs[4];
      // Recover the polynomial by sampling the simulator at four coordinates (u = -1, -1/3,
      // 1/3, 1) and solving the Vandermonde system.
      Eigen::Matrix4d V;
      Eigen::Vector4d y;
      const double mid = 0.5 * (indep::kTravelMin[a] + indep::kTravelMax[a]);
      const double half = 0.5 * (indep::kTravelMax[a] - indep::kTravelMin[a]);
      for (int i = 0; i < 4; ++i) {
        const double u = -1.0 + 2.0 * i / 3.0;
        indep::Pose p;
        p.q[a] = mid + half * u;
        double e[6];
        sim.errors(a, p, e);
        y[i] = e[c];
        for (int k = 0; k < 4; ++k) V(i, k) = std::pow(u, k);
      }
      const Eigen::Vector4d poly = V.fullPivLu().solve(y);
      for (int k = 0; k < 4; ++k) coeffs[k] = poly[k];
      const double cheb[4] = {coeffs[0] + coeffs[2] / 2, coeffs[1] + 0.75 * coeffs[3],
                              coeffs[2] / 2, coeffs[3] / 4};
      for (int k = 0; k < 4; ++k) {
        const std::string code = std::string("E") + comps[c] + axes[a] + ".c" + std::to_string(k);
        const int idx = m.model.findParameter(code);
        ASSERT_GE(idx, 0) << code;
        m.params[idx] = cheb[k];
      }
      (void)p0;
    }
  const ForwardKinematics fk(m.model, m.params);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int i = 0; i < 200; ++i) {
    indep::Pose p;
    JointVector q(5);
    for (int a = 0; a < 5; ++a) {
      p.q[a] = indep::kTravelMin[a] + (indep::kTravelMax[a] - indep::kTravelMin[a]) * u(rng);
      q[a] = p.q[a];
    }
    indep::Setup s;
    s.table_ball_w = Eigen::Vector3d(80, 10, 20);
    s.tool_ball_t = Eigen::Vector3d(25, 0, -5);
    BallbarSetup bs;
    bs.table_ball_w = s.table_ball_w;
    bs.tool_ball_t = s.tool_ball_t;
    EXPECT_NEAR(sim.reading(p, s), ballbarLength(fk, q, bs), 1e-9) << i;
  }
}

class IndependentDiagnosis : public test::TempDirTest {};

// Clean data, 20 generator seeds x both set-up styles: nothing is added, no structure is
// claimed, and the written files predict the held-out readings at the noise.
TEST_F(IndependentDiagnosis, TwentyCleanSeedsInBothSetupStylesAddNothing) {
  const test::DiagnosisCase clean = test::diagnosisCases()[0];
  for (bool on_axis : {false, true})
    for (unsigned seed = 1; seed <= 20; ++seed) {
      SCOPED_TRACE(std::string(on_axis ? "on axis" : "off axis") + " seed " + std::to_string(seed));
      const test::DiagnosisOutcome o = test::runDiagnosisCase(clean, on_axis, seed, path("c"));
      EXPECT_TRUE(o.named_right) << o.message
                                 << (o.unexplained ? " unexplained " + o.unexplained_variable : "");
      EXPECT_LT(o.written_vs_memory_um, 1e-3);
      EXPECT_LT(o.heldout_after_um, 1.0);  // 0.5 um noise
    }
}

TEST_F(IndependentDiagnosis, AnUndeclaredEffectIsNamedAndTheWrittenFilesPredictBetter) {
  const auto cases = test::diagnosisCases();
  for (bool on_axis : {false, true})
    for (size_t k : {1u, 2u}) {  // reversal, periodic
      SCOPED_TRACE(cases[k].name + (on_axis ? " on axis" : " off axis"));
      const test::DiagnosisOutcome o = test::runDiagnosisCase(cases[k], on_axis, 3, path("e"));
      std::string added;
      for (const std::string& a : o.added) added += a + "; ";
      EXPECT_TRUE(o.named_right) << o.message << ": " << added;
      EXPECT_LT(o.written_vs_memory_um, 1e-3);
      EXPECT_LT(o.heldout_after_um, o.heldout_before_um);
      EXPECT_LT(o.heldout_after_um, 1.0);
      // The gain on the held-out readings is confirmed: above twice its standard error.
      EXPECT_GT(o.heldout_gain_um2, 2.0 * o.heldout_gain_se_um2) << o.message;
    }
}

// Without held-out readings the cross-validation decides (point 3 of issue 33): each fold refits
// the effects' own parameters, and the gain per reading must exceed twice its standard error over
// the folds. The effects are still named and confirmed, clean data adds nothing, and the held-out
// readings (kept apart, judged through the written files) agree.
TEST_F(IndependentDiagnosis, WithoutHeldOutReadingsTheCrossValidatedGainDecides) {
  const auto cases = test::diagnosisCases();
  for (size_t k : {0u, 1u, 2u, 4u, 6u})  // none, reversal, periodic, warm-up, drift
    for (unsigned seed : {11u, 12u}) {
      SCOPED_TRACE(cases[k].name + " seed " + std::to_string(seed));
      const test::DiagnosisOutcome o =
          test::runDiagnosisCase(cases[k], false, seed, path("v"), false, false);
      std::string added;
      for (const std::string& a : o.added) added += a + "; ";
      EXPECT_TRUE(o.named_right) << o.message << ": " << added;
      if (k == 0) {  // nothing added: the same model before and after, no gain
        EXPECT_TRUE(o.added.empty()) << added;
        EXPECT_EQ(o.cv_gain_um2, 0.0);
        continue;
      }
      EXPECT_GT(o.cv_gain_se_um2, 0.0);
      EXPECT_GT(o.cv_gain_um2, 2.0 * o.cv_gain_se_um2) << o.message;
      EXPECT_LT(o.heldout_after_um, o.heldout_before_um);
      EXPECT_LT(o.heldout_after_um, 1.0);
    }
}

// With every tool ball on the spindle axis the base fit holds parameters it cannot see; they stay
// held (at their prior values) in the augmented model the diagnosis writes.
TEST_F(IndependentDiagnosis, HeldParametersStayHeld) {
  const test::DiagnosisOutcome o =
      test::runDiagnosisCase(test::diagnosisCases()[1], true, 4, path("h"));
  EXPECT_GT(o.held, 0);
  EXPECT_TRUE(o.held_stayed_held);
  EXPECT_TRUE(o.named_right) << o.message;
  EXPECT_LT(o.heldout_after_um, o.heldout_before_um);
}

// The final check: held-out readings from the machine without the reversal the fit readings
// have; the augmented model predicts them worse than the base one and is withdrawn.
TEST_F(IndependentDiagnosis, AnAugmentedModelThatPredictsWorseIsWithdrawn) {
  const test::DiagnosisOutcome o =
      test::runDiagnosisCase(test::diagnosisCases()[1], false, 5, path("w"), true);
  EXPECT_TRUE(o.withdrawn) << o.message;
  EXPECT_TRUE(o.added.empty());
  EXPECT_NE(o.message.find("predicted the held-out readings worse"), std::string::npos)
      << o.message;
}

// An effect the library does not have (a 70 mm cyclic error; periods are searched from 5 to
// 40 mm): the report names the structure along X that is left. A degree-8 term of X may take a
// part of it (it does on this seed), never a term of another axis.
TEST_F(IndependentDiagnosis, StructureOutsideTheLibraryIsSaid) {
  test::DiagnosisCase c;
  for (const test::DiagnosisCase& k : test::diagnosisCases())
    if (!k.unexplained_variable.empty()) c = k;
  ASSERT_FALSE(c.truth.empty());
  for (unsigned seed : {6u, 7u}) {
    const test::DiagnosisOutcome o = test::runDiagnosisCase(c, false, seed, path("u"));
    EXPECT_TRUE(o.unexplained) << seed;
    EXPECT_EQ(o.unexplained_variable, "X") << seed;
    for (const std::string& a : o.added) EXPECT_EQ(a.rfind("chebyshev X ", 0), 0u) << a;
  }
}

// A direction-dependent tilt of the A cradle about y (+-20 urad, a bearing clearance): no effect
// of the library has it, and the residual follows nothing in particular, but the fit's residual
// is twice the repeatability of the plan's returns to the reference pose: the verdict is
// "incomplete", never "nothing missing", with where and what to measure (issue 33; before, 8 of
// 10 runs said nothing was missing).
TEST_F(IndependentDiagnosis, ALackOfFitIsNeverNothingMissing) {
  test::DiagnosisCase c;
  for (const test::DiagnosisCase& k : test::diagnosisCases())
    if (k.lack_of_fit) c = k;
  ASSERT_FALSE(c.truth.empty());
  for (unsigned seed : {1u, 2u}) {
    const test::DiagnosisOutcome o = test::runDiagnosisCase(c, false, seed, path("l"));
    EXPECT_EQ(o.verdict, DiagnosisVerdict::Incomplete) << o.message;
    EXPECT_LT(o.lack_of_fit_p, 1e-3) << o.message;
    EXPECT_NE(o.message.find("misses"), std::string::npos) << o.message;
  }
}

// A gain within its uncertainty is not confirmed: a 1.5 um reversal, held-out readings measured
// without it, the augmented model a hair better on them (RMS 0.723 -> 0.710 um, mean squared
// gain 0.018 +- 0.048 um^2): withdrawn, never written as an improvement.
TEST_F(IndependentDiagnosis, AGainWithinItsUncertaintyIsNotConfirmed) {
  test::DiagnosisCase c{
      "Y reversal 1.5 um", {{"reversal", indep::kY, 1, 1.5e-3}}, {{"reversal", "Y", 1}}};
  const test::DiagnosisOutcome o = test::runDiagnosisCase(c, false, 2, path("n"), true);
  EXPECT_TRUE(o.withdrawn) << o.message;
  EXPECT_TRUE(o.added.empty());
  EXPECT_NE(o.message.find("not confirmed"), std::string::npos) << o.message;
  EXPECT_GT(o.heldout_gain_um2, 0.0);
  EXPECT_LT(o.heldout_gain_um2, 2.0 * o.heldout_gain_se_um2);
}

// A drift no machine has (Y at 300 um/h): diagnose does not add it as "drift Y ey" (its value
// is beyond the plausible 50 um/h); the verdict says the model is incomplete.
TEST_F(IndependentDiagnosis, AnImplausibleValueIsNotAdded) {
  test::DiagnosisCase c{"Y drift 300 um/h", {{"reversal", indep::kY, 1, 0.0}}, {}};
  c.truth = {{"drift", indep::kY, 1, 0.3}};
  const test::DiagnosisOutcome o = test::runDiagnosisCase(c, false, 2, path("p"));
  for (const std::string& a : o.added) EXPECT_EQ(a.find("drift Y ey"), std::string::npos) << a;
  ASSERT_FALSE(o.implausible.empty()) << o.message;
  EXPECT_NE(o.implausible.front().find("beyond the plausible"), std::string::npos)
      << o.implausible.front();
  EXPECT_EQ(o.verdict, DiagnosisVerdict::Incomplete) << o.message;
}

}  // namespace
}  // namespace tolver
