#pragma once
// STEP parts (ISO 10303-21; AP203, AP214, AP242) through OpenCASCADE 7.6 (STEPCAFControl_Reader,
// XCAF): the B-rep of one solid tessellated within a chordal tolerance (BRepMesh), each
// triangle kept with the CAD face it came from. The reader runs in a child process
// (io/common/child_process.h): OCCT raises on damaged geometry and can abort.
//
// Face groups: one per CAD face, named "face #N" after the ADVANCED_FACE (or FACE_SURFACE)
// entity #N of the file, which every STEP file has and any text editor shows; its aliases are the
// face's own name when the file gives one (not "" or "NONE"), and "colour #rrggbb" when the file
// styles it (XCAF surface colour; sRGB). Lengths are converted to mm from the file's unit.
#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "geometry/triangle_mesh.h"

namespace tolver {

struct StepReadOptions {
  double chordal_mm = 0.001;  // the tessellation's largest distance to the true surface
  double angular_rad = 0.2;   // and its largest angle between adjacent facets' normals
  std::string part_name;      // the solid to read in an assembly (product or instance name)
  bool in_process = false;    // read in this process (fuzz harnesses)
};

struct StepFace {
  int entity = 0;            // #N of its face entity in the file (0: none found)
  std::string name, colour;  // "" when the file gives none; colour "#rrggbb"
  double area_mm2 = 0;       // of the B-rep face (BRepGProp), not of its triangles
};

// A geometric tolerance of the file's semantic PMI (AP242, XCAFDoc_DimTolTool).
struct StepTolerance {
  std::string type;        // "profile of a surface", "flatness", "position", ...
  std::string name;        // as the file names it, e.g. "Position surfacic profile.2"
  double value_mm = 0;     // the zone's width
  bool unequal = false;    // unequally disposed (ISO UZ, ASME U): offset_mm holds it
  double offset_mm = 0;    // ASME U: the part of the zone outside the material
  std::vector<int> faces;  // the face groups it applies to
};

struct StepPart {
  TriangleMesh mesh;                // mm, in the file's frame; groups = faces below
  std::vector<StepFace> faces;      // #groups
  std::string schema;               // FILE_SCHEMA's first identifier, e.g. "AP242_MANAGED_..."
  std::string system;               // FILE_NAME's originating system
  std::string file_unit;            // the file's length unit as it names it ("MILLIMETRE", ...)
  std::string solid;                // the name of the solid read ("" when it has none)
  std::vector<std::string> solids;  // every solid's name in the file (assemblies)
  double area_mm2 = 0;              // B-rep area of the solid
  Eigen::AlignedBox3d box_mm;       // B-rep bounding box (BRepBndLib, optimal)
  double chordal_mm = 0, angular_rad = 0;  // the tessellation's bounds as requested
  double deflection_mm = 0;  // the largest deflection BRepMesh reports on a face (it may
                             // exceed chordal_mm on some B-spline faces)
  std::vector<StepTolerance> tolerances;
  std::vector<std::string> notes;  // repairs made, what was left out (a line each)
};

// Throws InputError naming the file: unreadable (OCCT's reader status), no solid or shell, an
// assembly without --part-name, a name that matches no solid, a B-rep that BRepCheck finds
// invalid after ShapeFix (the face and the check named), a failed tessellation.
StepPart readStepPart(const std::string& path, const StepReadOptions& options = {});

// The tolver_occt module's reader (io/mesh/step_reader_occt.cpp): the part as bytes (mesh_bytes.h),
// which readStepPart decodes.
using StepPartBytes = std::string(const std::string& path, const StepReadOptions& options);

}  // namespace tolver
