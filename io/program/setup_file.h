#pragma once
// Set-up files: how the part and the tool sit on the machine. Plain text, one `key = value` per
// line, `#` starts a comment. Keys (all optional):
//   part_zero_mm      = x, y, z     # part zero (origin of w) in the table frame, mm
//   part_rotation_deg = c           # rotation of w about the table z axis, degrees
//   gauge_length_mm   = L           # tool tip to spindle gauge point, mm
//   g54_mm            = x, y, z     # G-code work offsets (g54 ... g59, g54.1p1, g59.3), machine
//                                   # coordinates, mm; one not given puts its origin at part zero
//   tool_h1_mm        = L           # G-code tool length of H1 (G43 H1); one not given: gauge
//   length
#include <string>

#include "core/model/machine_model.h"

namespace tolver {

// Reads a set-up file on top of `base` (values not given are kept). Throws InputError.
PartSetup readSetupFile(const std::string& path, PartSetup base = {});
PartSetup parseSetup(const std::string& text, const std::string& file_name, PartSetup base = {});

}  // namespace tolver
