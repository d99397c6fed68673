// The real programs of ../shared/data (other people's CAM systems and posts, none written for
// tolver), end to end as a planner runs them: setup, then predict with the set-up it wrote (or,
// when setup finds none, predict on the defaults), and verify where the part is there. Each
// outcome is asserted: predicted, split into named pieces, or refused for the reason named here
// (a refusal that blames another construct fails). A program found in ../shared/data and not in
// the table must still be read or refused with file and line, never crash. Label: corpus.
// Skipped, saying so, when ../shared is not beside the checkout (the project never reads it at
// run time; only this test does).
#include <gtest/gtest.h>

#include <filesystem>
#include <set>
#include <string>

#include "machine_errors.h"
#include "pipeline/compensate.h"
#include "test_support.h"

namespace tolver {
namespace {

namespace fs = std::filesystem;

struct Expected {
  const char* file;     // under ../shared/data
  const char* machine;  // under the source tree
  const char* options;  // more options for setup and predict
  int setup_exit;
  const char* setup_says;
  int predict_exit;  // with the set-up setup wrote (or the defaults when it wrote none)
  const char* predict_says;
};

constexpr const char* kVmc = "resources/machines/vmc_3axis_iso.xml";
constexpr const char* kMatsuura = "resources/machines/matsuura_mc760vx.xml";
constexpr const char* kSinumerik = "resources/machines/sinumerik_bc_table.xml";

const Expected kCorpus[] = {
    // Three-axis posted G-code: the part zero is the work offset; setup proposes it exactly.
    {"corpus/cambam_contour1.nc", kVmc, "", 0, "exact: each axis's range centred", 0, "deviation"},
    {"corpus/fabex_Op_Plane_1.tap", kVmc, "", 0, "exact: each axis's range centred", 0,
     "deviation"},
    {"corpus/freecad_grbl_platteyz-helix.nc", kVmc, "", 0, "exact: each axis's range centred", 0,
     "deviation"},
    {"corpus/fusion_led-floor_1124_jig.nc", kVmc, "", 0, "exact: each axis's range centred", 0,
     "deviation"},
    // G10 L2 sets the work offsets in machine coordinates for CAMotics' own machine, whose
    // travel is centred on zero: no set-up moves them, and they are outside this machine's.
    {"corpus/camotics-ex_botomata_bottom.nc", kVmc, "", 1,
     "a work offset the program sets itself (G10)", 2, "unreachable: axis"},
    // G53 X10 Y-10 at the end: a home position beyond this machine's X travel.
    {"corpus/linuxcnc-tests_Cereal.ngc", kVmc, "", 1,
     "a move in machine coordinates (G53/G28/SUPA) is outside X's travel by 10.000 mm", 2,
     "Cereal.ngc:2270: unreachable: axis X"},
    // Sinumerik 840D as NX posts it (DEF, SUPA, TRAFOOF, MCALL CYCLE81).
    {"corpus/nx_sin840d_Keychain.mpf", kSinumerik, "", 0, "every point inside travel", 0,
     "deviation"},
    // CL data: drilling cycles expanded, NX's MCS kept as the part frame.
    {"corpus/nx_deep_drill.clsf", kVmc, "", 0, "every point inside travel", 0, "deviation"},
    {"corpus/swcam_basemach.apt", kMatsuura, "", 0, "every point inside travel", 0, "deviation"},
    {"corpus/creo_schruppen_1.ncl", kVmc, "", 0, "every point inside travel", 0, "deviation"},
    // Its rapids rise 548 mm above the cut (Z travel 508): split into pieces, each named.
    {"corpus/nx_10_KONTUR_125_N2_162.cls", kVmc, "", 1,
     "no single set-up reaches the whole program", 2, "unreachable: axis Z"},
    {"cl/nx_ust_a.cls", kMatsuura, "", 1, "--absolute-msys", 2, "unreachable"},
    {"cl/nx_ust_a.cls", kMatsuura, "--absolute-msys", 1,
     "2 set-ups reach the program, one piece each", 2, "unreachable"},
    {"cl/nx_nurbs.clsf", kMatsuura, "", 2, "nx_nurbs.clsf:13: NURBS: NURBS motion is not supported",
     2, "NURBS motion is not supported"},
    {"cl/nx_cutcom.clsf", kMatsuura, "", 0, "every point inside travel", 0, "deviation"},
    {"cl/nx_TORETC_250_BOK.cls", kMatsuura, "", 0, "every point inside travel", 0, "deviation"},
    {"cl/swcam_Teste-Metrologia.apt", kMatsuura, "", 0, "every point inside travel", 0,
     "deviation"},
    {"cl/swcam_RotateThick.apt", kMatsuura, "", 0, "every point inside travel", 0, "deviation"},
    {"cl/swcam_Interface-glue.apt", kMatsuura, "", 0, "every point inside travel", 0, "deviation"},
    {"cl/creo_profile_milling.ncl", kMatsuura, "", 0, "every point inside travel", 0, "deviation"},
    {"cl/creo_drilling.ncl", kMatsuura, "", 0, "every point inside travel", 0, "deviation"},
    // LinuxCNC's simulated trt machines (small travel: the xyzac boat needs two set-ups).
    {"gcode/linuxcnc_boat-xyzac.ngc", "resources/machines/linuxcnc_xyzac_trt.xml",
     "--gauge-lengths 100", 1, "no single set-up reaches the whole program", 2,
     "unreachable: axis Y"},
    {"gcode/linuxcnc_boat-xyzbc.ngc", "resources/machines/linuxcnc_xyzbc_trt.xml", "", 0,
     "every point inside travel", 0, "deviation"},
    {"gcode/linuxcnc_xyzab-tdr-demo.ngc", "tests/fixtures/machines/xyzab_tdr_like.xml", "", 0,
     "every point inside travel", 0, "deviation"},
};

fs::path sharedData() { return fs::path(TOLVER_SOURCE_DIR) / ".." / "shared" / "data"; }

class Corpus : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!fs::is_directory(sharedData()))
      GTEST_SKIP() << "../shared/data is not beside the checkout: the corpus is not run";
    dir_ = fs::temp_directory_path() / ("tolver_corpus_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ec;
    if (!dir_.empty()) fs::remove_all(dir_, ec);
  }
  fs::path dir_;
};

