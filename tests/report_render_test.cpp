// The HTML report as a planner opens it: rendered by headless Chromium (Debian's package, installed
// by scripts/install_deps.sh) from the file alone, with no network: the verdict comes first (the
// red FAIL badge at the top), the worst regions' map thumbnails load (the embedded PNGs show the
// map's in-tolerance green), and the tables are in the page.
#include <gtest/gtest.h>
#include <vtkImageData.h>
#include <vtkNew.h>
#include <vtkPNGReader.h>

#include <cstdio>
#include <filesystem>

#include "test_support.h"

namespace tolver {
namespace {

namespace fs = std::filesystem;

class ReportRender : public test::TempDirTest {
 protected:
  // Runs Chromium headless on a file with the given extra arguments; returns its stdout.
  std::string chromium(const std::string& args) {
    const std::string cmd =
        "timeout 120 /usr/bin/chromium --headless --no-sandbox --disable-gpu --disable-quic "
        "--no-first-run --disable-background-networking --disable-component-update "
        "--disable-sync --user-data-dir=" +
        path("profile") + " " + args + " 2>/dev/null";
    std::string out;
    if (FILE* p = popen(cmd.c_str(), "r")) {
      char buf[4096];
      size_t n;
      while ((n = fread(buf, 1, sizeof buf, p)) > 0) out.append(buf, n);
      pclose(p);
    }
    return out;
  }
};

TEST_F(ReportRender, TheReportOpensOnTheVerdictWithItsImagesAndTables) {
  ASSERT_TRUE(fs::exists("/usr/bin/chromium"))
      << "chromium is missing: run scripts/install_deps.sh";
  const auto r = test::runTolver(
      "verify --machine " + test::sourcePath("samples/machines/matsuura_mc760vx_measured.xml") +
      " --setup " + test::sourcePath("samples/matsuura_setup.txt") + " --cl " +
      test::sourcePath("samples/sculptured_finish.apt") + " --part " +
      test::sourcePath("samples/sculptured_part.obj") +
      " --spacing 1.2 --tolerance 0.012 --report-dir " + path("rep"));
  ASSERT_EQ(r.exit_code, 1) << r.output;
  const std::string url = "file://" + path("rep/report.html");
  const std::string dom = chromium("--dump-dom " + url);
  ASSERT_FALSE(dom.empty());
  EXPECT_NE(dom.find(">FAIL<"), std::string::npos);
  EXPECT_NE(dom.find("Worst regions"), std::string::npos);
  EXPECT_LT(dom.find(">FAIL<"), dom.find("<table"));  // the verdict before any figure
  EXPECT_NE(dom.find("Out-of-tolerance regions"), std::string::npos);
  EXPECT_NE(dom.find("class=\"thumb\""), std::string::npos);
  chromium("--window-size=1280,1000 --screenshot=" + path("shot.png") + " " + url);
  ASSERT_TRUE(fs::exists(path("shot.png")));
  vtkNew<vtkPNGReader> reader;
  reader->SetFileName(path("shot.png").c_str());
  reader->Update();
  vtkImageData* img = reader->GetOutput();
  int dims[3];
  img->GetDimensions(dims);
  ASSERT_EQ(dims[0], 1280);
  auto count = [&](int y0, int y1, auto&& match) {
    int n = 0;
    for (int y = y0; y < y1; ++y)
      for (int x = 0; x < dims[0]; ++x) {
        int c[3];
        for (int k = 0; k < 3; ++k)
          c[k] = static_cast<int>(img->GetScalarComponentAsDouble(x, y, 0, k));
        n += match(c);
      }
    return n;
  };
  // PNG rows from the bottom in VTK: the top 150 px of the page hold the red badge.
  const int badge = count(dims[1] - 150, dims[1],
                          [](const int* c) { return c[0] > 170 && c[1] < 30 && c[2] < 30; });
  EXPECT_GT(badge, 500);
  // The thumbnails below it: the map's in-tolerance green.
  const int green = count(0, dims[1] - 150, [](const int* c) {
    return std::abs(c[0] - 46) < 20 && std::abs(c[1] - 160) < 25 && std::abs(c[2] - 67) < 20;
  });
  EXPECT_GT(green, 5000);
}

}  // namespace
}  // namespace tolver
