// tolver verify from the command line: verdicts and exit codes, report files, bad input, batch.
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>

#include "test_support.h"

namespace tolver {
namespace {

using test::runTolver;
using test::sourcePath;

class VerifyCli : public test::TempDirTest {
 protected:
  std::string base(const std::string& extra) const {
    return "verify --machine " + sourcePath("samples/machines/matsuura_mc760vx_measured.xml") +
           " --setup " + sourcePath("samples/matsuura_setup.txt") + " --cl " +
           sourcePath("samples/sculptured_finish.apt") + " --part " +
           sourcePath("samples/sculptured_part.obj") + " --spacing 1.2 " + extra;
  }
  static std::string slurp(const std::string& p) {
    std::ifstream in(p);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
  }
};

// The blame split adds up: in deviations.csv, total = program + machine at every sample whose
// deviation splits (to the 4 decimals written), on the main job and on a real 3-axis pocket
// (SolidWorks CAM, with its STL); the machine's share there stays within the tool's displacement
// on this machine (below 25 um: its tool-tip error is 14-18 um), and the JSON counts the rest.
TEST_F(VerifyCli, TheBlameSplitAddsUpOnEverySample) {
  const std::string m = sourcePath("samples/machines/matsuura_mc760vx_measured.xml");
  const std::vector<std::string> jobs = {
      base("--tolerance 0.03 --no-images --report-dir " + path("a")),
      "verify --machine " + m + " --part-zero 0,0,100 --gauge-length 100 --cl " +
          sourcePath("tests/fixtures/cl/swcam_Teste-Metrologia.apt") + " --part " +
          sourcePath("tests/fixtures/mesh/swcam_Teste-Metrologia.stl") +
          " --tolerance 0.05 --no-images --report-dir " + path("b")};
  for (size_t k = 0; k < jobs.size(); ++k) {
    const auto r = runTolver(jobs[k]);
    ASSERT_TRUE(r.exit_code == 0 || r.exit_code == 1) << r.output;
    const std::string dir = path(k ? "b" : "a");
    std::ifstream in(dir + "/deviations.csv");
    std::string line;
    int rows = 0, split = 0;
    std::map<std::string, int> col;
    while (std::getline(in, line)) {
      if (line.empty() || line[0] == '#') continue;
      std::vector<std::string> cells;
      std::stringstream ls(line);
      for (std::string c; std::getline(ls, c, ',');) cells.push_back(c);
      if (line.size() > 0 && line.back() == ',') cells.push_back("");
      if (col.empty()) {
        for (size_t c = 0; c < cells.size(); ++c) col[cells[c]] = static_cast<int>(c);
        ASSERT_TRUE(col.count("split")) << line;
        continue;
      }
      ++rows;
      if (cells[col["split"]] != "split") continue;
      ++split;
      const double t = std::stod(cells[col["total_um"]]), p = std::stod(cells[col["program_um"]]),
                   mm = std::stod(cells[col["machine_um"]]);
      EXPECT_NEAR(t, p + mm, 2e-4) << line;
      EXPECT_LT(std::abs(mm), 25.0) << line;
    }
    EXPECT_GT(split, 1000) << dir;
    const nlohmann::json j = nlohmann::json::parse(slurp(dir + "/report.json"));
    ASSERT_TRUE(j.contains("split")) << dir;
    EXPECT_TRUE(j["split"].contains("cut_boundary"));
  }
}

// Coverage is part of the verdict: the sculptured part with a 10 x 10 mm hole cut out of its top
// face (the face being checked) is INCOMPLETE (exit 1) with the hole's area, not "100 % in
// tolerance"; --allow-open accepts it and notes it.
TEST_F(VerifyCli, AHoleInTheCheckedFaceMakesTheVerdictIncomplete) {
  std::ifstream in(sourcePath("samples/sculptured_part.obj"));
  std::ofstream out(path("holed.obj"));
  std::vector<Eigen::Vector3d> v;
  int removed = 0;
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("v ", 0) == 0) {
      std::stringstream ls(line.substr(2));
      Eigen::Vector3d p;
      ls >> p.x() >> p.y() >> p.z();
      v.push_back(p);
    } else if (line.rfind("f ", 0) == 0) {
      std::stringstream ls(line.substr(2));
      Eigen::Vector3d c = Eigen::Vector3d::Zero();
      int n = 0;
      for (std::string tok; ls >> tok; ++n) c += v[std::stoi(tok.substr(0, tok.find('/'))) - 1];
      c /= n;
      // Top-face triangles with their centroid in the box [0, 10] x [0, 10].
      if (c.z() > -11 && c.x() > 0 && c.x() < 10 && c.y() > 0 && c.y() < 10) {
        ++removed;
        continue;
      }
    }
    out << line << "\n";
  }
  out.close();
  ASSERT_GT(removed, 100);
  const std::string job = "verify --machine " +
                          sourcePath("samples/machines/matsuura_mc760vx_measured.xml") +
                          " --setup " + sourcePath("samples/matsuura_setup.txt") + " --cl " +
                          sourcePath("samples/sculptured_finish.apt") + " --part " +
                          path("holed.obj") + " --spacing 1.2 --tolerance 0.05 --no-images";
  auto r = runTolver(job + " --report-dir " + path("h"));
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("tolver verify: INCOMPLETE"), std::string::npos) << r.output;
  const nlohmann::json j = nlohmann::json::parse(slurp(path("h/report.json")));
  EXPECT_EQ(j["verdict"], "incomplete");
  EXPECT_EQ(j["exit_code"], 1);
  std::smatch m;
  ASSERT_TRUE(std::regex_search(r.output, m, std::regex("([0-9.]+) mm2 not verified"))) << r.output;
  EXPECT_NEAR(std::stod(m[1]), 100.0, 15.0);  // the 10 x 10 mm hole (its border follows the grid)
  auto a = runTolver(job + " --allow-open --report-dir " + path("a"));
  EXPECT_EQ(a.exit_code, 0) << a.output;
  // The unmodified part has no hole.
  auto c = runTolver(base("--tolerance 0.05 --no-images --report-dir " + path("c")));
  EXPECT_EQ(c.exit_code, 0) << c.output;
  EXPECT_EQ(c.output.find("INCOMPLETE"), std::string::npos);
}

