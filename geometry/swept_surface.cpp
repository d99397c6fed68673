#include "geometry/swept_surface.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>
#include <unordered_map>

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
  explicit BoxTree(const std::vector<Box>& boxes) {
    if (boxes.empty()) return;
    // The splits sort compact keys (the centre in floats, 16 bytes) rather than the boxes (56):
    // the build took 6 % of a verify's CPU moving boxes. The boxes then take the keys' order.
    const int n = static_cast<int>(boxes.size());
    keys_.resize(n);
    tbb::parallel_for(tbb::blocked_range<int>(0, n, 8192), [&](const tbb::blocked_range<int>& r) {
      for (int k = r.begin(); k < r.end(); ++k) {
        const Eigen::Array3d c = boxes[k].lo + boxes[k].hi;
        keys_[k] = {{static_cast<float>(c[0]), static_cast<float>(c[1]), static_cast<float>(c[2])},
                    k};
      }
    });
    // Each subtree's nodes follow its root (the left subtree's first): with the node count of a
    // subtree known from its size, both halves are built at once, into the places they take.
    countNodes(n);
    nodes_.resize(node_count_.at(n));
    build(boxes, 0, 0, n);
    boxes_.resize(n);
    tbb::parallel_for(tbb::blocked_range<int>(0, n, 8192), [&](const tbb::blocked_range<int>& r) {
      for (int k = r.begin(); k < r.end(); ++k) boxes_[k] = boxes[keys_[k].index];
    });
    std::vector<Key>().swap(keys_);
  }
  // Calls f(id) for each box that overlaps [lo, hi]. lo and hi may shrink while it runs (f
  // changes them): what is left to visit is tested against them as they are.
  template <class F>
  void query(const Eigen::Array3d& lo, const Eigen::Array3d& hi, F&& f) const {
    visit([&](const Eigen::Array3d& a,
              const Eigen::Array3d& b) { return !((a > hi).any() || (b < lo).any()); },
          f);
  }
  // Calls f(id) for each box within Euclidean distance sqrt(r2) of the box [lo, hi] (both may
  // shrink while it runs, as above).
  template <class F>
  void queryNear(const Eigen::Array3d& lo, const Eigen::Array3d& hi, const double& r2,
                 F&& f) const {
    visit(
        [&](const Eigen::Array3d& a, const Eigen::Array3d& b) {
          return ((a - hi).max(lo - b).max(0.0)).square().sum() <= r2;
        },
        f);
  }

 private:
  template <class Near, class F>
  void visit(Near&& near, F&& f) const {
    if (nodes_.empty()) return;
    int stack[128];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
      const Node& node = nodes_[stack[--top]];
      if (!near(node.lo, node.hi)) continue;
      if (node.count > 0) {
        for (int k = node.first; k < node.first + node.count; ++k) {
          const Box& b = boxes_[k];
          if (near(b.lo, b.hi)) f(b.id);
        }
      } else {
        stack[top++] = node.right;
        stack[top++] = node.first;  // the left child
      }
    }
  }

  static constexpr int kLeaf = 4;
  struct Node {
    Eigen::Array3d lo, hi;
    int first = 0;  // leaf: first box; inner: left child
    int count = 0;  // boxes in a leaf, 0 for an inner node
    int right = 0;
  };
  // The nodes of a subtree over n boxes, for every size the splits below n make (at most two a
  // level).
  int countNodes(int n) {
    if (const auto it = node_count_.find(n); it != node_count_.end()) return it->second;
    const int c = n <= kLeaf ? 1 : 1 + countNodes(n / 2) + countNodes(n - n / 2);
    node_count_.emplace(n, c);
    return c;
  }
  // The node `index` over keys_[first, last) (boxes given, by their keys' index), its subtree's
  // nodes after it. Depth stays below 64: each split halves. Halves of more than kParallel keys
  // are built in parallel (the nodes and the keys they sort are their own).
  void build(const std::vector<Box>& boxes, int index, int first, int last) {
    Node& node = nodes_[index];
    if (last - first <= kLeaf) {
      Eigen::Array3d lo = boxes[keys_[first].index].lo, hi = boxes[keys_[first].index].hi;
      for (int k = first + 1; k < last; ++k) {
        lo = lo.min(boxes[keys_[k].index].lo);
        hi = hi.max(boxes[keys_[k].index].hi);
      }
      node.lo = lo;
      node.hi = hi;
      node.first = first;
      node.count = last - first;
      return;
    }
    std::array<float, 3> clo = keys_[first].c, chi = clo;
    for (int k = first + 1; k < last; ++k)
      for (int i = 0; i < 3; ++i) {
        clo[i] = std::min(clo[i], keys_[k].c[i]);
        chi[i] = std::max(chi[i], keys_[k].c[i]);
      }
    int axis = 0;
    for (int i = 1; i < 3; ++i)
      if (chi[i] - clo[i] > chi[axis] - clo[axis]) axis = i;
    const int mid = first + (last - first) / 2;
    std::nth_element(keys_.begin() + first, keys_.begin() + mid, keys_.begin() + last,
                     [axis](const Key& a, const Key& b) { return a.c[axis] < b.c[axis]; });
    const int left = index + 1, right = index + 1 + node_count_.at(mid - first);
    if (last - first > kParallel)
      tbb::parallel_invoke([&] { build(boxes, left, first, mid); },
                           [&] { build(boxes, right, mid, last); });
    else
      build(boxes, left, first, mid), build(boxes, right, mid, last);
    // The box from the children's (each node's box is its boxes').
    node.lo = nodes_[left].lo.min(nodes_[right].lo);
    node.hi = nodes_[left].hi.max(nodes_[right].hi);
    node.first = left;
    node.right = right;
  }
  static constexpr int kParallel = 16384;
  std::unordered_map<int, int> node_count_;  // the nodes of a subtree, by its boxes
  struct Key {
    std::array<float, 3> c;  // the box's centre, twice (lo + hi)
    int index;               // into the boxes given
  };
  std::vector<Key> keys_;  // while building
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
  // A ball end (no flat between the corners): the ball's centres go in a tree of their own,
  // searched by distance (a blade meets the ball only within rc of its centre), and the boxes of
  // the rest of the tool start at the centre's height, where it is no wider than the ball's
  // radius: a blade on the surface meets the ball of a few placements and the boxes of none.
  const double rc = cutter.corner_radius;
  const bool ball = rc > 0 && 0.5 * cutter.diameter - rc <= 1e-12 && rc < L;
  const double from = ball ? rc : 0.0;  // where the boxes start along the axis
  // One box per chunk of the cutter no longer than its diameter: a tilted tool's single box would
  // hold much empty space, and every blade inside it would test the tool for nothing.
  const int chunks =
      std::max(1, static_cast<int>(std::ceil((L - from) / std::max(2.0 * Rmax, 1e-6))));
  // The boxes in parallel, placement by placement (box k * chunks + c: chunk c of placement k).
  std::vector<BoxTree::Box> boxes(placements.size() * chunks),
      centres(ball ? placements.size() : 0);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, placements.size(), 4096),
                    [&](const tbb::blocked_range<size_t>& r) {
                      for (size_t k = r.begin(); k != r.end(); ++k) {
                        const Eigen::Vector3d& u = placements[k].axis_w;
                        if (ball) {
                          const Eigen::Array3d c = (placements[k].tip_w + rc * u).array();
                          centres[k] = {c, c, static_cast<int>(k)};
                        }
                        for (int c = 0; c < chunks; ++c) {
                          const double h0 = from + (L - from) * c / chunks,
                                       h1 = from + (L - from) * (c + 1) / chunks;
                          const Eigen::Vector3d p = placements[k].tip_w + h0 * u;
                          const Eigen::Vector3d q = placements[k].tip_w + h1 * u;
                          const double radius = std::max(cutter.radiusAt(h0), cutter.radiusAt(h1));
                          // Box of the cylinder of that radius around the axis segment: per
                          // coordinate the segment's extent plus radius sqrt(1 - u_i^2).
                          Eigen::Vector3d lo, hi;
                          for (int i = 0; i < 3; ++i) {
                            const double grow =
                                radius * std::sqrt(std::max(0.0, 1.0 - u[i] * u[i])) + 1e-9;
                            lo[i] = std::min(p[i], q[i]) - grow;
                            hi[i] = std::max(p[i], q[i]) + grow;
                          }
                          boxes[k * chunks + c] = {lo.array(), hi.array(), static_cast<int>(k)};
                        }
                      }
                    });
  const BoxTree tree(boxes), centre_tree(centres);
  std::vector<BoxTree::Box>().swap(boxes);  // the trees hold their own, in their order
  std::vector<BoxTree::Box>().swap(centres);

  const double below = options.gouge_range, above = options.excess_range;
  // With a ball end, below the plane of the ball's centre the tool is the ball alone.
  const double ball_reach2 = (rc + 1e-9) * (rc + 1e-9);
  // What is left of the blade is [-below, top] along the normal, and only a placement that
  // reaches into it can cut deeper: the search box and the rejection tests shrink with it, and
  // each blade first tries the placement that cut the previous sample of its block (a
  // neighbour: it, or one near it, usually cuts deepest), so the blade is short from the start.
  // The tests only skip placements that cannot meet what is left of the blade (each bound holds
  // with a margin of 1e-9 mm), so the answer is the same as testing every placement.
  auto sweepOne = [&](size_t i, int& hint) {
    if (!samples.on_edge.empty() && samples.on_edge[i]) return;
    const Eigen::Vector3d& p = samples.p_w[i];
    const Eigen::Vector3d& nrm = samples.n_w[i];
    const Eigen::Vector3d e0 = p - below * nrm;  // the blade's lower end
    double top = above;
    int who = -1;
    Eigen::Array3d lo, hi;
    Eigen::Vector3d mid;
    double reach2 = 0.0;
    auto shrink = [&]() {
      const Eigen::Array3d b = (p + top * nrm).array();
      lo = e0.array().min(b);
      hi = e0.array().max(b);
      const double half = 0.5 * (top + below);
      mid = p + 0.5 * (top - below) * nrm;
      reach2 = (Rmax + half + 1e-9) * (Rmax + half + 1e-9);
    };
    shrink();
    auto cut = [&](int k) {
      const ToolPlacement& t = placements[k];
      bool below_centre = false;
      if (ball) {
        // The blade wholly below the ball centre's plane: it meets the tool only if it comes
        // within rc of the centre.
        const Eigen::Vector3d e0c = e0 - (t.tip_w + rc * t.axis_w);
        const double len = top + below;
        const double h0 = e0c.dot(t.axis_w), h1 = h0 + len * nrm.dot(t.axis_w);
        if (h0 < -1e-9 && h1 < -1e-9) {
          const double along = std::clamp(-e0c.dot(nrm), 0.0, len);
          if ((e0c + along * nrm).squaredNorm() > ball_reach2) return;
          below_centre = true;
        }
      }
      if (!below_centre) {
        // The blade's midpoint farther from the tool axis than the tool's largest radius plus
        // half the blade.
        const Eigen::Vector3d w = mid - t.tip_w;
        const double h = std::clamp(w.dot(t.axis_w), 0.0, L);
        if ((w - h * t.axis_w).squaredNorm() > reach2) return;
      }
      const double s = cutter.lineEntry(p - t.tip_w, nrm, t.axis_w, -below, top);
      // Ties go to the earlier placement, whatever order the tree visits them in.
      if (s < top || (s == top && who > k)) {
        const bool deeper = s < top;
        top = s;
        who = k;
        if (deeper) shrink();
      }
    };
    if (options.first_try && (*options.first_try)[i] >= 0 &&
        (*options.first_try)[i] < static_cast<int>(placements.size()))
      cut((*options.first_try)[i]);
    if (hint >= 0) cut(hint);
    if (ball) centre_tree.queryNear(lo, hi, ball_reach2, cut);
    tree.query(lo, hi, cut);
    if (who >= 0) {
      result->deviation[i] = top;
      result->machined[i] = 1;
      result->placement[i] = who;
      hint = who;
    }
  };
  const size_t block = 4096;
  for (size_t first = 0; first < n; first += block) {
    const size_t last = std::min(n, first + block);
    tbb::parallel_for(tbb::blocked_range<size_t>(first, last, 64),
                      [&](const tbb::blocked_range<size_t>& r) {
                        int hint = -1;
                        for (size_t i = r.begin(); i != r.end(); ++i) sweepOne(i, hint);
                      });
    if (progress) progress(static_cast<double>(last) / n);
  }
}

