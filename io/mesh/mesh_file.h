#pragma once
// Part meshes from CAD (assimp): STL (ASCII and binary), OBJ, PLY, OFF, 3MF, glTF 2 (.gltf,
// .glb). Faces are triangulated; points and lines dropped. Each mesh of the file (an OBJ group,
// a glTF mesh, a 3MF object) becomes a region, named as the file names it. Node transforms are
// applied; then p_w = R (scale p_file) + t with the placement below.
// STEP parts (.step, .stp) through OpenCASCADE (io/mesh/step_file.h): tessellated within a
// chordal tolerance, one region per CAD face; their unit is the file's.
#include <Eigen/Geometry>
#include <memory>
#include <string>

#include "geometry/mesh_repair.h"
#include "geometry/triangle_mesh.h"
#include "io/mesh/step_file.h"

namespace tolver {

struct PartImportOptions {
  // File length unit: "mm", "inch" or "m"; empty: mm, but m for glTF (its specification's unit).
  std::string units;
  Eigen::Isometry3d w_T_file = Eigen::Isometry3d::Identity();  // placement of the file in w, mm
  MeshRepairOptions repair;
  // STEP: the tessellation's chordal tolerance (mm) and the solid of an assembly.
  double chordal_mm = 0.001;
  std::string part_name;
};

struct ImportedPart {
  TriangleMesh mesh;  // repaired, in w, mm
  MeshRepairReport repair;
  std::string units;   // the unit applied
  std::string format;  // file extension, lower case
  // STEP: what the file says of the part (faces, PMI, units); its mesh moved into `mesh`.
  std::shared_ptr<StepPart> cad;
};

// Throws InputError naming the file (field "mesh") when the file cannot be read or the mesh has a
// defect that cannot be repaired safely (with where it is).
ImportedPart readPartMesh(const std::string& path, const PartImportOptions& options = {});

// Writes a mesh with a per-vertex scalar as binary little-endian PLY ("deviation" property,
// in the unit the caller gives) and as VTK XML PolyData (.vtp, a point-data array of that name).
// Atomic writes; InputError when the file cannot be written.
void writePlyWithScalar(const std::string& path, const std::vector<Eigen::Vector3d>& points,
                        const std::vector<Eigen::Vector3i>& faces,
                        const std::vector<double>& scalar, const std::string& scalar_name);
void writeVtpWithScalars(
    const std::string& path, const std::vector<Eigen::Vector3d>& points,
    const std::vector<Eigen::Vector3i>& faces,
    const std::vector<std::pair<std::string, const std::vector<double>*>>& scalars);

}  // namespace tolver
