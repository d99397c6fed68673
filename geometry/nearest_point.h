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

// For each point, the other point of a lower label (the label: the piece of a tool path a point
// belongs to, in cutting order) of least cost among the `visits` nearest points within reach[i]
// of it (empty: no bound), or -1 when none of them has one. `cost(i, j)` is at least their
// distance (the search stops where no farther point can cost less), negative when j cannot be
// i's; without it, the distance. Among equal costs, the highest label. `cost` is called from
// several threads. The tree is built once and searched in parallel, incrementally (CGAL's search
// only reads a built tree).
std::vector<int> nearestWithLowerLabel(const std::vector<Eigen::Vector3d>& points,
                                       const std::vector<int>& label, int visits,
                                       const std::vector<double>& reach = {},
                                       const std::function<double(int, int)>& cost = {});

}  // namespace tolver