std::string q(const fs::path& p) { return "'" + p.string() + "'"; }

TEST_F(Corpus, EveryProgramIsPredictedSplitOrRefusedForItsOwnReason) {
  int k = 0;
  for (const Expected& e : kCorpus) {
    SCOPED_TRACE(std::string(e.file) + " " + e.options);
    const fs::path program = sharedData() / e.file;
    ASSERT_TRUE(fs::exists(program)) << "missing from ../shared/data";
    const std::string machine = test::sourcePath(e.machine);
    const fs::path setup = dir_ / ("setup" + std::to_string(++k) + ".txt");
    const auto s = test::runTolver("setup --machine " + q(machine) + " --cl " + q(program) + " " +
                                   e.options + " -o " + q(setup));
    EXPECT_EQ(s.exit_code, e.setup_exit) << s.output;
    EXPECT_NE(s.output.find(e.setup_says), std::string::npos) << s.output;
    std::string with_setup;
    if (fs::exists(setup)) with_setup = " --setup " + q(setup);
    std::string options = e.options;
    if (options.find("--gauge-lengths") != std::string::npos) options.clear();
    const auto p =
        test::runTolver("predict --machine " + q(machine) + " --cl " + q(program) + with_setup +
                        " " + options + " -o " + q(dir_ / ("p" + std::to_string(k) + ".apt")));
    EXPECT_EQ(p.exit_code, e.predict_exit) << p.output;
    EXPECT_NE(p.output.find(e.predict_says), std::string::npos) << p.output;
  }
}

// A program in ../shared/data that the table does not name (more are added to judge the
// reader): read and predicted, or refused with the file and a line; never a crash.
TEST_F(Corpus, AProgramTheTableDoesNotNameIsReadOrRefusedWithItsLine) {
  std::set<std::string> named;
  for (const Expected& e : kCorpus) named.insert(e.file);
  static const std::set<std::string> programs = {".nc",   ".ngc", ".tap",   ".mpf", ".apt", ".cls",
                                                 ".clsf", ".ncl", ".gcode", ".cnc", ".eia", ".h"};
  for (const char* sub : {"corpus", "cl", "gcode"}) {
    if (!fs::is_directory(sharedData() / sub)) continue;
    for (const auto& entry : fs::directory_iterator(sharedData() / sub)) {
      const std::string rel = std::string(sub) + "/" + entry.path().filename().string();
      if (named.count(rel) || !programs.count(entry.path().extension().string())) continue;
      SCOPED_TRACE(rel);
      const auto s = test::runTolver("setup --machine " + q(test::sourcePath(kVmc)) + " --cl " +
                                     q(entry.path()));
      EXPECT_LE(s.exit_code, 2) << s.output;
      if (s.exit_code == 2)
        EXPECT_NE(s.output.find(entry.path().filename().string() + ":"), std::string::npos)
            << s.output;
    }
  }
}

