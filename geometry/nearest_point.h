#pragma once
// Nearest neighbours among a point set (CGAL's k-d tree, kept inside nearest_point.cpp): for
// each query, the index of the closest point.
#include <Eigen/Core>
#include <vector>

namespace tolver {

// points must not be empty.
std::vector<int> nearestPointIndices(const std::vector<Eigen::Vector3d>& points,
                                     const std::vector<Eigen::Vector3d>& queries);

}  // namespace tolver
