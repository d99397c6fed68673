#pragma once
// The interactive 3D view of report.html: the predicted surface coloured on the maps' discrete
// scale (io/report/deviation_map.h) with its legend, turned, panned and zoomed with the mouse
// (three.js r111 and its OrbitControls from Debian's libjs-three, inline: the report opens
// offline), the nominal surface and the out-of-tolerance faces as toggles, the maps' camera
// presets, and a click that reads the sample under the pointer: its total, program and machine
// deviations, zone, CAD face and CL line. The surface is the verification's, decimated for the
// browser (geometry/mesh_decimate.h) within bounds the section states.
#include <string>

#include "io/report/verify_report.h"

namespace tolver {

// The section's HTML (styles, controls, canvas, data, scripts); empty when r.view_mesh is null.
std::string view3dSection(const VerifyReport& r);

// An HTML id for a region's name: letters and digits kept, every other run one '-'
// ("face #376" is "face-376"); the CAD faces table's rows are "region-" + this.
std::string regionHtmlId(const std::string& name);

}  // namespace tolver
