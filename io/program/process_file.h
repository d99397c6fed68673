#pragma once
// Process corrections (process.txt, written by tolver measure; read by verify and measure with
// --process): what a measured part showed of the set-up and the tools, as `key value` lines
// ('#' starts a comment):
//   set-up_x_mm, set-up_y_mm, set-up_z_mm           the part's position on the table off by
//   set-up_about_x_rad, _about_y_rad, _about_z_rad  this, and its orientation (small angles,
//                                                   about the part's origin)
//   cutter_radius_dR_mm, cutter_radius_T<k>_dR_mm   a tool's radius off by this (length preset
//                                                   to its tip)
//   tool_length_dL_mm, tool_length_T<k>_dL_mm       a tool longer than preset by this
//   thermal_drift_spindle_growth_mm/h               the spindle growing along the tool axis at
//                                                   this rate from the program's start (its
//                                                   clock from the feed rates)
//   tool_deflection[_T<k>]_across_the_feed_mm       a tool pushed sideways of its feed by this
//                                                   (along a x f, f the move's direction)
//   stock_offset_mm, tool_offset_T<k>_{x,y,z}_mm,   read and listed, not applied (no physical
//   tool_deflection[_T<k>]_off_the_surface_mm,      input of verify holds them)
//   machine_<parameter>
#include <Eigen/Geometry>
#include <map>
#include <string>
#include <vector>

namespace tolver {

struct ProcessCorrections {
  Eigen::Isometry3d part_error = Eigen::Isometry3d::Identity();  // the part's true pose in w
  std::map<int, double> radius_mm, length_mm;                    // by tool index (0-based)
  std::map<int, double> across_feed_mm;                          // by tool index
  double drift_mm_per_h = 0.0;
  std::vector<std::string> not_applied;  // keys read, not applied
  bool empty() const {
    return part_error.isApprox(Eigen::Isometry3d::Identity(), 0.0) && radius_mm.empty() &&
           length_mm.empty() && across_feed_mm.empty() && drift_mm_per_h == 0.0;
  }
};

ProcessCorrections parseProcessFile(const std::string& text, const std::string& file);
ProcessCorrections readProcessFile(const std::string& path);

}  // namespace tolver
