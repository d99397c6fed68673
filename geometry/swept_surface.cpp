#include "geometry/swept_surface.h"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/Simple_cartesian.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

namespace tolver {
namespace {

using Kernel = CGAL::Simple_cartesian<double>;

// An AABB-tree primitive: the bounding box of one tool placement (cutter over its length).
struct PlacementBox {
  using Id = int;
  using Point = Kernel::Point_3;
  using Datum = Kernel::Iso_cuboid_3;
  Id index;
  Datum box;
  PlacementBox() = default;
  PlacementBox(Id i, const Datum& b) : index(i), box(b) {}
  // The tree builds its primitives from the iterators it is given.
  template <class It>
  explicit PlacementBox(It it) : index(it->index), box(it->box) {}
  const Datum& datum() const { return box; }
  Id id() const { return index; }
  Point reference_point() const { return box.min(); }
};

using Traits = CGAL::AABB_traits<Kernel, PlacementBox>;
using Tree = CGAL::AABB_tree<Traits>;

// Output iterator that hands each primitive id to a callable, without storing it.
template <class F>
struct CallOut {
  using iterator_category = std::output_iterator_tag;
  using value_type = void;
  using difference_type = std::ptrdiff_t;
  using pointer = void;
  using reference = void;
  F* f;
  CallOut& operator*() { return *this; }
  CallOut& operator++() { return *this; }
  CallOut operator++(int) { return *this; }
  CallOut& operator=(int id) {
    (*f)(id);
    return *this;
  }
};

}  // namespace

void sweepSurface(const SurfaceSamples& samples, const Cutter& cutter,
                  const std::vector<ToolPlacement>& placements, const SweepOptions& options,
                  SweepResult* result, const std::function<void(double)>& progress) {
  const size_t n = samples.size();
  result->deviation.assign(n, options.excess_range);
  result->machined.assign(n, 0);
  result->placement.assign(n, -1);
  if (placements.empty() || n == 0) return;

  const double L = cutter.effectiveLength(), Rmax = cutter.maxRadius();
  // One box per chunk of the cutter no longer than its diameter: a tilted tool's single box would
  // hold much empty space, and every blade inside it would test the tool for nothing.
  const int chunks = std::max(1, static_cast<int>(std::ceil(L / std::max(2.0 * Rmax, 1e-6))));
  std::vector<PlacementBox> boxes;
  boxes.reserve(placements.size() * chunks);
  for (size_t k = 0; k < placements.size(); ++k) {
    const Eigen::Vector3d& u = placements[k].axis_w;
    for (int c = 0; c < chunks; ++c) {
      const Eigen::Vector3d p = placements[k].tip_w + (L * c / chunks) * u;
      const Eigen::Vector3d q = placements[k].tip_w + (L * (c + 1) / chunks) * u;
      const double radius = cutter.radiusAt(L * (c + 1) / chunks);
      // Box of the cylinder of that radius around the axis segment: per coordinate the
      // segment's extent plus radius sqrt(1 - u_i^2).
      Eigen::Vector3d lo, hi;
      for (int i = 0; i < 3; ++i) {
        const double grow = radius * std::sqrt(std::max(0.0, 1.0 - u[i] * u[i])) + 1e-9;
        lo[i] = std::min(p[i], q[i]) - grow;
        hi[i] = std::max(p[i], q[i]) + grow;
      }
      boxes.emplace_back(static_cast<int>(k), Kernel::Iso_cuboid_3(lo.x(), lo.y(), lo.z(), hi.x(),
                                                                   hi.y(), hi.z()));
    }
  }
  Tree tree(boxes.begin(), boxes.end());
  tree.build();

  const double below = options.gouge_range, above = options.excess_range;
  auto sweepOne = [&](size_t i) {
    if (!samples.on_edge.empty() && samples.on_edge[i]) return;
    const Eigen::Vector3d& p = samples.p_w[i];
    const Eigen::Vector3d& nrm = samples.n_w[i];
    const Eigen::Vector3d a = p - below * nrm, b = p + above * nrm;
    const Kernel::Segment_3 blade(Kernel::Point_3(a.x(), a.y(), a.z()),
                                  Kernel::Point_3(b.x(), b.y(), b.z()));
    double top = above;
    int who = -1;
    const Eigen::Vector3d mid = p + 0.5 * (above - below) * nrm;
    const double reach2 = (Rmax + 0.5 * (above + below)) * (Rmax + 0.5 * (above + below));
    auto cut = [&](int k) {
      const ToolPlacement& t = placements[k];
      // Cheap rejection: the blade's midpoint farther from the tool axis than the tool's
      // largest radius plus half the blade.
      const Eigen::Vector3d w = mid - t.tip_w;
      const double h = std::clamp(w.dot(t.axis_w), 0.0, L);
      if ((w - h * t.axis_w).squaredNorm() > reach2) return;
      const double s = cutter.lineEntry(p - t.tip_w, nrm, t.axis_w, -below, top);
      if (s < top) {
        top = s;
        who = k;
      }
    };
    tree.all_intersected_primitives(blade, CallOut<decltype(cut)>{&cut});
    if (who >= 0) {
      result->deviation[i] = top;
      result->machined[i] = 1;
      result->placement[i] = who;
    }
  };
  const size_t block = 4096;
  for (size_t first = 0; first < n; first += block) {
    const size_t last = std::min(n, first + block);
    tbb::parallel_for(tbb::blocked_range<size_t>(first, last, 64),
                      [&](const tbb::blocked_range<size_t>& r) {
                        for (size_t i = r.begin(); i != r.end(); ++i) sweepOne(i);
                      });
    if (progress) progress(static_cast<double>(last) / n);
  }
}

}  // namespace tolver
