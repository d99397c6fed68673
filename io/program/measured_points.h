#pragma once
// Measured points of a machined part (tolver measure): a CMM's or the machine probe's points on
// the machined surface, in the part frame (the frame of the part file, mm).
//
// CSV with a header ('#' lines are comments; names case-insensitive):
//   x_mm, y_mm, z_mm        the measured surface point (the stylus's contact, radius corrected)
//   nx, ny, nz              (optional) the nominal surface normal at it, outward; absent: the
//                           part mesh's normal at the point's foot
//   deviation_mm            (optional) the instrument's own normal deviation; reported beside
//                           tolver's (the point's distance from the mesh along the normal)
// x, y, z (and deviation) are accepted without the _mm suffix, as CMM exports write them;
// actual_x_mm, actual_y_mm, actual_z_mm stand for x_mm, ...; a deviation table without the
// measured point (nominal_x_mm, nominal_y_mm, nominal_z_mm, nx, ny, nz, deviation_mm on every
// row) gives it as the nominal moved by the deviation along the normal.
// An ASC point cloud (CloudCompare, PolyWorks: whitespace- or comma-separated numbers per line,
// no header; 3 columns x y z, or 6 with the normal) is read when the first data line is numbers.
// A PLY point cloud (CloudCompare, GOM, scanners' exports; ascii or binary of either byte order)
// is read when the file starts with "ply": the vertex element's x, y, z and, when all three are
// there, nx, ny, nz; faces and other properties are ignored. A binary PLY's "line" is the vertex
// number. (A reader of its own: Debian's assimp 5.2 trusts a PLY's counts and turns a point
// cloud into a mesh of points; io/mesh/mesh_file.cpp.)
#include <Eigen/Core>
#include <string>
#include <vector>

namespace tolver {

struct MeasuredPoint {
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  Eigen::Vector3d n = Eigen::Vector3d::Zero();  // zero: not given
  double deviation = 0.0;
  bool has_deviation = false;
  int line = 0;
};

std::vector<MeasuredPoint> parseMeasuredPoints(const std::string& text, const std::string& file);
std::vector<MeasuredPoint> readMeasuredPoints(const std::string& path);

}  // namespace tolver