TEST_F(VerifyCli, InToleranceExitsZeroAndWritesTheReport) {
  const auto r = runTolver(base("--tolerance 0.05 --report-dir " + path("out")));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("PASS"), std::string::npos);
  for (const char* f : {"report.html", "report.json", "deviations.csv", "swept_predicted.ply",
                        "swept_predicted.vtp", "swept_nominal.ply", "swept_nominal.vtp",
                        "map_isometric.png", "map_top.png", "map_worst.png", "histogram.png"})
    EXPECT_TRUE(std::filesystem::exists(path("out/") + f)) << f;
  const auto j = nlohmann::json::parse(slurp(path("out/report.json")));
  EXPECT_EQ(j["verdict"], "pass");
  EXPECT_EQ(j["exit_code"], 0);
  EXPECT_GT(j["area"]["percent_in_tolerance"].get<double>(), 99.999);
  EXPECT_GT(j["deviation"]["machine"]["rms_um"].get<double>(), 0.5);  // the sample machine's errors
  EXPECT_LT(j["deviation"]["total"]["max_um"].get<double>(), 25.0);
  const std::string html = slurp(path("out/report.html"));
  EXPECT_NE(html.find("PASS"), std::string::npos);
  EXPECT_NE(html.find("data:image/png;base64,"), std::string::npos);
  EXPECT_EQ(slurp(path("out/swept_predicted.ply")).rfind("ply\nformat binary_little_endian", 0),
            0u);
}

TEST_F(VerifyCli, OutOfToleranceExitsOneWithRegionsAndTheirCause) {
  const auto r =
      runTolver(base("--tolerance 0.01 --no-images --line-pass 3 --report-dir " + path("out")));
  ASSERT_EQ(r.exit_code, 1) << r.output;
  const auto j = nlohmann::json::parse(slurp(path("out/report.json")));
  EXPECT_EQ(j["verdict"], "fail");
  ASSERT_GT(j["out_of_tolerance_regions"].size(), 0u);
  const auto& g = j["out_of_tolerance_regions"][0];
  EXPECT_TRUE(g["cause"] == "machine" || g["cause"] == "program");
  EXPECT_GT(g["worst_excursion_um"].get<double>(), 0.0);
  EXPECT_EQ(j["line_profile"]["pass"], 3);
  EXPECT_GT(j["line_profile"]["points"].size(), 50u);
}

