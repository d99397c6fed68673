#pragma once
// Nearest neighbours among a point set (CGAL's k-d tree, kept inside nearest_point.cpp): for
// each query, the index of the closest point.
#include <Eigen/Core>
#include <functional>
#include <vector>

namespace tolver {

// points must not be empty.
std::vector<int> nearestPointIndices(const std::vector<Eigen::Vector3d>& points,
                                     const std::vector<Eigen::Vector3d>& queries);

// For each point, the closest other point of a lower label (the label: the piece of a tool path
// a point belongs to, in cutting order) among the `visits` nearest points, or -1 when none of
// them has one and within reach[i] of it (empty: no bound); among equally near ones, the one of
// the highest label. `accept(i, j)`, when
// given, must also hold for j to be i's (called from several threads). The tree is built once
// and searched in parallel, incrementally (CGAL's search only reads a built tree).
std::vector<int> nearestWithLowerLabel(const std::vector<Eigen::Vector3d>& points,
                                       const std::vector<int>& label, int visits,
                                       const std::vector<double>& reach = {},
                                       const std::function<bool(int, int)>& accept = {});

}  // namespace tolver
