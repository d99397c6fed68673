#include "geometry/nearest_point.h"

#include <CGAL/Orthogonal_incremental_neighbor_search.h>
#include <CGAL/Orthogonal_k_neighbor_search.h>
#include <CGAL/Search_traits_3.h>
#include <CGAL/Search_traits_adapter.h>
#include <CGAL/Simple_cartesian.h>
#include <CGAL/property_map.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <boost/iterator/counting_iterator.hpp>
#include <cmath>
#include <functional>
#include <stdexcept>

namespace tolver {
namespace {

using Kernel = CGAL::Simple_cartesian<double>;
using Point = Kernel::Point_3;
using PointMap = CGAL::Pointer_property_map<Point>::type;
using Traits = CGAL::Search_traits_adapter<std::size_t, PointMap, CGAL::Search_traits_3<Kernel>>;
using Search = CGAL::Orthogonal_k_neighbor_search<Traits>;
using Tree = Search::Tree;
using Splitter = Search::Splitter;
using Distance = Search::Distance;
using Incremental = CGAL::Orthogonal_incremental_neighbor_search<Traits, Distance, Splitter, Tree>;

std::vector<Point> cgalPoints(const std::vector<Eigen::Vector3d>& points) {
  std::vector<Point> pts;
  pts.reserve(points.size());
  for (const Eigen::Vector3d& p : points) pts.emplace_back(p.x(), p.y(), p.z());
  return pts;
}

// The points and their k-d tree, built at once (searches may then run in parallel: CGAL's
// search only reads a built tree). Neither copied nor moved: the tree points into `pts`.
struct PointTree {
  explicit PointTree(const std::vector<Eigen::Vector3d>& points)
      : pts(cgalPoints(points)),
        map(CGAL::make_property_map(pts)),
        tree(boost::counting_iterator<std::size_t>(0),
             boost::counting_iterator<std::size_t>(pts.size()), Splitter(), Traits(map)),
        distance(map) {
    tree.build();
  }
  PointTree(const PointTree&) = delete;
  PointTree& operator=(const PointTree&) = delete;
  std::vector<Point> pts;
  PointMap map;
  Tree tree;
  Distance distance;
};

}  // namespace

std::vector<int> nearestPointIndices(const std::vector<Eigen::Vector3d>& points,
                                     const std::vector<Eigen::Vector3d>& queries) {
  if (points.empty()) throw std::invalid_argument("nearestPointIndices: no points");
  const PointTree t(points);
  std::vector<int> out(queries.size());
  for (size_t i = 0; i < queries.size(); ++i) {
    const Search search(t.tree, Point(queries[i].x(), queries[i].y(), queries[i].z()), 1, 0, true,
                        t.distance);
    out[i] = static_cast<int>(search.begin()->first);
  }
  return out;
}

std::vector<int> nearestWithLowerLabel(const std::vector<Eigen::Vector3d>& points,
                                       const std::vector<int>& label, int visits,
                                       const std::vector<double>& reach,
                                       const std::function<double(int, int)>& cost) {
  if (label.size() != points.size() || (!reach.empty() && reach.size() != points.size()))
    throw std::invalid_argument("nearestWithLowerLabel: one label (and reach) per point");
  std::vector<int> out(points.size(), -1);
  if (points.size() < 2) return out;
  const PointTree t(points);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, points.size()), [&](const auto& range) {
    for (size_t i = range.begin(); i != range.end(); ++i) {
      // In increasing distance, until no farther point can cost less than the best; among
      // equal costs (a point two pieces share), the latest piece. The 32 nearest first (one
      // cheap search), then on, incrementally, as far as `visits` points or reach[i].
      const double reach2 = reach.empty() ? INFINITY : reach[i] * reach[i];
      double best = INFINITY;  // the best cost so far
      int seen = 0;
      auto take = [&](size_t j, double d2) {  // false: stop
        if (!(d2 <= reach2) || d2 > best * best * (1 + 1e-12)) return false;
        if (label[j] >= label[i]) return true;
        const double c = cost ? cost(static_cast<int>(i), static_cast<int>(j)) : std::sqrt(d2);
        if (c < 0) return true;
        if (out[i] < 0 || c < best * (1 - 1e-12) ||
            (c <= best * (1 + 1e-12) && label[j] > label[out[i]])) {
          out[i] = static_cast<int>(j);
          best = std::min(best, c);
        }
        return true;
      };
      const int first = std::min(32, visits);
      bool more = true;
      {
        const Search search(t.tree, t.pts[i], static_cast<unsigned>(first), 0, true, t.distance);
        for (const auto& [j, d2] : search) {
          ++seen;
          if (!take(j, d2)) {
            more = false;
            break;
          }
        }
      }
      if (!more || seen < first) continue;
      Incremental search(t.tree, t.pts[i], 0.0, true, t.distance);
      int k = 0;
      for (auto it = search.begin(); it != search.end() && k < visits; ++it, ++k)
        if (k >= first && !take(it->first, it->second)) break;
    }
  });
  return out;
}

}  // namespace tolver
