#include "io/report/view3d.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <nlohmann/json.hpp>

#include "core/numerics/units.h"
#include "io/common/text_util.h"
#include "io/report/deviation_map.h"

// three.js, its OrbitControls (Debian's libjs-three, paths from io/CMakeLists.txt) and the view's
// own script (io/report/view3d.js), built into the program: a report opens offline, and tolver
// reads nothing outside its inputs at run time.
#define TOLVER_EMBED(symbol, path)          \
  asm(".pushsection .rodata\n"              \
      ".balign 16\n"                        \
      ".global " #symbol "_begin\n" #symbol \
      "_begin:\n"                           \
      ".incbin \"" path                     \
      "\"\n"                                \
      ".global " #symbol "_end\n" #symbol   \
      "_end:\n"                             \
      ".byte 0\n"                           \
      ".popsection\n");                     \
  extern "C" const char symbol##_begin[], symbol##_end[];
TOLVER_EMBED(tolver_three_js, TOLVER_THREE_JS)
TOLVER_EMBED(tolver_orbit_controls_js, TOLVER_ORBIT_CONTROLS_JS)
TOLVER_EMBED(tolver_view3d_js, TOLVER_VIEW3D_JS)

namespace tolver {
namespace {

using nlohmann::json;

template <class T>
std::string base64Of(const std::vector<T>& v) {
  return base64Encode(std::string(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(T)));
}

std::string colourHex(const Rgb& c) {
  char s[8];
  std::snprintf(s, sizeof s, "#%02x%02x%02x", c[0], c[1], c[2]);
  return s;
}

std::string umText(double mm) { return formatWith("%+.1f", mmToUm(mm)); }

// Deviations shown along the normal times a factor that makes the largest one about 3 % of the
// part's radius, rounded down to 1, 2 or 5 times a power of ten (1: true scale).
double autoExaggeration(double largest_um, double radius_mm) {
  if (!(largest_um > 0) || !(radius_mm > 0)) return 1;
  const double want = 0.03 * radius_mm / (largest_um * 1e-3);
  if (want <= 1) return 1;
  const double decade = std::pow(10.0, std::floor(std::log10(want)));
  for (double m : {5.0, 2.0, 1.0})
    if (m * decade <= want) return m * decade;
  return decade;
}

std::string script(const char* begin, const char* end) {
  return "<script>" + std::string(begin, end) + "\n</script>\n";
}

}  // namespace

std::string regionHtmlId(const std::string& name) {
  std::string id;
  for (char c : name)
    if (std::isalnum(static_cast<unsigned char>(c)))
      id += c;
    else if (id.empty() || id.back() != '-')
      id += '-';
  return id;
}

// Long by design: the data's arrays, then the section's markup, in the order the script reads
// them.
std::string view3dSection(const VerifyReport& r) {
  if (!r.view_mesh || r.view_mesh->vertex.empty() || r.zones.empty()) return "";
  const DecimatedMesh& m = *r.view_mesh;
  const SurfaceSamples& s = *r.samples;
  const VerifyResult& v = *r.result;
  const size_t n = m.vertex.size();
  std::vector<float> pos(3 * n), nor(3 * n), total(n), program(n), machine(n);
  std::vector<std::uint8_t> rgb(3 * n), flags(n), state(n);
  std::vector<std::uint32_t> sample(n), line(n), faces;
  std::vector<std::int32_t> zone(n), group(n);
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(INFINITY), hi = -lo;
  double largest_um = 0;
  for (size_t j = 0; j < n; ++j) {
    const int i = m.vertex[j];
    for (int k = 0; k < 3; ++k) {
      pos[3 * j + k] = static_cast<float>(s.p_w[i][k]);
      nor[3 * j + k] = static_cast<float>(s.n_w[i][k]);
    }
    lo = lo.cwiseMin(s.p_w[i]);
    hi = hi.cwiseMax(s.p_w[i]);
    const Rgb c = sampleColour(v, r.zones, i);
    std::copy(c.begin(), c.end(), rgb.begin() + 3 * j);
    const bool machined = v.machined[i];
    const bool split = v.split.empty() || v.split[i] == Split::Attributable;
    const bool beyond = !v.total_beyond.empty() && v.total_beyond[i];
    const bool out =
        v.conformance[i] == Conformance::Gouge || v.conformance[i] == Conformance::Excess;
    flags[j] = static_cast<std::uint8_t>((machined ? 1 : 0) | (split ? 2 : 0) | (beyond ? 4 : 0) |
                                         (out ? 8 : 0));
    total[j] = machined && !beyond ? static_cast<float>(mmToUm(v.total[i])) : 0.0f;
    program[j] = machined && split ? static_cast<float>(mmToUm(v.program[i])) : 0.0f;
    machine[j] = machined && split ? static_cast<float>(mmToUm(v.machine[i])) : 0.0f;
    if (machined && !beyond) largest_um = std::max(largest_um, std::abs(mmToUm(v.total[i])));
    sample[j] = static_cast<std::uint32_t>(i);
    zone[j] = v.zone[i];
    group[j] = i < static_cast<int>(s.group.size()) ? s.group[i] : 0;
    state[j] = static_cast<std::uint8_t>(v.conformance[i]);
    const int c_index = v.cl_index[i];
    line[j] = c_index >= 0 && c_index < static_cast<int>(r.cl_lines.size())
                  ? static_cast<std::uint32_t>(r.cl_lines[c_index])
                  : 0u;
  }
  faces.reserve(3 * m.faces.size());
  for (const Eigen::Vector3i& f : m.faces)
    for (int k = 0; k < 3; ++k) faces.push_back(static_cast<std::uint32_t>(f[k]));
  const Eigen::Vector3d centre = 0.5 * (lo + hi);
  const double radius = std::max(0.5 * (hi - lo).norm(), 1e-3);
  const double exaggeration = autoExaggeration(largest_um, radius);

  json d;
  d["positions"] = base64Of(pos);
  d["normals"] = base64Of(nor);
  d["colours"] = base64Of(rgb);
  d["total_um"] = base64Of(total);
  d["program_um"] = base64Of(program);
  d["machine_um"] = base64Of(machine);
  d["flags"] = base64Of(flags);
  d["sample"] = base64Of(sample);
  d["zone"] = base64Of(zone);
  d["group"] = base64Of(group);
  d["state"] = base64Of(state);
  d["cl_line"] = base64Of(line);
  d["faces"] = base64Of(faces);
  d["centre"] = {centre.x(), centre.y(), centre.z()};
  d["radius"] = radius;
  d["exaggeration"] = exaggeration;
  json states = json::array();
  for (Conformance c : {Conformance::In, Conformance::Excess, Conformance::Gouge,
                        Conformance::Unmachined, Conformance::Unchecked})
    states.push_back(conformanceName(c));
  d["states"] = states;
  json zones = json::array();
  for (const ToleranceZone& z : r.zones)
    zones.push_back(
        {{"region", z.region}, {"lower_um", mmToUm(z.lower)}, {"upper_um", mmToUm(z.upper)}});
  d["zones"] = zones;
  json groups = json::array(), group_ids = json::array();
  for (size_t g = 0; g < s.group_names.size(); ++g) {
    std::string text = s.group_names[g];
    if (g < s.group_aliases.size())
      for (const std::string& a : s.group_aliases[g]) text += ", " + a;
    groups.push_back(text);
    group_ids.push_back(regionHtmlId(s.group_names[g]));
  }
  d["groups"] = groups;
  d["group_ids"] = group_ids;
  json views = json::array();
  std::string buttons;
  for (const MapView& view : deviationMapViews(s, v)) {
    views.push_back({{"name", view.name},
                     {"direction", {view.direction.x(), view.direction.y(), view.direction.z()}},
                     {"up", {view.up.x(), view.up.y(), view.up.z()}}});
    buttons += "<button type=\"button\" data-view=\"" + view.name + "\">" + view.name + "</button>";
  }
  d["views"] = views;
  json regions = json::array();
  for (size_t k = 0; k < v.regions.size() && k < 3; ++k) {  // as the maps' callouts
    const OutOfToleranceRegion& g = v.regions[k];
    regions.push_back({{"label", "R" + std::to_string(k + 1)},
                       {"where", {g.where_w.x(), g.where_w.y(), g.where_w.z()}},
                       {"text", "R" + std::to_string(k + 1) + " " + conformanceName(g.kind) + " " +
                                    worstDeviationText(v, g)}});
  }
  d["regions"] = regions;
  // Names from the files may hold invalid UTF-8: replaced, as in report.json.
  std::string data = d.dump(-1, ' ', false, json::error_handler_t::replace);
  // "</" would end the script element: JSON lets it be written "<\/".
  for (size_t at = data.find("</"); at != std::string::npos; at = data.find("</", at + 3))
    data.insert(at + 1, "\\");

  // The legend: the first zone's bands, then the two greys.
  const ToleranceZone& z0 = r.zones.front();
  std::string legend = "<table class=\"tv-legend\">";
  const std::vector<LegendBand> bands = deviationLegend(z0.lower, z0.upper);
  for (auto it = bands.rbegin(); it != bands.rend(); ++it) {
    const std::string range = std::isinf(it->to_mm) ? "above " + umText(it->from_mm)
                              : std::isinf(it->from_mm)
                                  ? "below " + umText(it->to_mm)
                                  : umText(it->from_mm) + " to " + umText(it->to_mm);
    legend += "<tr><td class=\"sw\" style=\"background:" + colourHex(it->colour) + "\"></td><td>" +
              range + (it->from_mm == z0.lower ? " (in tolerance)" : "") + "</td></tr>";
  }
  legend += "<tr><td class=\"sw\" style=\"background:" + colourHex(kUnmachinedColour) +
            "\"></td><td>not machined</td></tr><tr><td class=\"sw\" style=\"background:" +
            colourHex(kUncheckedColour) +
            "\"></td><td>not checked (edge, no zone)</td></tr></table><p class=\"tv-small\">"
            "deviation &micro;m, + material left, &minus; gouge" +
            (r.zones.size() > 1 ? "; values of zone " + xmlEscape(z0.region) +
                                      ", the others coloured by their own limits"
                                : std::string()) +
            "</p>";

  const std::string budget = std::to_string(m.max_vertices);
  const std::string bounds =
      (n == s.size()
           ? "Shown: all " + std::to_string(n) +
                 " samples, as sampled (within the view's budget of " + budget +
                 " vertices, nothing is decimated)."
           : "Shown: " + std::to_string(n) + " of " + std::to_string(s.size()) + " samples, " +
                 (m.given_faces_drawn > 0
                      ? std::to_string(m.given_faces_drawn) + " of the part's " +
                            std::to_string(s.given_faces.size()) +
                            " faces as given (where they carry the map), the rest decimated by "
                            "OpenMesh, within the view's budget of "
                      : std::string("decimated by OpenMesh down to the view's budget of ")) +
                 budget + " vertices: every sample lies within " +
                 formatWith("%.3g", m.max_distance_mm) +
                 " mm of the surface shown, and every value interpolated on a triangle within " +
                 formatWith("%.3g", mmToUm(m.max_value_difference)) +
                 " &micro;m of the total deviation of each sample the triangle stands for, all "
                 "of one CAD face, zone and state; sharp edges and borders are kept whole" +
                 (m.relaxed ? " (bounds doubled until the view fitted its budget)" : "") + ".") +
      " A click reads the sample nearest the point, with its own values. The predicted surface "
      "is the CAD surface moved along its normal by the total deviation times the factor set "
      "above.";

  std::string h;
  h += "<h2 id=\"view3d\">3D view</h2>\n<style>"
       "#tolver-view{position:relative}#tolver-view .tv-bar{margin:4px 0}"
       "#tolver-view .tv-bar label,#tolver-view .tv-bar button{margin-right:10px}"
       "#tolver-view .tv-row{display:flex;gap:10px}"
       "#tolver-view canvas{flex:1;min-width:0;height:640px;border:1px solid #ccc;display:block;"
       "cursor:crosshair}#tolver-view .tv-side{width:280px;font-size:0.9em}"
       ".tv-legend td{border:none;padding:1px 6px;text-align:left}.tv-legend td.sw{width:28px}"
       "#tolver-pick table td,#tolver-pick table th{padding:2px 6px;text-align:left}"
       ".tv-label{position:absolute;transform:translate(-50%,-130%);background:#fff;"
       "border:1px solid #333;font-size:12px;padding:0 3px;pointer-events:none}"
       ".tv-small{color:#555;font-size:0.85em}#tolver-view input[type=number]{width:6em}"
       "body.tv-full{margin:0;max-width:none}body.tv-full>*:not(#tolver-view){display:none}"
       "body.tv-full #tolver-view{padding:6px}"
       "body.tv-full #tolver-view canvas{height:calc(100vh - 50px)}"
       "</style>\n";
  h += "<div id=\"tolver-view\"><div class=\"tv-bar\">"
       "<label><input type=\"checkbox\" id=\"tv-predicted\" checked> predicted</label>"
       "<label><input type=\"checkbox\" id=\"tv-nominal\"> nominal (CAD)</label>"
       "<label><input type=\"checkbox\" id=\"tv-out\" checked> out of tolerance</label>"
       "<label><input type=\"checkbox\" id=\"tv-shading\" checked> shading</label>"
       "<label>deviation &times;<input type=\"number\" id=\"tv-exaggeration\" min=\"0\" "
       "step=\"any\" value=\"" +
       formatWith("%.6g", exaggeration) + "\"></label> views: " + buttons +
       "</div><div class=\"tv-msg\"></div><div class=\"tv-row\"><canvas></canvas>"
       "<div class=\"tv-side\">" +
       legend +
       "<h4>Picked</h4><div id=\"tolver-pick\">click the part to read a sample</div></div>"
       "</div><p class=\"tv-small\">" +
       bounds +
       " Drag to turn, right-drag to pan, wheel to zoom; report.html#view3d opens the view "
       "alone.</p>\n";
  h += "<script type=\"application/json\" id=\"tolver-view-data\">" + data + "</script>\n";
  h += script(tolver_three_js_begin, tolver_three_js_end);
  h += script(tolver_orbit_controls_js_begin, tolver_orbit_controls_js_end);
  h += script(tolver_view3d_js_begin, tolver_view3d_js_end);
  h += "</div>\n";
  return h;
}

}  // namespace tolver