double ToolSet::maxLength() const {
  double L = 0.0;
  for (const Cutter& c : cutters) L = std::max(L, c.effectiveLength());
  return L;
}

double ToolSet::maxRadius() const {
  double R = 0.0;
  for (const Cutter& c : cutters) R = std::max(R, c.maxRadius());
  return R;
}

void sweepSurface(const SurfaceSamples& samples, const ToolSet& tools,
                  const std::vector<ToolPlacement>& placements, const SweepOptions& options,
                  SweepResult* result, const std::function<void(double)>& progress) {
  if (tools.cutters.size() == 1 || tools.tool_of_cl.empty()) {
    sweepSurface(samples, tools.cutters.front(), placements, options, result, progress);
    return;
  }
  // Several tools: each sweeps its own placements, numbered afresh (no first tries).
  SweepOptions own_options = options;
  own_options.first_try = nullptr;
  const size_t n = samples.size();
  result->deviation.assign(n, options.excess_range);
  result->machined.assign(n, 0);
  result->placement.assign(n, -1);
  const int tool_count = static_cast<int>(tools.cutters.size());
  std::vector<std::vector<int>> of_tool(tool_count);
  for (size_t k = 0; k < placements.size(); ++k) {
    const int cl = placements[k].cl_index;
    const int t =
        cl >= 0 && cl < static_cast<int>(tools.tool_of_cl.size()) ? tools.tool_of_cl[cl] : 0;
    of_tool[std::clamp(t, 0, tool_count - 1)].push_back(static_cast<int>(k));
  }
  size_t done = 0;
  for (int t = 0; t < tool_count; ++t) {
    if (of_tool[t].empty()) continue;
    std::vector<ToolPlacement> own;
    own.reserve(of_tool[t].size());
    for (int k : of_tool[t]) own.push_back(placements[k]);
    SweepResult r;
    const double share = static_cast<double>(own.size()) / static_cast<double>(placements.size());
    const double before = static_cast<double>(done) / static_cast<double>(placements.size());
    sweepSurface(samples, tools.cutters[t], own, own_options, &r, [&](double f) {
      if (progress) progress(before + share * f);
    });
    done += own.size();
    for (size_t i = 0; i < n; ++i) {
      if (!r.machined[i]) continue;
      if (!result->machined[i] || r.deviation[i] < result->deviation[i]) {
        result->deviation[i] = r.deviation[i];
        result->placement[i] = of_tool[t][r.placement[i]];
      }
      result->machined[i] = 1;
    }
  }
}

}  // namespace tolver
