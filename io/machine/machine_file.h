#pragma once
// Machine description files (XML). Format (see docs/formats.md, "Machine file"):
//
// <machine name="..." length_unit="mm|inch" angle_unit="deg|rad">
//   <axis name="X" type="prismatic|rotary" branch="workpiece|tool" direction="1 0 0"
//         min="-380" max="380" nc_sign="-1" [order="2"]>
//     <link translation="0 0 0" rotation="0 0 0"/>   <!-- nominal D1: trans, then rot z,y,x -->
//   </axis>
//   <table translation=".." rotation=".."/>     <!-- table frame in the last workpiece joint -->
//   <spindle translation=".." rotation=".."/>   <!-- spindle gauge frame in the last tool joint -->
//   <errors length_unit="mm|um|inch" angle_unit="rad|urad|deg|arcsec" default_degree="3">
//     <link axis="X" component="gz" value="12"/>
//     <motion axis="X" component="ey" [degree="3"] coefficients="0 1.5 -0.3 0.1"/>
//     <setup frame="workpiece|tool" component="ex" value="5"/>
//     <effect type="reversal" axis="X" component="ex" values="3"/>   <!-- core/model/effects.h -->
//     <effect type="periodic" axis="Y" component="ey" period_mm="10" values="1.5 -0.8"/>
//     <effect type="harmonics" axis="C" component="gz" orders="2 4" values="..6 values.."/>
//     <effect type="chebyshev" axis="X" component="ey" orders="4 5" values="2 -1"/>
//     <effect type="warmup" axis="Z" component="ez" tau_s="1800" values="6"/>
//     <effect type="drift" axis="X" component="ex" values="1.2"/>   <!-- per hour -->
//     <effect type="bar_length" values="2"/>                          <!-- the instrument -->
//   </errors>
// </machine>
//
// Axes are listed from the foundation outwards in each branch (or sorted by `order`).
// Rotations in link/table/spindle are (rx ry rz) in angle_unit, applied as rot(k,rz) rot(j,ry)
// rot(i,rx) after the translation ([AM01] eq. 21). Components: ex ey ez gx gy gz.
#include <string>

#include "core/model/machine_model.h"

namespace tolver {

// Throws InputError (file, line, field) on a malformed file.
Machine readMachineFile(const std::string& path);
Machine parseMachineXml(const std::string& xml, const std::string& file_name);

// The machine file of a machine (geometry in mm and deg, errors in um and urad): every
// parameter that is not zero, every alias and preference, so that reading it back gives the
// same model and parameter values (to the last digit). comment: a line for the file's head.
std::string formatMachineXml(const Machine& machine, const std::string& comment = "");

}  // namespace tolver
