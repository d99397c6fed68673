// predict and verify on a calibrated machine: the covariance of the calibration travels in the
// machine file; predict writes each point's uncertainty and applies the set-up a shop measures
// (--absolute keeps the raw prediction); verify turns a decision inside the 95 % band into
// UNDECIDED (exit 4), one clear of it into PASS (0) or FAIL (1).
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>

#include "core/kinematics/forward_kinematics.h"
#include "core/path/tool_path_prediction.h"
#include "io/common/io_error.h"
#include "io/machine/machine_file.h"
#include "io/program/apt_reader.h"
#include "io/program/probe_file.h"
#include "io/program/setup_file.h"
#include "test_support.h"

namespace tolver {
namespace {

class UncertaintyCli : public test::TempDirTest {
 protected:
  std::string identified() {
    const std::string nominal = test::sourcePath("resources/machines/matsuura_mc760vx.xml");
    const std::string truth = test::sourcePath("samples/machines/matsuura_mc760vx_measured.xml");
    auto r = test::runTolver("plan-ballbar --machine " + nominal + " --poses 360 --seed 5 -o " +
                             path("plan.csv"));
    EXPECT_EQ(r.exit_code, 0) << r.output;
    r = test::runTolver("simulate-ballbar --machine " + truth + " --plan " + path("plan.csv") +
                        " --noise-um 0.5 --ball-error-um 10 --seed 5 -o " + path("r.csv"));
    EXPECT_EQ(r.exit_code, 0) << r.output;
    r = test::runTolver("calibrate --machine " + nominal + " --readings " + path("r.csv") + " -o " +
                        path("id.xml"));
    EXPECT_EQ(r.exit_code, 0) << r.output;
    return path("id.xml");
  }
};

TEST_F(UncertaintyCli, PredictWritesTheUncertaintyAndAppliesTheMeasuredSetup) {
  const std::string id = identified();
  const Machine m = readMachineFile(id);
  ASSERT_EQ(m.identification.parameters.size(), 92u);
  ASSERT_EQ(m.identification.covered_min.size(), 5u);
  const std::string base = "predict --machine " + id + " --cl " +
                           test::sourcePath("samples/nas979_cone.apt") + " --setup " +
                           test::sourcePath("samples/matsuura_setup.txt");
  auto r = test::runTolver(base + " -o " + path("p.apt"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("predicted after the set-up a shop measures"), std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("uncertainty (1 sigma) of the prediction"), std::string::npos)
      << r.output;
  std::ifstream in(path("p.csv"));
  std::string header;
  std::getline(in, header);
  EXPECT_NE(header.find(",u_tip_um,u_along_axis_um,u_axis_urad,outside_calibrated,cov_xx_um2"),
            std::string::npos);
  // The band is checkable from the file: the tip covariance along the nominal tool axis gives
  // u_along_axis_um, and its largest eigenvalue u_tip_um (to the printed digits).
  {
    std::vector<std::string> names;
    std::stringstream hs(header);
    for (std::string c; std::getline(hs, c, ',');) names.push_back(c);
    auto col = [&](const std::string& n) {
      return static_cast<size_t>(std::find(names.begin(), names.end(), n) - names.begin());
    };
    int rows = 0;
    for (std::string line; std::getline(in, line) && rows < 200; ++rows) {
      std::vector<double> v;
      std::stringstream ls(line);
      for (std::string c; std::getline(ls, c, ',');) v.push_back(std::stod(c));
      ASSERT_EQ(v.size(), names.size());
      Eigen::Matrix3d C;
      C << v[col("cov_xx_um2")], v[col("cov_xy_um2")], v[col("cov_xz_um2")], v[col("cov_xy_um2")],
          v[col("cov_yy_um2")], v[col("cov_yz_um2")], v[col("cov_xz_um2")], v[col("cov_yz_um2")],
          v[col("cov_zz_um2")];
      const Eigen::Vector3d n =
          Eigen::Vector3d(v[col("nominal_i")], v[col("nominal_j")], v[col("nominal_k")])
              .normalized();
      const double along = std::sqrt(n.dot(C * n));
      EXPECT_NEAR(along, v[col("u_along_axis_um")], 1e-4 + 1e-5 * along) << rows;
      const double worst =
          std::sqrt(Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(C).eigenvalues().maxCoeff());
      EXPECT_NEAR(worst, v[col("u_tip_um")], 1e-4 + 1e-5 * worst) << rows;
    }
    EXPECT_EQ(rows, 200);
  }
  auto a = test::runTolver(base + " --absolute -o " + path("a.apt"));
  ASSERT_EQ(a.exit_code, 0) << a.output;
  EXPECT_NE(a.output.find("absolute prediction"), std::string::npos) << a.output;
  // The raw prediction carries what the set-up takes up: a larger RMS deviation.
  const std::regex rms(
      "deviation  max [0-9.]+ um at point [0-9]+ \\(line [0-9]+\\), RMS ([0-9.]+) um");
  std::smatch s1, s2;
  ASSERT_TRUE(std::regex_search(r.output, s1, rms)) << r.output;
  ASSERT_TRUE(std::regex_search(a.output, s2, rms)) << a.output;
  EXPECT_LT(std::stod(s1[1]), std::stod(s2[1]));
}

TEST_F(UncertaintyCli, VerifySaysUndecidedWhenTheLimitIsInsideTheBand) {
  const std::string id = identified();
  const std::string base = "verify --machine " + id + " --cl " +
                           test::sourcePath("samples/nas979_cone.apt") + " --setup " +
                           test::sourcePath("samples/matsuura_setup.txt") + " --no-images";
  auto r = test::runTolver(base + " --tolerance 0.05 --report-dir " + path("v0"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::smatch m;
  ASSERT_TRUE(
      std::regex_search(r.output, m, std::regex("total +([-+0-9.]+) \\.\\. ([-+0-9.]+) um")))
      << r.output;
  const double worst = std::max(std::abs(std::stod(m[1])), std::abs(std::stod(m[2])));  // um
  ASSERT_TRUE(std::regex_search(r.output, m, std::regex("known to \\+- ([0-9.]+) um"))) << r.output;
  const double band = std::stod(m[1]);
  ASSERT_GT(band, 0.0);
  // Where the band comes from, in the console and the JSON: this calibration's test showed no
  // lack of fit (its repeats agree with the fit).
  EXPECT_NE(r.output.find("calibration's covariance at each contact, tip and tool axis; no lack "
                          "of fit; spindle tilt not included)"),
            std::string::npos)
      << r.output;
  {
    std::ifstream j0(path("v0") + "/report.json");
    const nlohmann::json k = nlohmann::json::parse(j0);
    EXPECT_EQ(k["uncertainty"]["lack_of_fit_um"].get<double>(),
              readMachineFile(id).identification.lack_of_fit_mm * 1e3);
    EXPECT_EQ(k["uncertainty"]["spindle_tilt_prior_urad"].get<double>(), 0.0);
    // The printed band is the largest of deviations.csv's per-sample bands.
    std::ifstream csv(path("v0") + "/deviations.csv");
    std::string line;
    double largest = 0;
    int rows = 0;
    while (std::getline(csv, line)) {
      if (line.empty() || line[0] == '#' || line.rfind("sample,", 0) == 0) {
        if (line.rfind("sample,", 0) == 0) EXPECT_NE(line.find(",band95_um"), std::string::npos);
        continue;
      }
      largest = std::max(largest, std::stod(line.substr(line.rfind(',') + 1)));
      ++rows;
    }
    EXPECT_GT(rows, 0);
    EXPECT_NEAR(largest, k["uncertainty"]["band95_max_um"].get<double>(), 1e-4);
    EXPECT_NEAR(largest, band, 0.006);
    EXPECT_NE(k["uncertainty"]["sources"].get<std::string>().find("tip and tool axis"),
              std::string::npos);
  }
  auto run = [&](double t_um, const std::string& dir) {
    char t[32];
    std::snprintf(t, sizeof t, "%.6f", t_um * 1e-3);
    return test::runTolver(base + " --tolerance " + t + " --report-dir " + path(dir));
  };
  // The worst sample exactly at the limit: inside its band.
  r = run(2 * worst, "u");
  EXPECT_EQ(r.exit_code, 4) << r.output;
  EXPECT_NE(r.output.find("tolver verify: UNDECIDED"), std::string::npos) << r.output;
  std::ifstream in(path("u") + "/report.json");
  const nlohmann::json j = nlohmann::json::parse(in);
  EXPECT_EQ(j["verdict"], "undecided");
  EXPECT_EQ(j["exit_code"], 4);
  // Clear of the band on both sides.
  EXPECT_EQ(run(2 * (worst + 2 * band), "p").exit_code, 0);
  EXPECT_EQ(run(2 * (worst - 3 * band), "f").exit_code, 1);
}

// plan-ballbar --for: poses chosen by the prediction variance where the program cuts give a
// smaller expected tip uncertainty there than the D-optimal plan of the same size (the
// comparison plan-ballbar prints, recomputed here from its output).
TEST_F(UncertaintyCli, APlanForAProgramPredictsItBetter) {
  auto r = test::runTolver(
      "plan-ballbar --machine " + test::sourcePath("resources/machines/matsuura_mc760vx.xml") +
      " --setup " + test::sourcePath("samples/matsuura_setup.txt") + " --for " +
      test::sourcePath("samples/nas979_cone.apt") + " --poses 360 -o " + path("p.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::smatch m;
  ASSERT_TRUE(
      std::regex_search(r.output, m,
                        std::regex("median ([0-9.]+) um, max ([0-9.]+) um; the D-optimal plan of "
                                   "the same size: median ([0-9.]+) um, max ([0-9.]+) um")))
      << r.output;
  EXPECT_LT(std::stod(m[1]), 0.9 * std::stod(m[3]));
  EXPECT_LT(std::stod(m[2]), std::stod(m[4]));
  // It says what it buys: the two medians' ratio (to the printed digits).
  const double gain = 100.0 * (1.0 - std::stod(m[1]) / std::stod(m[3]));
  std::smatch b;
  ASSERT_TRUE(
      std::regex_search(r.output, b, std::regex("buys       an expected ([0-9]+) % lower median")))
      << r.output;
  EXPECT_NEAR(std::stod(b[1]), gain, 2.0);
}

// compensate on a calibrated machine: the after carries the model's 95 % band (from the
// calibration's covariance), said on the console and in the report; the after itself (the model's
// own prediction) is zero to the stopping rule.
TEST_F(UncertaintyCli, CompensationSaysHowMuchOfTheAfterIsModelUncertainty) {
  const std::string id = identified();
  auto r = test::runTolver("compensate --machine " + id + " --cl " +
                           test::sourcePath("samples/nas979_cone.apt") + " --setup " +
                           test::sourcePath("samples/matsuura_setup.txt") + " -o " + path("c.apt"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  // The after is the band (tip and axis), the model's own residual apart.
  EXPECT_NE(r.output.find("after      within the calibration's 95 % radius: tip median"),
            std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("model      tip max"), std::string::npos) << r.output;
  // Where the band comes from: no tilt prior was stated, and it says the axis band leaves it out.
  EXPECT_NE(r.output.find("band from  the covariance;"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("the spindle's tilt, which a ball-bar cannot see, is not in the axis"),
            std::string::npos)
      << r.output;
  std::ifstream in(path("c.json"));
  const nlohmann::json j = nlohmann::json::parse(in);
  ASSERT_TRUE(j.contains("after_uncertainty")) << j.dump(1);
  EXPECT_EQ(j["after_uncertainty"]["axis_spindle_tilt_prior_urad"].get<double>(), 0.0);
  const double band = j["after_uncertainty"]["band95_max_um"].get<double>();
  EXPECT_GT(band, 0.01);
  EXPECT_LT(band, 5.0);
  // One point of the cone needs C beyond its travel (line 553, where the table swings): it is
  // reported and left as programmed; the others come out on the nominal.
  EXPECT_EQ(j["uncompensated"]["out_of_travel_lines"], nlohmann::json::array({553}));
  EXPECT_LT(j["after_compensated_points"]["tip_max_um"].get<double>(), 0.01);
  EXPECT_GT(j["after_uncertainty"]["axis_band95_max_urad"].get<double>(), 0.1);
  {
    // With a stated tilt prior of 20 urad (the machine file's attribute), the axis's 95 % radius
    // holds it: at least sqrt(chi2_2(0.95)) 20 = 48.95 urad on every point, and it says so.
    std::ifstream mf(id);
    std::string xml((std::istreambuf_iterator<char>(mf)), std::istreambuf_iterator<char>());
    const std::string tag = "<identification_uncertainty ";
    ASSERT_NE(xml.find(tag), std::string::npos);
    xml.replace(xml.find(tag), tag.size(), tag + "spindle_tilt_urad=\"20\" ");
    std::ofstream(path("tilt.xml")) << xml;
    auto t =
        test::runTolver("compensate --machine " + path("tilt.xml") + " --cl " +
                        test::sourcePath("samples/nas979_cone.apt") + " --setup " +
                        test::sourcePath("samples/matsuura_setup.txt") + " -o " + path("t.apt"));
    ASSERT_EQ(t.exit_code, 0) << t.output;
    EXPECT_NE(t.output.find("the spindle tilt's prior, 20.0 urad on the axis"), std::string::npos)
        << t.output;
    std::ifstream tj(path("t.json"));
    const nlohmann::json k = nlohmann::json::parse(tj);
    EXPECT_EQ(k["after_uncertainty"]["axis_spindle_tilt_prior_urad"].get<double>(), 20.0);
    EXPECT_GE(k["after_uncertainty"]["axis_band95_median_urad"].get<double>(), 48.95);
    EXPECT_LT(k["after_uncertainty"]["axis_band95_median_urad"].get<double>(),
              48.95 + j["after_uncertainty"]["axis_band95_max_urad"].get<double>());
  }
  // The joints of every point: a compensated point's after joints put the calibrated machine's
  // tip on the program's point; the out-of-travel one keeps its joints.
  ASSERT_EQ(j["joints_file"], path("c_joints.csv"));
  const Machine m = readMachineFile(id);
  const ForwardKinematics fk(m.model, m.params);
  const ClProgram cl = readAptFile(test::sourcePath("samples/nas979_cone.apt"));
  std::ifstream jin(path("c_joints.csv"));
  std::string header;
  std::getline(jin, header);
  EXPECT_EQ(header.rfind("index,line,status,x_mm_before", 0), 0u) << header;
  int rows = 0, checked = 0;
  for (std::string line; std::getline(jin, line); ++rows) {
    std::vector<std::string> c;
    std::stringstream ls(line);
    for (std::string x; std::getline(ls, x, ',');) c.push_back(x);
    ASSERT_EQ(c.size(), 15u);
    if (c[2] == "out_of_travel") {
      EXPECT_EQ(c[1], "553");
      for (int a = 0; a < 5; ++a) EXPECT_EQ(c[3 + a], c[8 + a]);
    }
    if (c[2] != "compensated" || rows % 50) continue;
    JointVector q(5);
    for (int a = 0; a < 5; ++a) q[a] = std::stod(c[8 + a]) * (a >= 3 ? M_PI / 180 : 1.0);
    Eigen::Vector3d p, u;
    fk.tipAndAxis(q, &p, &u);
    // The machine after the measured set-up is not the file's: compare the change instead.
    JointVector q0(5);
    for (int a = 0; a < 5; ++a) q0[a] = std::stod(c[3 + a]) * (a >= 3 ? M_PI / 180 : 1.0);
    Eigen::Vector3d p0, u0;
    fk.tipAndAxis(q0, &p0, &u0);
    EXPECT_LT((p - p0).norm(), 0.05) << rows;  // corrections of micrometres, not a different pose
    ++checked;
  }
  EXPECT_EQ(rows, 723);
  EXPECT_GT(checked, 5);
}

// plan-ballbar --volume: the same design for predictions anywhere in the travel; its expected
// uncertainty over the travel is below the D-optimal plan's. With --for as well: exit 2.
TEST_F(UncertaintyCli, APlanForTheWholeTravel) {
  const std::string base = "plan-ballbar --machine " +
                           test::sourcePath("resources/machines/matsuura_mc760vx.xml") +
                           " --volume --poses 360 -o " + path("p.csv");
  auto r = test::runTolver(base);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::smatch m;
  ASSERT_TRUE(std::regex_search(
      r.output, m,
      std::regex("over the whole travel .* median ([0-9.]+) um, max ([0-9.]+) um; the "
                 "D-optimal plan of the same size: median ([0-9.]+) um, max ([0-9.]+) um")))
      << r.output;
  EXPECT_LT(std::stod(m[1]), std::stod(m[3]));
  EXPECT_LT(std::stod(m[2]), std::stod(m[4]));
  // A gain under 10 % is said to buy little, with the default plan as good.
  if (std::stod(m[1]) > 0.9 * std::stod(m[3]))
    EXPECT_NE(r.output.find("buys       little"), std::string::npos) << r.output;
  auto both = test::runTolver(base + " --for " + test::sourcePath("samples/nas979_cone.apt"));
  EXPECT_EQ(both.exit_code, 2) << both.output;
}

// The set-up a shop measures, from probed points, end to end: touches simulated on the true
// machine (the measured sample, where its tip really is at 12 of the cone's poses), given to
// predict --probed with the identified machine: the predicted deviations follow the truth's,
// and a bad probe file is exit 2 naming its line.
std::vector<std::vector<double>> columns(const std::string& csv, const char* a, const char* b,
                                         const char* c) {
  std::ifstream in(csv);
  std::string line;
  std::getline(in, line);
  std::vector<std::string> names;
  std::stringstream hs(line);
  for (std::string c; std::getline(hs, c, ',');) names.push_back(c);
  const auto col = [&](const char* n) {
    return std::find(names.begin(), names.end(), n) - names.begin();
  };
  const long x = col(a), y = col(b), z = col(c);
  std::vector<std::vector<double>> out;
  while (std::getline(in, line)) {
    std::vector<std::string> cells;
    std::stringstream ls(line);
    for (std::string c; std::getline(ls, c, ',');) cells.push_back(c);
    out.push_back({std::stod(cells[x]), std::stod(cells[y]), std::stod(cells[z])});
  }
  return out;
}

TEST_F(UncertaintyCli, PredictWithProbedPointsFollowsTheTruth) {
  const std::string id = identified();
  const std::string truth_file = test::sourcePath("samples/machines/matsuura_mc760vx_measured.xml");
  const std::string setup = test::sourcePath("samples/matsuura_setup.txt");
  const std::string cone = test::sourcePath("samples/nas979_cone.apt");
  Machine truth = readMachineFile(truth_file);
  truth.model.setup = readSetupFile(setup, truth.model.setup);
  const ClProgram program = readAptFile(cone);
  const PredictionResult pr = predictToolPath(truth.model, truth.params, program.path);
  ASSERT_TRUE(pr.ok());
  std::vector<ProbedPoint> probes;
  for (size_t i = 0; i < pr.points.size(); i += pr.points.size() / 12) {
    ProbedPoint p;
    p.q = pr.points[i].q;
    p.p_w = pr.points[i].p_pred_w;  // where the true machine puts the tip: the part is there
    p.probe_length = truth.model.setup.gauge_length;
    probes.push_back(p);
  }
  writeFileAtomically(path("probed.csv"), formatProbeCsv(truth.model, probes));
  const std::string base = "predict --cl " + cone + " --setup " + setup;
  auto t = test::runTolver(base + " --machine " + truth_file + " -o " + path("t.apt"));
  ASSERT_EQ(t.exit_code, 0) << t.output;
  auto r = test::runTolver(base + " --machine " + id + " --probed " + path("probed.csv") + " -o " +
                           path("p.apt"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("part set-up fitted to"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("uncertainty (1 sigma)"), std::string::npos) << r.output;
  auto deviations = [](const std::string& csv) {
    return columns(csv, "dev_x_um", "dev_y_um", "dev_z_um");
  };
  const auto dt = deviations(path("t.csv")), dp = deviations(path("p.csv"));
  ASSERT_EQ(dt.size(), dp.size());
  double own = 0, err = 0;
  for (size_t i = 0; i < dt.size(); ++i)
    for (int k = 0; k < 3; ++k) {
      own += dt[i][k] * dt[i][k];
      err += (dt[i][k] - dp[i][k]) * (dt[i][k] - dp[i][k]);
    }
  own = std::sqrt(own / dt.size());
  err = std::sqrt(err / dt.size());
  std::printf("[ probed ] truth's deviation RMS %.3f um, predicted against it %.3f um\n", own, err);
  EXPECT_LT(err, 0.3 * own);
  {
    // The set-up fit and its uncertainty are linear in the touches (issue 36): the same 12
    // touches 1 000 times over (12 000 rows) give the same prediction, where the uncertainty's
    // full U of the touches' SVD (36 000 x 36 000) ran out of memory.
    std::vector<ProbedPoint> many;
    for (int k = 0; k < 1000; ++k) many.insert(many.end(), probes.begin(), probes.end());
    writeFileAtomically(path("touches.csv"), formatProbeCsv(truth.model, many));
    auto m = test::runTolver(base + " --machine " + id + " --probed " + path("touches.csv") +
                             " -o " + path("many.apt"));
    ASSERT_EQ(m.exit_code, 0) << m.output;
    const auto dm = deviations(path("many.csv"));
    ASSERT_EQ(dm.size(), dp.size());
    double diff = 0;
    for (size_t i = 0; i < dm.size(); ++i)
      for (int k = 0; k < 3; ++k) diff = std::max(diff, std::abs(dm[i][k] - dp[i][k]));
    EXPECT_LT(diff, 1e-3);  // um
    const auto um = columns(path("many.csv"), "u_tip_um", "u_axis_urad", "u_tip_um");
    const auto up = columns(path("p.csv"), "u_tip_um", "u_axis_urad", "u_tip_um");
    ASSERT_EQ(um.size(), up.size());
    for (size_t i = 0; i < um.size(); i += 50) EXPECT_NEAR(um[i][0], up[i][0], 1e-3) << i;
  }
  // The tool axis: the touches cannot see the spindle's tilt; a tram (the truth's tool axis
  // against its table at the first touch's place, rotaries at zero) fits it.
  JointVector q = probes.front().q;
  q.tail<2>().setZero();
  probes.push_back(simulatedTram(truth, q));
  writeFileAtomically(path("tram.csv"), formatProbeCsv(truth.model, probes));
  auto w = test::runTolver(base + " --machine " + id + " --probed " + path("tram.csv") + " -o " +
                           path("w.apt"));
  ASSERT_EQ(w.exit_code, 0) << w.output;
  EXPECT_NE(w.output.find("spindle tilted"), std::string::npos) << w.output;
  EXPECT_NE(r.output.find("no tram"), std::string::npos) << r.output;
  auto axes = [](const std::string& csv) {
    return columns(csv, "predicted_i", "predicted_j", "predicted_k");
  };
  auto nominalAxes = [](const std::string& csv) {
    return columns(csv, "nominal_i", "nominal_j", "nominal_k");
  };
  const auto at = axes(path("t.csv")), ap = axes(path("p.csv")), aw = axes(path("w.csv")),
             an = nominalAxes(path("t.csv"));
  auto rmsAngle = [&](const std::vector<std::vector<double>>& u) {
    double s = 0;
    for (size_t i = 0; i < u.size(); ++i) {
      const Eigen::Vector3d a(u[i][0], u[i][1], u[i][2]), b(at[i][0], at[i][1], at[i][2]);
      s += (a.normalized() - b.normalized()).squaredNorm();
    }
    return std::sqrt(s / u.size());
  };
  const double axis_own = rmsAngle(an), axis_probed = rmsAngle(ap), axis_tram = rmsAngle(aw);
  std::printf(
      "[ tram ] tool axis against the truth: nominal %.1f urad, probed %.1f, probed + tram %.1f\n",
      axis_own * 1e6, axis_probed * 1e6, axis_tram * 1e6);
  EXPECT_LT(axis_tram, 0.5 * axis_own);
  EXPECT_LT(axis_tram, axis_probed);
  // Touches no rigid set-up explains (every other part point moved 30 mm): refused, nothing
  // written.
  std::vector<ProbedPoint> moved(probes.begin(), probes.end() - 1);
  for (size_t i = 0; i < moved.size(); i += 2) moved[i].p_w.x() += 30.0;
  writeFileAtomically(path("moved.csv"), formatProbeCsv(truth.model, moved));
  auto mv = test::runTolver(base + " --machine " + id + " --probed " + path("moved.csv") + " -o " +
                            path("m.apt"));
  EXPECT_EQ(mv.exit_code, 2) << mv.output;
  EXPECT_NE(mv.output.find("do not belong to this part and set-up"), std::string::npos)
      << mv.output;
  EXPECT_FALSE(std::filesystem::exists(path("m.apt")));
  // A bad row: exit 2, the file and line named.
  std::ofstream(path("bad.csv"))
      << "part_x_mm,part_y_mm,part_z_mm,x_mm,y_mm,z_mm,a_deg,c_deg\n1,2,3,4,5,6,x,8\n";
  auto b = test::runTolver(base + " --machine " + id + " --probed " + path("bad.csv") + " -o " +
                           path("b.apt"));
  EXPECT_EQ(b.exit_code, 2);
  EXPECT_NE(b.output.find("bad.csv:2"), std::string::npos) << b.output;
}

}  // namespace
}  // namespace tolver