// A region's worst deviation reads once with its unit, in the terminal and in the report, also
// where the cut goes deeper than the gouge search range (a 0.3 um range here): "-0.3 um or
// deeper (beyond the search range)", never "... deeper) um" nor "-0 um".
TEST_F(VerifyCli, ARegionsWorstDeviationReadsWithItsUnitOnce) {
  const auto r = runTolver(
      base("--tolerance 0.0004 --gouge-range 0.0003 --no-images --report-dir " + path("out")));
  ASSERT_EQ(r.exit_code, 1) << r.output;
  const std::regex plain(R"(region 1   (excess|gouge) [0-9.]+ mm2, worst [+-][0-9.]+ um at \()");
  const std::regex beyond(
      R"(region [0-9]   gouge [0-9.]+ mm2, worst -0\.3 um or deeper \(beyond the search range\) at \()");
  EXPECT_TRUE(std::regex_search(r.output, plain)) << r.output;
  EXPECT_TRUE(std::regex_search(r.output, beyond)) << r.output;
  EXPECT_EQ(r.output.find(") um"), std::string::npos) << r.output;
  const std::string html = slurp(path("out/report.html"));
  EXPECT_NE(html.find("um or deeper (beyond the search range), "), std::string::npos);
  EXPECT_NE(html.find("<td>-0.3 or deeper (beyond the search range)</td>"), std::string::npos);
}

TEST_F(VerifyCli, UnequalZonesFromAFile) {
  const std::string zones = write("zones.csv", "region,tolerance,uz,u\n*,0.03,,\ntop,0.03,,0.0\n");
  const auto r = runTolver(base("--zones " + zones + " --no-images --report-dir " + path("out")));
  // Everything left on top (scallops, +) is beyond an all-inside ASME U 0 zone.
  EXPECT_EQ(r.exit_code, 1) << r.output;
  const auto j = nlohmann::json::parse(slurp(path("out/report.json")));
  EXPECT_EQ(j["zones"][1]["upper_um"], 0.0);
  EXPECT_EQ(j["out_of_tolerance_regions"][0]["kind"], "excess");
}

TEST_F(VerifyCli, BadInputExitsTwoNamingTheFile) {
  auto r = runTolver(base("--tolerance 0.02 --report-dir " + path("out"))
                         .replace(base("").find("sculptured_part.obj"), 19, "missing_part.stl"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("missing_part.stl"), std::string::npos) << r.output;
  const std::string zones = write("bad.csv", "region,tolerance\n*,0.02\ntop,-1\n");
  r = runTolver(base("--zones " + zones + " --report-dir " + path("out")));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("bad.csv:3"), std::string::npos) << r.output;
  r = runTolver(base("--report-dir " + path("out")));  // no tolerance
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("--tolerance"), std::string::npos) << r.output;
  // A zone name with an invalid UTF-8 byte: the report is written and
  // reads back as JSON.
  const std::string zbad = write("zbad.csv",
                                 "region,tolerance\n*,0.05\n\xcb"
                                 "bad,0.03\n");
  r = runTolver("verify --machine " + sourcePath("samples/machines/matsuura_mc760vx_measured.xml") +
                " --setup " + sourcePath("samples/matsuura_setup.txt") + " --cl " +
                sourcePath("samples/nas979_cone.apt") + " --zones " + zbad +
                " --no-images --report-dir " + path("z"));
  EXPECT_TRUE(r.exit_code == 0 || r.exit_code == 1) << r.output;
  EXPECT_NO_THROW(nlohmann::json::parse(slurp(path("z") + "/report.json")));
  // A report directory below a regular file: exit 2 naming it, not 3.
  const std::string file = write("plain.txt", "x");
  r = runTolver("verify --machine " + sourcePath("samples/machines/matsuura_mc760vx_measured.xml") +
                " --setup " + sourcePath("samples/matsuura_setup.txt") + " --cl " +
                sourcePath("samples/nas979_cone.apt") +
                " --tolerance 0.05 --no-images --report-dir " + file + "/out");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("--report-dir"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("internal error"), std::string::npos) << r.output;
}

// A part that is not where the program cuts (here moved 500 mm by --mesh-offset) is an error
// that says so, never a verdict on the few samples a rapid grazes (issue 32).
TEST_F(VerifyCli, APartAwayFromTheProgramIsAnError) {
  const auto r =
      runTolver(base("--tolerance 0.05 --mesh-offset 500,0,0 --report-dir " + path("away")));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("the part is not where the program cuts"), std::string::npos) << r.output;
  EXPECT_FALSE(std::filesystem::exists(path("away")));
}

