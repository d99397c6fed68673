// The HTML report as a planner opens it: rendered by headless Chromium (Debian's package, installed
// by scripts/install_deps.sh) from the file alone, with no network: the verdict comes first (the
// red FAIL badge at the top), the worst regions' map thumbnails load (the embedded PNGs show the
// map's in-tolerance green), and the tables are in the page.
#include <gtest/gtest.h>
#include <vtkImageData.h>
#include <vtkNew.h>
#include <vtkPNGReader.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

#include "test_support.h"

namespace tolver {
namespace {

namespace fs = std::filesystem;

class ReportRender : public test::TempDirTest {
 protected:
  // Runs Chromium headless on a file with the given extra arguments; returns its stdout.
  std::string chromium(const std::string& args) {
    const std::string cmd =
        "timeout 300 /usr/bin/chromium --headless --no-sandbox --disable-gpu --disable-quic "
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
  // The report with the test's script (kViewProbe) added before </body>, opened in Chromium:
  // what the script wrote.
  nlohmann::json probe(const std::string& report, const std::string& flags);
  // tolver verify of the sculptured sample job on the measured Matsuura, with `options`.
  test::RunResult verifySample(const std::string& options) {
    return test::runTolver("verify --machine " +
                           test::sourcePath("samples/machines/matsuura_mc760vx_measured.xml") +
                           " --setup " + test::sourcePath("samples/matsuura_setup.txt") + " --cl " +
                           test::sourcePath("samples/sculptured_finish.apt") + " --part " +
                           test::sourcePath("samples/sculptured_part.obj") + " " + options);
  }
};

TEST_F(ReportRender, TheReportOpensOnTheVerdictWithItsImagesAndTables) {
  ASSERT_TRUE(fs::exists("/usr/bin/chromium"))
      << "chromium is missing: run scripts/install_deps.sh";
  const auto r = verifySample("--spacing 1.2 --tolerance 0.012 --report-dir " + path("rep"));
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

// The script the test adds to the report (the report's own code stays as written): after the
// page has loaded, it turns shading off (the legend's colours exactly) and the out-of-tolerance
// wire off, looks from the top, reads the canvas's pixels, then clicks (pointer events on the
// canvas) where chosen samples are drawn and reads the pick panel each time.
const char* kViewProbe = R"js(
<script>
window.addEventListener('load', function () {
  const out = {};
  try {
    const tv = window.tolverView;
    document.getElementById('tv-shading').click();
    document.getElementById('tv-out').click();
    tv.setView('top');
    const gl = tv.renderer.getContext();
    const w = gl.drawingBufferWidth, h = gl.drawingBufferHeight;
    const px = new Uint8Array(4 * w * h);
    gl.readPixels(0, 0, w, h, gl.RGBA, gl.UNSIGNED_BYTE, px);
    const legend = Array.from(document.querySelectorAll('.tv-legend td.sw')).map(function (td) {
      return getComputedStyle(td).backgroundColor.match(/\d+/g).map(Number);
    });
    let part = 0, matched = 0;
    const perColour = legend.map(function () { return 0; });
    for (let i = 0; i < w * h; ++i) {
      const r = px[4 * i], g = px[4 * i + 1], b = px[4 * i + 2];
      if (r === 255 && g === 255 && b === 255) continue;
      ++part;
      for (let k = 0; k < legend.length; ++k)
        if (Math.abs(r - legend[k][0]) <= 2 && Math.abs(g - legend[k][1]) <= 2 &&
            Math.abs(b - legend[k][2]) <= 2) { ++matched; ++perColour[k]; break; }
    }
    out.width = w; out.height = h; out.part = part; out.matched = matched;
    out.legend = legend; out.per_colour = perColour; out.vertices = tv.vertices;
    // Clicks where samples are drawn: every 97th vertex, projected to the window.
    const rect = tv.canvas.getBoundingClientRect();
    const pos = tv.predicted.geometry.getAttribute('position').array;
    out.picks = [];
    out.misses = 0;
    for (let v = 0; v < tv.vertices && out.picks.length < 40; v += 97) {
      const p = new THREE.Vector3(pos[3 * v], pos[3 * v + 1], pos[3 * v + 2]).project(tv.camera);
      const x = rect.left + (p.x + 1) / 2 * rect.width, y = rect.top + (1 - p.y) / 2 * rect.height;
      for (const type of ['pointerdown', 'pointerup'])
        tv.canvas.dispatchEvent(new PointerEvent(type, {clientX: x, clientY: y, bubbles: true}));
      const d = document.getElementById('tolver-pick').dataset;
      if (d.sample === undefined) { ++out.misses; continue; }  // edge-on: the ray meets nothing
      // Where the picked sample is drawn, in window pixels from the click.
      let k = 0;
      while (k < tv.vertices && tv.sample[k] !== Number(d.sample)) ++k;
      const q = new THREE.Vector3(pos[3 * k], pos[3 * k + 1], pos[3 * k + 2]).project(tv.camera);
      const miss = Math.hypot(rect.left + (q.x + 1) / 2 * rect.width - x,
                              rect.top + (1 - q.y) / 2 * rect.height - y);
      out.picks.push({vertex: v, x: x, y: y, sample: Number(d.sample), total: d.total, program: d.program,
                      machine: d.machine, line: Number(d.line), face: d.face, miss_px: miss});
    }
    // A CAD faces table's link: the face outlined in the view.
    const link = document.querySelector('a[data-face]');
    if (link) {
      link.click();
      const index = tv.highlight.geometry.getIndex();
      out.face_link = {face: Number(link.dataset.face), visible: tv.highlight.visible,
                       triangles: index ? index.count / 3 : 0};
    }
  } catch (e) {
    out.error = String(e) + ' ' + (e.stack || '');
  }
  const pre = document.createElement('pre');
  pre.id = 'tv-test';
  pre.textContent = JSON.stringify(out);
  document.body.appendChild(pre);
});
</script>
)js";

std::string unescapeHtml(std::string s) {
  for (const auto& [from, to] : {std::pair<std::string, std::string>{"&quot;", "\""},
                                 {"&lt;", "<"},
                                 {"&gt;", ">"},
                                 {"&amp;", "&"}}) {
    for (size_t at = s.find(from); at != std::string::npos; at = s.find(from, at + to.size()))
      s.replace(at, from.size(), to);
  }
  return s;
}

nlohmann::json ReportRender::probe(const std::string& report, const std::string& flags) {
  std::string html;
  {
    std::ifstream in(report, std::ios::binary);
    html.assign(std::istreambuf_iterator<char>(in), {});
  }
  const size_t end = html.rfind("</body>");
  if (end == std::string::npos) return {{"error", "no </body> in " + report}};
  std::ofstream(path("probe.html"), std::ios::binary)
      << html.substr(0, end) << kViewProbe << html.substr(end);
  const std::string dom = chromium(flags + "--dump-dom file://" + path("probe.html"));
  const size_t at = dom.find("<pre id=\"tv-test\">");
  if (at == std::string::npos) return {{"error", "no result: " + dom.substr(0, 400)}};
  const size_t stop = dom.find("</pre>", at);
  return nlohmann::json::parse(unescapeHtml(dom.substr(at + 18, stop - at - 18)));
}

// deviations.csv: per sample, its total, program and machine (um; empty: no value) and CL line.
struct CsvRow {
  std::string total, program, machine;
  int line = 0;
};
std::map<int, CsvRow> readDeviations(const std::string& path) {
  std::map<int, CsvRow> rows;
  std::ifstream in(path);
  std::string l;
  while (std::getline(in, l)) {
    if (l.empty() || l[0] == '#' || l.rfind("sample", 0) == 0) continue;
    std::vector<std::string> f;
    std::stringstream ss(l);
    std::string cell;
    while (std::getline(ss, cell, ',')) f.push_back(cell);
    while (f.size() < 15) f.emplace_back();
    rows[std::stoi(f[0])] = {f[10], f[11], f[12], std::atoi(f[13].c_str())};
  }
  return rows;
}

// The 3D view as a planner meets it: the sample job (the README's) opened in headless Chromium
// with WebGL (SwiftShader), offline, from report.html alone; the canvas shows the part in the
// legend's colours (more than one: the part fails); clicks on the part read the sample under
// the pointer with the values deviations.csv holds for it; the report stays under 20 MB.
TEST_F(ReportRender, TheThreeDViewShowsThePartInTheLegendsColoursAndAClickReadsTheSample) {
  ASSERT_TRUE(fs::exists("/usr/bin/chromium"))
      << "chromium is missing: run scripts/install_deps.sh";
  const auto r = verifySample("--tolerance 0.02 --report-dir " + path("rep"));
  ASSERT_EQ(r.exit_code, 1) << r.output;  // FAIL: material left beyond +10 um in a corner
  const std::string report = path("rep/report.html");
  EXPECT_LT(fs::file_size(report), 20u << 20);
  std::string html;
  {
    std::ifstream in(report, std::ios::binary);
    html.assign(std::istreambuf_iterator<char>(in), {});
  }
  ASSERT_NE(html.find("id=\"tolver-view-data\""), std::string::npos);
  EXPECT_EQ(html.find("http://"), html.find("http://www.w3.org"));  // nothing fetched
  const std::string flags =
      "--use-angle=swiftshader --enable-unsafe-swiftshader --window-size=1280,1000 "
      "--virtual-time-budget=60000 ";
  const nlohmann::json out = probe(report, flags);
  ASSERT_FALSE(out.contains("error")) << out["error"];
  // The part fills a good share of the canvas, drawn in the legend's colours (antialiased
  // silhouettes aside), more than one of them.
  const double part = out["part"], matched = out["matched"];
  EXPECT_GT(part, 0.1 * double(out["width"]) * double(out["height"]));
  // Colours between two bands blend across a triangle, as in the PNG maps.
  EXPECT_GT(matched, 0.9 * part);
  int colours_seen = 0;
  for (const auto& n : out["per_colour"]) colours_seen += int(n) > 50;
  EXPECT_GE(colours_seen, 2) << out["per_colour"];
  // Each click read a sample drawn within a few pixels of it, with deviations.csv's values.
  const auto csv = readDeviations(path("rep/deviations.csv"));
  ASSERT_GE(out["picks"].size(), 20u);
  EXPECT_LT(int(out["misses"]), 10);
  int with_values = 0;
  for (const auto& p : out["picks"]) {
    const int sample = p["sample"];
    ASSERT_TRUE(csv.count(sample)) << sample;
    const CsvRow& row = csv.at(sample);
    EXPECT_LT(double(p["miss_px"]), 4.0) << p.dump();
    for (const auto& [field, truth] : {std::pair<std::string, std::string>{"total", row.total},
                                       {"program", row.program},
                                       {"machine", row.machine}}) {
      const std::string shown = p[field];
      if (truth.empty() || row.total.empty()) continue;
      ASSERT_FALSE(shown.empty()) << sample << " " << field;
      EXPECT_NEAR(std::stod(shown), std::stod(truth), 2e-3) << sample << " " << field;
      ++with_values;
    }
    EXPECT_EQ(int(p["line"]), row.line) << sample;
  }
  EXPECT_GT(with_values, 20);
  // The README's STEP job: its CAD faces table links each face to the view; the view alone
  // (report.html#view3d) is the README's picture.
  std::ofstream(path("flank.csv")) << "region,tolerance\ncolour #e77c7c,0.02\n";
  const auto step = test::runTolver(
      "verify --machine " + test::sourcePath("samples/machines/matsuura_mc760vx_measured.xml") +
      " --setup " + test::sourcePath("samples/matsuura_setup.txt") + " --cl " +
      test::sourcePath("samples/nas979_cone.apt") + " --part " +
      test::sourcePath("samples/nas979_cone.step") + " --zones " + path("flank.csv") +
      " --spacing 1 --report-dir " + path("cone"));
  ASSERT_EQ(step.exit_code, 1) << step.output;
  const std::string cone = path("cone/report.html");
  EXPECT_LT(fs::file_size(cone), 20u << 20);
  {
    std::ifstream in(cone, std::ios::binary);
    const std::string text((std::istreambuf_iterator<char>(in)), {});
    EXPECT_NE(text.find("<tr id=\"region-face-"), std::string::npos);
    EXPECT_NE(text.find("data-face=\""), std::string::npos);
  }
  chromium(
      "--use-angle=swiftshader --enable-unsafe-swiftshader --window-size=1280,800 "
      "--virtual-time-budget=60000 --screenshot=" +
      path("view3d.png") + " file://" + cone + "#view3d");
  ASSERT_TRUE(fs::exists(path("view3d.png")));
  // Its first CAD face link outlines that face in the view.
  const nlohmann::json cone_out = probe(cone, flags);
  ASSERT_FALSE(cone_out.contains("error")) << cone_out["error"];
  ASSERT_TRUE(cone_out.contains("face_link"));
  EXPECT_TRUE(bool(cone_out["face_link"]["visible"]));
  EXPECT_GT(int(cone_out["face_link"]["triangles"]), 100);
  // The view fills the window: the legend's in-tolerance green and the part's colours are in it.
  vtkNew<vtkPNGReader> png;
  png->SetFileName(path("view3d.png").c_str());
  png->Update();
  int dims[3];
  png->GetOutput()->GetDimensions(dims);
  int green = 0;
  for (int y = 0; y < dims[1]; ++y)
    for (int x = 0; x < dims[0]; ++x) {
      int c[3];
      for (int k = 0; k < 3; ++k)
        c[k] = static_cast<int>(png->GetOutput()->GetScalarComponentAsDouble(x, y, 0, k));
      green += std::abs(c[0] - 46) < 30 && std::abs(c[1] - 160) < 40 && std::abs(c[2] - 67) < 30;
    }
  EXPECT_GT(green, 20000);
  if (const char* dir = std::getenv("TOLVER_SCREENSHOTS"))
    fs::copy_file(path("view3d.png"), fs::path(dir) / "view3d.png",
                  fs::copy_options::overwrite_existing);
}

}  // namespace
}  // namespace tolver
