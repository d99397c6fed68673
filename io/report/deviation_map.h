#pragma once
// Deviation maps (VTK, off screen), as inspection software draws them: the part coloured in
// discrete steps with the zone limits as boundaries: one green in tolerance, then four bands
// beyond each limit (gouges yellow to dark red, material left light to dark blue), the last
// saturated (at `saturation` half-widths from the zone's centre), unmachined grey. The colour bar
// is labelled at the limits and the band boundaries; the part's bounding box carries its
// coordinates in mm (axes and scale); callouts (region, value, position, CL line) are placed
// beside their points without covering each other; every view shows the whole part. Plus a
// histogram and a line profile.
// Rendering needs an X display: see io/report/offscreen_display.h.
#include <Eigen/Core>
#include <array>
#include <string>
#include <vector>

#include "geometry/tolerance_zone.h"
#include "geometry/triangle_mesh.h"
#include "geometry/verification.h"

namespace tolver {

using Rgb = std::array<unsigned char, 3>;

// Colour of deviation d (mm) in the zone [lower, upper], saturated at `saturation` half-widths
// from the zone's centre.
Rgb deviationColour(double d, double lower, double upper, double saturation = 3.0);
constexpr Rgb kUnmachinedColour = {165, 165, 165};
constexpr Rgb kUncheckedColour = {215, 215, 215};
// Sample i's colour on the maps: unmachined and unchecked greys, else its total deviation in its
// zone.
Rgb sampleColour(const VerifyResult& r, const std::vector<ToleranceZone>& zones, size_t i);

struct MapCallout {
  Eigen::Vector3d p_w;
  std::string text;
};

struct MapView {
  std::string name;           // "isometric", "top", "worst"
  Eigen::Vector3d direction;  // from the camera towards the part, in w
  Eigen::Vector3d up;
  bool focus = false;  // a region's view (the whole part, seen along its normal)
  Eigen::Vector3d focus_w = Eigen::Vector3d::Zero();
};

struct DeviationMap {
  const std::vector<Eigen::Vector3d>* points = nullptr;  // #S, mm
  const std::vector<Eigen::Vector3i>* faces = nullptr;
  std::vector<Rgb> colours;                    // #S
  double bar_lower = -0.01, bar_upper = 0.01;  // mm: the zone on the colour bar
  std::string title;
  std::vector<MapCallout> callouts;
  std::string grey_means = "not machined";  // what the grey surface means, in the title
  std::string bar_title = "deviation um\n+ material left\n- gouge";
  std::array<std::string, 2> limit_names = {"lower", "upper"};  // the bar's limits' labels
  // Points drawn over the surface as round dots in their colours (measured points, mm, in w).
  std::vector<Eigen::Vector3d> markers;
  std::vector<Rgb> marker_colours;
};

// The scale as a legend: its bands in order from the deepest gouge to the most material left,
// each with its colour and its deviations [from_mm, to_mm) (infinite at the saturated ends).
struct LegendBand {
  Rgb colour;
  double from_mm, to_mm;
};
std::vector<LegendBand> deviationLegend(double lower, double upper, double saturation = 3.0);

// Where the callout labels go (bottom-left corners, display pixels) for attachment points at
// `at` (display pixels): beside each point (to the right, or to the left near the right edge),
// pushed up so that no two labels of label_w x label_h overlap, kept inside the view.
std::vector<Eigen::Vector2d> placeCallouts(const std::vector<Eigen::Vector2d>& at, double label_w,
                                           double label_h, double view_w, double view_h);

// The maps' views: isometric, top, then along the normal of each of the three worst regions
// ("worst", "region2", "region3"), or of the largest deviation when nothing is out.
std::vector<MapView> deviationMapViews(const SurfaceSamples& s, const VerifyResult& r);

// Renders one view into a PNG (atomic write). Throws InputError (field "image") when it
// cannot render or write; call ensureDisplay() first.
void renderDeviationMap(const std::string& png_path, const DeviationMap& map, const MapView& view,
                        int width = 1200, int height = 900);
// Several views of one map, each into its PNG (path, view), in one window: the same pictures as
// renderDeviationMap's one by one, made faster.
void renderDeviationMaps(const std::vector<std::pair<std::string, MapView>>& views,
                         const DeviationMap& map, int width = 1200, int height = 900);

// Histogram of deviations (mm, area-weighted) with the zone limits marked, as a PNG.
// The axes' labels default to verify's (normal deviation, % of the machined area), the limits'
// to the zone's ("in the zone", "material left"...); a band_label names another band.
void renderHistogram(const std::string& png_path, const std::vector<double>& deviation,
                     const std::vector<double>& weight, double lower, double upper,
                     const std::string& title, int width = 900, int height = 500,
                     const std::string& x_label = "", const std::string& y_label = "",
                     const std::string& band_label = "");

// A line profile ([AM01] Fig. 5.7): deviation (mm) against arc length (mm) with the zone band.
void renderLineProfile(const std::string& png_path, const std::vector<double>& arc_length,
                       const std::vector<double>& total, const std::vector<double>& machine,
                       double lower, double upper, const std::string& title, int width = 900,
                       int height = 450);

}  // namespace tolver
