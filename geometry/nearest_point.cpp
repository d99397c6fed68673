#include "geometry/nearest_point.h"

#include <CGAL/Orthogonal_k_neighbor_search.h>
#include <CGAL/Search_traits_3.h>
#include <CGAL/Search_traits_adapter.h>
#include <CGAL/Simple_cartesian.h>
#include <CGAL/property_map.h>

#include <boost/iterator/counting_iterator.hpp>
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

}  // namespace

std::vector<int> nearestPointIndices(const std::vector<Eigen::Vector3d>& points,
                                     const std::vector<Eigen::Vector3d>& queries) {
  if (points.empty()) throw std::invalid_argument("nearestPointIndices: no points");
  std::vector<Point> pts;
  pts.reserve(points.size());
  for (const Eigen::Vector3d& p : points) pts.emplace_back(p.x(), p.y(), p.z());
  const PointMap map = CGAL::make_property_map(pts);
  Tree tree(boost::counting_iterator<std::size_t>(0),
            boost::counting_iterator<std::size_t>(pts.size()), Splitter(), Traits(map));
  const Distance distance(map);
  std::vector<int> out(queries.size());
  for (size_t i = 0; i < queries.size(); ++i) {
    const Search search(tree, Point(queries[i].x(), queries[i].y(), queries[i].z()), 1, 0, true,
                        distance);
    out[i] = static_cast<int>(search.begin()->first);
  }
  return out;
}

}  // namespace tolver