// Every CL program of the table that predicts, compensated on its machine with random errors (5 um,
// 20 urad a coefficient) in blocks of 61 points and whole: the same program and joints, byte for
// byte, and the same report (issue 36: compensate streams CL data).
TEST_F(Corpus, EveryClProgramIsCompensatedInBlocksAsItIsWhole) {
  int k = 0, compared = 0;
  for (const Expected& e : kCorpus) {
    const std::string ext = fs::path(e.file).extension().string();
    if (e.predict_exit != 0 || ext == ".nc" || ext == ".ngc" || ext == ".tap" || ext == ".mpf")
      continue;
    SCOPED_TRACE(std::string(e.file) + " " + e.options);
    const fs::path program = sharedData() / e.file;
    const fs::path setup = dir_ / ("s" + std::to_string(++k) + ".txt");
    const auto s = test::runTolver("setup --machine " + q(test::sourcePath(e.machine)) + " --cl " +
                                   q(program) + " " + e.options + " -o " + q(setup));
    ASSERT_EQ(s.exit_code, 0) << s.output;
    const fs::path machine = dir_ / ("m" + std::to_string(k) + ".xml");
    test::writeMachineWithErrors(test::sourcePath(e.machine), k, machine.string());
    CompensateInputs in;
    in.machine.machine = machine.string();
    in.machine.setup = setup.string();
    in.program.cl = program.string();
    std::string text[2], joints[2], report[2];
    for (int blocks = 0; blocks < 2; ++blocks) {
      in.block_points = blocks ? 61 : 0;
      in.output = (dir_ / ("c" + std::to_string(k) + "_" + std::to_string(blocks) + ext)).string();
      in.report = (dir_ / ("r" + std::to_string(blocks) + ".json")).string();
      const CompensateRun run = compensateProgram(in);
      ASSERT_TRUE(run.compensation);
      EXPECT_EQ(run.verdict, Verdict::Ok);
      text[blocks] = test::readText(in.output);
      joints[blocks] = test::readText(run.joints);
      // The report but for the names of the files written.
      std::string r = test::readText(in.report);
      for (const char* key : {"\"output\"", "\"joints_file\""})
        r.erase(r.find(key), r.find('\n', r.find(key)) - r.find(key));
      report[blocks] = r;
      // Compensated where the machine can: a 3-axis machine leaves no point unconverged.
      EXPECT_EQ(run.compensation->report.not_converged, 0);
    }
    EXPECT_EQ(text[0], text[1]);
    EXPECT_EQ(joints[0], joints[1]);
    EXPECT_EQ(report[0], report[1]);
    ++compared;
  }
  EXPECT_GE(compared, 9);
}

// Verify where the part is in ../shared/data: the Teste-Metrologia finish passes a 0.1 mm
// profile on a nominal machine (the program's own scallops, up to 40 um).
TEST_F(Corpus, VerifyARealPartWithItsProgram) {
  const fs::path cl = sharedData() / "cl/swcam_Teste-Metrologia.apt";
  const fs::path part = sharedData() / "mesh/swcam_Teste-Metrologia.stl";
  ASSERT_TRUE(fs::exists(cl) && fs::exists(part));
  const std::string machine = test::sourcePath(kMatsuura);
  const auto s = test::runTolver("setup --machine " + q(machine) + " --cl " + q(cl) + " -o " +
                                 q(dir_ / "s.txt"));
  ASSERT_EQ(s.exit_code, 0) << s.output;
  const auto v = test::runTolver("verify --machine " + q(machine) + " --setup " +
                                 q(dir_ / "s.txt") + " --cl " + q(cl) + " --part " + q(part) +
                                 " --tolerance 0.1 --report-dir " + q(dir_ / "report"));
  EXPECT_EQ(v.exit_code, 0) << v.output;
  EXPECT_NE(v.output.find("tolver verify: PASS"), std::string::npos) << v.output;
  EXPECT_TRUE(fs::exists(dir_ / "report" / "report.json"));
  // A program that changes tools is swept with each tool's own cutter, from its line on.
  const fs::path glue = sharedData() / "cl/swcam_Interface-glue.apt";
  const auto g = test::runTolver("verify --machine " + q(machine) + " --setup " +
                                 q(dir_ / "s.txt") + " --cl " + q(glue) + " --part " +
                                 q(sharedData() / "mesh/swcam_Interface-glue.stl") +
                                 " --tolerance 0.1 --report-dir " + q(dir_ / "glue"));
  EXPECT_NE(g.output.find("4 tools, each from its line on: line 4 flat end D6.5 mm"),
            std::string::npos)
      << g.output;
  EXPECT_NE(g.output.find("line 163 ball end D14 mm"), std::string::npos) << g.output;
}

}  // namespace
}  // namespace tolver
