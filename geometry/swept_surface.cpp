#include "geometry/swept_surface.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>

namespace tolver {
namespace {

// A bounding-volume hierarchy over axis-aligned boxes (one per chunk of each tool placement),
// queried with a box: median splits on the longest axis of the centroids, four boxes a leaf,
// nodes and boxes in flat arrays, an explicit stack. It replaced CGAL's AABB tree with segment
// queries, whose generic traversal was 60 % of a sweep: a blade is 0.3 mm long, so its own box
// rejects nearly as well, and box-box tests are a few comparisons.
class BoxTree {
 public:
  struct Box {
    Eigen::Array3d lo, hi;
    int id;
  };
  explicit BoxTree(std::vector<Box> boxes) : boxes_(std::move(boxes)) {
    if (!boxes_.empty()) {
      nodes_.reserve(2 * boxes_.size() / kLeaf + 2);
      build(0, static_cast<int>(boxes_.size()));
    }
  }
  // Calls f(id) for each box that overlaps [lo, hi].
  template <class F>
  void query(const Eigen::Array3d& lo, const Eigen::Array3d& hi, F&& f) const {
    if (nodes_.empty()) return;
    int stack[128];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
      const Node& node = nodes_[stack[--top]];
      if ((node.lo > hi).any() || (node.hi < lo).any()) continue;
      if (node.count > 0) {
        for (int k = node.first; k < node.first + node.count; ++k) {
          const Box& b = boxes_[k];
          if (!((b.lo > hi).any() || (b.hi < lo).any())) f(b.id);
        }
      } else {
        stack[top++] = node.right;
        stack[top++] = node.first;  // the left child
      }
    }
  }

 private:
  static constexpr int kLeaf = 4;
  struct Node {
    Eigen::Array3d lo, hi;
    int first = 0;  // leaf: first box; inner: left child
    int count = 0;  // boxes in a leaf, 0 for an inner node
    int right = 0;
  };
  // The node over boxes_[first, last); returns its index. Depth stays below 64: each split halves.
  int build(int first, int last) {
    const int index = static_cast<int>(nodes_.size());
    nodes_.emplace_back();
    Eigen::Array3d lo = boxes_[first].lo, hi = boxes_[first].hi;
    Eigen::Array3d clo = lo + hi, chi = clo;
    for (int k = first + 1; k < last; ++k) {
      lo = lo.min(boxes_[k].lo);
      hi = hi.max(boxes_[k].hi);
      const Eigen::Array3d c = boxes_[k].lo + boxes_[k].hi;
      clo = clo.min(c);
      chi = chi.max(c);
    }
    nodes_[index].lo = lo;
    nodes_[index].hi = hi;
    if (last - first <= kLeaf) {
      nodes_[index].first = first;
      nodes_[index].count = last - first;
      return index;
    }
    int axis = 0;
    (chi - clo).maxCoeff(&axis);
    const int mid = first + (last - first) / 2;
    std::nth_element(boxes_.begin() + first, boxes_.begin() + mid, boxes_.begin() + last,
                     [axis](const Box& a, const Box& b) {
                       return a.lo[axis] + a.hi[axis] < b.lo[axis] + b.hi[axis];
                     });
    const int left = build(first, mid);
    const int right = build(mid, last);
    nodes_[index].first = left;
    nodes_[index].right = right;
    return index;
  }
  std::vector<Box> boxes_;
  std::vector<Node> nodes_;
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
  std::vector<BoxTree::Box> boxes;
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
      boxes.push_back({lo.array(), hi.array(), static_cast<int>(k)});
    }
  }
  const BoxTree tree(std::move(boxes));

  const double below = options.gouge_range, above = options.excess_range;
  auto sweepOne = [&](size_t i) {
    if (!samples.on_edge.empty() && samples.on_edge[i]) return;
    const Eigen::Vector3d& p = samples.p_w[i];
    const Eigen::Vector3d& nrm = samples.n_w[i];
    const Eigen::Array3d a = (p - below * nrm).array(), b = (p + above * nrm).array();
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
      // Ties go to the earlier placement, whatever order the tree visits them in.
      if (s < top || (s == top && who > k)) {
        top = s;
        who = k;
      }
    };
    tree.query(a.min(b), a.max(b), cut);
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
