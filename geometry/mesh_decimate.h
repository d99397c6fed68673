#pragma once
// Decimation of a coloured surface for display (the report's 3D view), by OpenMesh's decimater,
// only when it has more vertices than the budget, and only down to it: halfedge collapses chosen
// by their quadric error among a few drawn near a cursor that sweeps the mesh (multiple choices:
// local in memory, so that a million samples take seconds), then by OpenMesh's heap for what
// those leave; no normal turned by more than 30 degrees, and each collapse
// allowed only within bounds of our own (ModDisplayBoundT), kept per vertex at the cost of its
// one-ring:
//   - the value: each vertex carries the interval of the values of the original vertices it
//     stands for; a collapse passes the removed vertex's interval to its one-ring, and is refused
//     when an interval would grow wider than `max_value_difference`. A value interpolated on a
//     face therefore lies within that bound of every original value the face stands for;
//   - the surface: the removed vertex's distance to the faces that replace it, added to the
//     distance its vertices already stood at, stays within `max_distance_mm` (an accumulated
//     bound; the tests measure the true distance against it);
//   - the category: a vertex goes only when its whole one-ring shares its category, so the
//     boundaries between categories (zones, CAD faces, machined or not) stay where they are.
// Vertices in `locked` stay (sharp edges), and so do the mesh's borders. A large mesh is cut in
// slabs decimated in parallel, each by its own decimater to its share of the budget, the faces
// across a seam kept as they are. The decimated mesh's vertices are original vertices, each with
// its index.
#include <Eigen/Core>
#include <functional>
#include <vector>

namespace tolver {

struct DecimateOptions {
  double max_distance_mm = 0.01;
  double max_value_difference = 1e-3;
  // The budget: a mesh with more vertices is decimated down to it; when the bounds above stop
  // it sooner, both are doubled until it fits (at most 12 times); the bounds met are returned.
  // What must stay (sharp edges, borders, seams, boundaries between categories) stays, over the
  // budget if it must.
  int max_vertices = 150000;
  // Pieces decimated in parallel (slabs along the longest axis, their seams kept whole): 0, one
  // per 100 000 vertices, at most 8 (whatever the machine's cores).
  int pieces = 0;
  // Called with the fraction of the collapses wanted that are done, from the decimating thread.
  std::function<void(double)> progress;
};

struct DecimatedMesh {
  std::vector<int> vertex;             // #V': the original vertex each one is
  std::vector<Eigen::Vector3i> faces;  // into `vertex`
  double max_distance_mm = 0;          // the bounds the result meets
  double max_value_difference = 0;
  bool relaxed = false;         // the bounds were doubled to fit max_vertices
  int max_vertices = 0;         // the budget it was given
  int faces_kept_as_given = 0;  // faces OpenMesh could not take (a non-manifold edge)
  int given_faces_drawn = 0;    // coarseForDisplay: the given faces drawn as they are
};

DecimatedMesh decimateForDisplay(const std::vector<Eigen::Vector3d>& p,
                                 const std::vector<Eigen::Vector3i>& faces,
                                 const std::vector<double>& value, const std::vector<int>& category,
                                 const std::vector<char>& locked, const DecimateOptions& options);

// decimateForDisplay of a resampled surface (resampleFaces: each face given, re-triangulated at
// the spacing): a given face is drawn as it is where it carries the map, that is when every
// sample on it (its re-triangulation's vertices) shares its corners' category, lies within
// max_distance_mm of it, and its value within max_value_difference of the value interpolated
// there from the corners; the rest, as sampled, is decimated (decimateForDisplay) to what the
// budget leaves, its border with the faces drawn whole kept. The given faces are the part's own
// geometry: where the field is smooth, their samples go without a collapse (the sculptured part's
// top at a million samples: 9 048 of its 10 440 faces). Where a face drawn whole meets the rest,
// the points on their common edge are vertices of the rest only (they lie on the edge). Empty
// (vertex empty) when the faces drawn whole would take more than half of the budget, or nothing
// is given: then decimateForDisplay of the whole.
// given_faces: in p's indices; face_given: for each face of `faces`, its given face; locked as
// decimateForDisplay's (or empty).
DecimatedMesh coarseForDisplay(const std::vector<Eigen::Vector3d>& p,
                               const std::vector<Eigen::Vector3i>& faces,
                               const std::vector<Eigen::Vector3i>& given_faces,
                               const std::vector<int>& face_given, const std::vector<double>& value,
                               const std::vector<int>& category, const std::vector<char>& locked,
                               const DecimateOptions& options);

}  // namespace tolver