TEST_F(VerifyCli, MalformedJobsFileExitsTwoNamingItsLine) {
  const std::string jobs =
      write("jobs.csv", "name,machine,cl,part,tolerance\nok/../x,m.xml,a.apt,,0.02\n");
  auto r = runTolver("verify --batch " + jobs + " --report-dir " + path("out"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("jobs.csv:2"), std::string::npos) << r.output;
  r = runTolver("verify --batch " + write("empty.csv", "") + " --report-dir " + path("out"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  r = runTolver("verify --batch " + write("nocol.csv", "name,cl\nx,a.apt\n") + " --report-dir " +
                path("out"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  // Two jobs of one name: the second named by its line.
  r = runTolver(
      "verify --batch " +
      write("twice.csv",
            "name,machine,cl,part,tolerance\nj,m.xml,a.apt,,0.02\nj,m.xml,b.apt,,0.02\n") +
      " --report-dir " + path("out"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("twice.csv:3"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("named twice"), std::string::npos) << r.output;
  EXPECT_FALSE(std::filesystem::exists(path("out/summary.csv")));
}

TEST_F(VerifyCli, ClOnlyModeWithoutAPart) {
  // verify on the measured Matsuura without a part: the report's JSON.
  auto clOnly = [&](const std::string& program, const std::string& out) {
    const auto r = runTolver(
        "verify --machine " + sourcePath("samples/machines/matsuura_mc760vx_measured.xml") +
        " --setup " + sourcePath("samples/matsuura_setup.txt") + " --cl " + sourcePath(program) +
        " --tolerance 0.05 --no-images --report-dir " + path(out));
    EXPECT_EQ(r.exit_code, 0) << r.output;
    // --no-images: the files the report line lists are those written (it listed *.png).
    EXPECT_NE(r.output.find("swept_*.ply/.vtp)"), std::string::npos) << r.output;
    EXPECT_EQ(r.output.find("*.png"), std::string::npos) << r.output;
    return nlohmann::json::parse(slurp(path(out + "/report.json")));
  };
  const auto j = clOnly("samples/nas979_cone.apt", "out");
  EXPECT_EQ(j["mode"], "cl-only");
  // The machine moves the tool about 10 um (tolver predict's figure for this program).
  EXPECT_GT(j["deviation"]["machine"]["max_um"].get<double>() -
                j["deviation"]["machine"]["min_um"].get<double>(),
            1.0);
  // A flank pass once around the cone: its tips form no surface, and the report says how the
  // deviation was taken instead (not a surface of strips to the approach move, as before).
  EXPECT_EQ(j["area"]["total_mm2"].get<double>(), 0.0);
  EXPECT_NE(j["notes"].dump().find("722 of the 722 points lie on no surface"), std::string::npos)
      << j["notes"].dump();
  // The sculptured finish's passes, 0.5 mm apart over the 80 x 60 mm top: a surface of about its
  // area, every point on it.
  const auto k = clOnly("samples/sculptured_finish.apt", "sculptured");
  EXPECT_GT(k["area"]["total_mm2"].get<double>(), 80 * 60);
  EXPECT_LT(k["area"]["total_mm2"].get<double>(), 1.1 * 80 * 60);
  EXPECT_EQ(k["notes"].dump().find("on no surface"), std::string::npos) << k["notes"].dump();
}

TEST_F(VerifyCli, BatchVerifiesJobsInParallelAndSummarises) {
  const std::string m = sourcePath("samples/machines/matsuura_mc760vx_measured.xml");
  const std::string jobs = write("jobs.csv",
                                 "name,machine,cl,part,tolerance,setup\n"
                                 "loose," +
                                     m + "," + sourcePath("samples/sculptured_finish.apt") + "," +
                                     sourcePath("samples/sculptured_part.obj") + ",0.05," +
                                     sourcePath("samples/matsuura_setup.txt") +
                                     "\n"
                                     "tight," +
                                     m + "," + sourcePath("samples/sculptured_finish.apt") + "," +
                                     sourcePath("samples/sculptured_part.obj") + ",0.01," +
                                     sourcePath("samples/matsuura_setup.txt") + "\n");
  const auto r = runTolver("verify --batch " + jobs + " --spacing 1.5 --no-images --report-dir " +
                           path("out"));
  EXPECT_EQ(r.exit_code, 1) << r.output;  // one job fails
  const std::string summary = slurp(path("out/summary.csv"));
  EXPECT_NE(summary.find("loose,pass"), std::string::npos) << summary;
  EXPECT_NE(summary.find("tight,fail"), std::string::npos) << summary;
  EXPECT_TRUE(std::filesystem::exists(path("out/loose/report.json")));
  EXPECT_TRUE(std::filesystem::exists(path("out/tight/report.json")));
}

}  // namespace
}  // namespace tolver

namespace tolver {
namespace {

// A STEP part (samples/nas979_cone.step, the B-rep twin of nas979_cone.stl written by OCCT):
// zones name its CAD faces by colour, the report has a row per CAD face, and the verdict is the
// STL's (the same share of the machined area in tolerance, within the two tessellations' gap).
TEST_F(VerifyCli, AStepPartIsCheckedFaceByFaceAndAgreesWithItsStl) {
  const std::string cone = "verify --machine " +
                           sourcePath("samples/machines/matsuura_mc760vx_measured.xml") +
                           " --setup " + sourcePath("samples/matsuura_setup.txt") + " --cl " +
                           sourcePath("samples/nas979_cone.apt") + " --spacing 2 --no-images ";
  const std::string zones = write("flank.csv", "region,tolerance\ncolour #e77c7c,0.02\n");
  auto r = runTolver(cone + "--part " + sourcePath("samples/nas979_cone.step") + " --zones " +
                     zones + " --report-dir " + path("step"));
  ASSERT_TRUE(r.exit_code == 0 || r.exit_code == 1) << r.output;
  EXPECT_NE(r.output.find("8 CAD faces"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("tessellated within 1 um"), std::string::npos) << r.output;
  const auto j = nlohmann::json::parse(slurp(path("step") + "/report.json"));
  const auto& faces = j["part"]["cad_faces"];
  ASSERT_EQ(faces.size(), 8u) << j["part"].dump();
  int flanks = 0;
  for (const auto& f : faces) {
    const bool flank = !f["aliases"].empty() && f["aliases"][0] == "colour #e77c7c";
    flanks += flank;
    if (flank) {
      EXPECT_GT(f["checked_mm2"].get<double>(), 0.9 * f["area_mm2"].get<double>());
      EXPECT_NEAR(f["area_mm2"].get<double>(), 9013.06, 0.5);  // pi (R0 + R1) s of the frustum
    } else {
      EXPECT_EQ(f["checked_mm2"].get<double>(), 0.0) << f.dump();
    }
  }
  EXPECT_EQ(flanks, 1);
  const std::string html = slurp(path("step") + "/report.html");
  EXPECT_NE(html.find("CAD faces"), std::string::npos);
  // Each row is addressable: the id of "face #376" is "region-face-376" (an HTML id holds no
  // space).
  for (const auto& f : faces) {
    std::string id = f["region"].get<std::string>();
    id.replace(id.find(" #"), 2, "-");
    EXPECT_NE(html.find("<tr id=\"region-" + id + "\">"), std::string::npos) << id;
  }
  // The same zone on the STL (its flank is the region "part" there: the whole part with --tolerance
  // limited to the flank is not expressible, so compare the flank rows' in-tolerance share).
  const std::string flank_only = write("flank_stl.csv", "region,tolerance\n*,0.02\n");
  auto s = runTolver(cone + "--part " + sourcePath("samples/nas979_cone.stl") + " --zones " +
                     flank_only + " --report-dir " + path("stl"));
  auto t = runTolver(cone + "--part " + sourcePath("samples/nas979_cone.step") + " --zones " +
                     flank_only + " --report-dir " + path("step_all"));
  const std::regex area("area +([0-9.]+) % of ([0-9.]+) mm2 machined in tolerance");
  std::smatch ms, mt;
  ASSERT_TRUE(std::regex_search(s.output, ms, area)) << s.output;
  ASSERT_TRUE(std::regex_search(t.output, mt, area)) << t.output;
  EXPECT_NEAR(std::stod(mt[1]), std::stod(ms[1]), 1.5);
  EXPECT_NEAR(std::stod(mt[2]), std::stod(ms[2]), 0.05 * std::stod(ms[2]));  // sampling at 2 mm
  // A zone naming no face: exit 2, and the message lists the names it could have used.
  const std::string bad = write("bad.csv", "region,tolerance\ncolour #000000,0.02\n");
  r = runTolver(cone + "--part " + sourcePath("samples/nas979_cone.step") + " --zones " + bad +
                " --report-dir " + path("bad"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("bad.csv"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("'colour #e77c7c'"), std::string::npos) << r.output;
  // STEP files carry their units: --mesh-units is refused.
  r = runTolver(cone + "--part " + sourcePath("samples/nas979_cone.step") +
                " --tolerance 0.02 --mesh-units inch --report-dir " + path("units"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
}

}  // namespace
}  // namespace tolver
