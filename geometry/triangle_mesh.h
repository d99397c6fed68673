#pragma once
// An indexed triangle mesh of a part's nominal surface in the part (workpiece) frame w, mm, and
// the surface samples the swept-surface computation works on.
//
// Faces are counter-clockwise seen from outside the material, so the right-hand normal of a
// face points out of the part: "+" along it is material left, "-" a gouge.
#include <Eigen/Core>
#include <string>
#include <vector>

namespace tolver {

struct TriangleMesh {
  std::vector<Eigen::Vector3d> vertices;  // #V, mm in w
  std::vector<Eigen::Vector3i> faces;     // #F, vertex indices
  std::vector<int> face_group;            // #F, index into group_names (region of the face)
  std::vector<std::string> group_names;   // at least one
  // Empty, or #groups: further names a zone may use for the group (a CAD face's name and colour,
  // io/mesh/step_file.h), shared by as many groups as carry them.
  std::vector<std::vector<std::string>> group_aliases;
  // Empty, or as resampleFaces leaves them: the faces as given (their vertices keep their
  // indices), and for each face the given face it re-triangulates (non-decreasing).
  std::vector<Eigen::Vector3i> given_faces;
  std::vector<int> face_given;

  double area() const;
  Eigen::Vector3d faceNormal(int f) const;  // unit; zero for a degenerate face
  double faceArea(int f) const;
};

// Remeshes to edges of about max_edge (CGAL's isotropic remeshing in mesh_refine.cpp: edges
// split, collapsed and flipped, vertices relaxed on the surface, sharp edges and face-group
// borders kept as constraints), so the samples lie about max_edge apart on the mesh's own
// (faceted) surface and the long thin triangles CAD systems write become well-shaped. Face groups
// are inherited.
void refineMesh(TriangleMesh* mesh, double max_edge);

// Re-triangulates each face at the spacing on its own plane (mesh_resample.cpp): its edges cut
// into equal pieces of at most 4/3 of the spacing (the same points for the two faces on an edge:
// the mesh stays conforming) and an equilateral lattice of the spacing inside, joined by a
// constrained Delaunay triangulation. Every vertex lies on an input face; sharp edges, borders and
// face groups are kept exactly; a face is never coarsened. About 1 us a sample, in parallel,
// where refineMesh costs 25 us; sampleSurface chooses between the two (see there).
void resampleFaces(TriangleMesh* mesh, double spacing);

// Surface samples: the refined mesh's vertices with outward unit normals. Along sharp edges
// (dihedral angle above feature_angle) a vertex is split into one sample per side, each with
// the normal of its own side, so a vector grown from a sample never leans across an edge.
struct SurfaceSamples {
  std::vector<Eigen::Vector3d> p_w;  // #S sample points, mm
  std::vector<Eigen::Vector3d> n_w;  // #S outward unit normals
  std::vector<double> area;          // #S area each sample stands for (a third of its faces), mm^2
  std::vector<int> group;            // #S region (group of its faces; the first one met)
  // #S: 1 on a sharp edge or a border. The normal deviation is undefined there (the point
  // belongs to two faces and a tool grazing the edge decides it), so such samples are not
  // verified; their neighbours, one spacing away, are (as inspection software excludes edges).
  std::vector<char> on_edge;
  std::vector<Eigen::Vector3i> faces;  // the mesh's faces re-indexed into samples
  std::vector<int> face_group;
  std::vector<std::string> group_names;
  std::vector<std::vector<std::string>> group_aliases;  // as the mesh's
  // Empty, or when the mesh was resampled (resampleFaces): the faces as given, in samples (each
  // corner the sample of its side), and for each face of `faces` the given face it lies on. The
  // 3D view draws a given face as it is where it carries the map (coarseForDisplay).
  std::vector<Eigen::Vector3i> given_faces;
  std::vector<int> face_given;
  size_t size() const { return p_w.size(); }
};

// The mesh is refined to the spacing first: by resampleFaces when the input is coarse, that is
// has fewer vertices than half of what equilateral triangles of the spacing would need over its
// area (CAD exports: long thin triangles on planes and cylinders); by refineMesh otherwise, whose
// collapses are then needed to keep the samples near the spacing.
SurfaceSamples sampleSurface(const TriangleMesh& mesh, double spacing,
                             double feature_angle_rad = 0.5236 /* 30 deg */);

}  // namespace tolver
