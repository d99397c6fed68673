#include "geometry/verification.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <unordered_map>

#include "core/numerics/units.h"
#include "geometry/nearest_point.h"

namespace tolver {
namespace {

// Area-weighted statistics of v over the samples where use(i).
template <class Use>
DeviationStats statistics(const SurfaceSamples& s, const std::vector<double>& v, Use use) {
  DeviationStats st;
  double w = 0, sum = 0, sum2 = 0;
  for (size_t i = 0; i < s.size(); ++i) {
    if (!use(i)) continue;
    const int ii = static_cast<int>(i);
    if (st.samples == 0 || v[i] < st.min) {
      st.min = v[i];
      st.min_sample = ii;
    }
    if (st.samples == 0 || v[i] > st.max) {
      st.max = v[i];
      st.max_sample = ii;
    }
    ++st.samples;
    // A sample with no area (isolated) still counts, with a tiny weight.
    const double a = std::max(s.area[i], 1e-12);
    w += a;
    sum += a * v[i];
    sum2 += a * v[i] * v[i];
  }
  if (w > 0) {
    st.mean = sum / w;
    st.rms = std::sqrt(sum2 / w);
  }
  return st;
}

}  // namespace

void evaluateZones(const SurfaceSamples& samples, const std::vector<ToleranceZone>& zones,
                   VerifyResult* r) {
  const size_t n = samples.size();
  r->zone = assignZones(samples, zones);
  r->conformance.assign(n, Conformance::Unchecked);
  r->area = r->area_machined = r->area_in = r->area_unmachined = r->area_edge = 0;
  for (size_t i = 0; i < n; ++i) {
    r->area += samples.area[i];
    if (!samples.on_edge.empty() && samples.on_edge[i]) {
      r->conformance[i] = Conformance::Unchecked;
      r->area_edge += samples.area[i];
      continue;
    }
    if (!r->machined[i]) {
      r->conformance[i] = Conformance::Unmachined;
      r->area_unmachined += samples.area[i];
      continue;
    }
    if (r->zone[i] < 0) continue;
    r->conformance[i] = classify(r->total[i], true, zones[r->zone[i]]);
    r->area_machined += samples.area[i];
    if (r->conformance[i] == Conformance::In) r->area_in += samples.area[i];
  }
  r->percent_in = r->area_machined > 0 ? 100.0 * r->area_in / r->area_machined : 0.0;
  r->total_stats =
      statistics(samples, r->total, [&](size_t i) { return r->machined[i] && r->zone[i] >= 0; });
  r->regions = outOfToleranceRegions(samples, r->total, r->conformance, r->zone, zones);
  r->pass = r->regions.empty() && r->total_stats.samples > 0;
}

VerifyResult verifyPart(const SurfaceSamples& samples, const Cutter& cutter,
                        const std::vector<ToolPlacement>& nominal,
                        const std::vector<ToolPlacement>& predicted,
                        const std::vector<ToleranceZone>& zones, const SweepOptions& options,
                        const std::function<void(double)>& progress) {
  ToolSet tools;
  tools.cutters = {cutter};
  return verifyPart(samples, tools, nominal, predicted, zones, options, progress);
}

VerifyResult verifyPart(const SurfaceSamples& samples, const ToolSet& tools,
                        const std::vector<ToolPlacement>& nominal,
                        const std::vector<ToolPlacement>& predicted,
                        const std::vector<ToleranceZone>& zones, const SweepOptions& options,
                        const std::function<void(double)>& progress) {
  return verifyPart(samples, tools, tools, nominal, predicted, zones, options, progress);
}

VerifyResult verifyPart(const SurfaceSamples& samples, const ToolSet& tools,
                        const ToolSet& predicted_tools, const std::vector<ToolPlacement>& nominal,
                        const std::vector<ToolPlacement>& predicted,
                        const std::vector<ToleranceZone>& zones, const SweepOptions& options,
                        const std::function<void(double)>& progress) {
  SweepResult nom, pred;
  std::function<void(double)> first, second;
  if (progress) {
    first = [&](double f) { progress(0.5 * f); };
    second = [&](double f) { progress(0.5 + 0.5 * f); };
  }
  sweepSurface(samples, tools, nominal, options, &nom, first);
  // The predicted placements are the nominal ones moved by microns, index for index: each
  // sample first tries the placement that cut it deepest nominally (the same answer, sooner).
  SweepOptions predicted_options = options;
  if (nominal.size() == predicted.size()) predicted_options.first_try = &nom.placement;
  sweepSurface(samples, predicted_tools, predicted, predicted_options, &pred, second);
  const size_t n = samples.size();
  VerifyResult r;
  r.total.assign(n, 0.0);
  r.program.assign(n, 0.0);
  r.machine.assign(n, 0.0);
  r.split.assign(n, Split::Attributable);
  r.total_beyond.assign(n, 0);
  r.machined.assign(n, 0);
  r.cl_index.assign(n, -1);
  r.contact_offset_w.assign(n, Eigen::Vector3f::Zero());
  const double floor_mm = -options.gouge_range + 1e-9;
  const double L = tools.maxLength(), R = tools.maxRadius();
  // How far placement k moves between the perfect and the real machine, seen at height h on the
  // tool (the tip plus the axis's turn over h and over the radius).
  auto moved = [&](int k, double h) {
    const double turn = (predicted[k].axis_w - nominal[k].axis_w).norm();
    return (predicted[k].tip_w - nominal[k].tip_w).norm() + turn * (std::clamp(h, 0.0, L) + R);
  };
  for (size_t i = 0; i < n; ++i) {
    r.machined[i] = pred.machined[i];
    if (pred.machined[i]) {
      r.total[i] = pred.deviation[i];
      r.cl_index[i] = predicted[pred.placement[i]].cl_index;
      r.contact_offset_w[i] = (samples.p_w[i] - predicted[pred.placement[i]].tip_w).cast<float>();
      r.total_beyond[i] = pred.deviation[i] <= floor_mm;
    }
    const bool nom_ok = nom.machined[i] && nom.deviation[i] > floor_mm;
    const bool pred_ok = pred.machined[i] && pred.deviation[i] > floor_mm;
    if (!pred.machined[i]) continue;  // unmachined: no verdict, no split
    if (!nom_ok || !pred_ok) {
      r.split[i] = Split::BeyondRange;
      ++r.split_beyond;
      continue;
    }
    const double machine = pred.deviation[i] - nom.deviation[i];
    const int kn = nom.placement[i], kp = pred.placement[i];
    const Eigen::Vector3d entry = samples.p_w[i] + pred.deviation[i] * samples.n_w[i];
    const double hn = (entry - nominal[kn].tip_w).dot(nominal[kn].axis_w);
    const double hp = (entry - predicted[kp].tip_w).dot(predicted[kp].axis_w);
    const double bound = std::max(moved(kn, hn), moved(kp, hp));
    if (std::abs(machine) > 1.5 * bound + 1e-4) {
      r.split[i] = Split::CutBoundary;
      ++r.split_boundary;
      continue;
    }
    r.program[i] = nom.deviation[i];
    r.machine[i] = machine;
  }
  evaluateZones(samples, zones, &r);
  auto attributable = [&](size_t i) { return r.machined[i] && r.split[i] == Split::Attributable; };
  r.program_stats = statistics(samples, r.program, attributable);
  r.machine_stats = statistics(samples, r.machine, attributable);
  return r;
}

const char* splitName(Split s) {
  switch (s) {
    case Split::Attributable:
      return "split";
    case Split::BeyondRange:
      return "beyond range";
    case Split::CutBoundary:
      return "cut boundary";
  }
  return "";
}

std::vector<ClPass> clPasses(const std::vector<ClPoint>& path) {
  std::vector<ClPass> raw;
  const int n = static_cast<int>(path.size());
  const double cos_turn = std::cos(degToRad(60.0));
  int first = 0;
  Eigen::Vector3d prev_dir = Eigen::Vector3d::Zero();
  for (int i = 1; i < n; ++i) {
    if (path[i].rapid) {
      if (i - 1 > first) raw.push_back({first, i - 1});
      first = i;
      prev_dir.setZero();
      continue;
    }
    const Eigen::Vector3d d = path[i].p_w - path[i - 1].p_w;
    const double len = d.norm();
    if (len < 1e-9) continue;
    const Eigen::Vector3d dir = d / len;
    if (!prev_dir.isZero() && dir.dot(prev_dir) < cos_turn) {
      if (i - 1 > first) raw.push_back({first, i - 1});
      first = i - 1;
    }
    prev_dir = dir;
  }
  if (n - 1 > first) raw.push_back({first, n - 1});
  // Two-point passes much shorter than the typical pass are links between passes.
  std::vector<double> lengths;
  for (const auto& p : raw) lengths.push_back((path[p.last].p_w - path[p.first].p_w).norm());
  std::vector<double> sorted = lengths;
  std::sort(sorted.begin(), sorted.end());
  const double median = sorted.empty() ? 0.0 : sorted[sorted.size() / 2];
  std::vector<ClPass> passes;
  for (size_t k = 0; k < raw.size(); ++k)
    if (raw[k].last - raw[k].first >= 2 || lengths[k] >= 0.25 * median) passes.push_back(raw[k]);
  return passes;
}

std::vector<LineProfilePoint> lineProfile(const SurfaceSamples& samples, const VerifyResult& r,
                                          const ClPass& pass) {
  std::unordered_map<int, int> best;  // cl index -> sample
  for (size_t i = 0; i < samples.size(); ++i) {
    const int c = r.cl_index[i];
    if (c < pass.first || c > pass.last || !r.machined[i]) continue;
    auto it = best.find(c);
    if (it == best.end() || std::abs(r.program[i]) < std::abs(r.program[it->second]))
      best[c] = static_cast<int>(i);
  }
  std::vector<LineProfilePoint> out;
  for (int c = pass.first; c <= pass.last; ++c) {
    auto it = best.find(c);
    if (it == best.end()) continue;
    LineProfilePoint p;
    p.cl_index = c;
    p.sample = it->second;
    p.total = r.total[p.sample];
    p.machine = r.machine[p.sample];
    if (!out.empty())
      p.arc_length =
          out.back().arc_length + (samples.p_w[p.sample] - samples.p_w[out.back().sample]).norm();
    out.push_back(p);
  }
  return out;
}

namespace {

// The surface's pieces: the passes, each cut where it has turned a full turn about the tool
// axis (the turns of a spiral and the loops of an offset contour lie side by side within one
// pass, and are joined as neighbouring passes are).
std::vector<ClPass> surfacePieces(const std::vector<ClPoint>& path,
                                  const std::vector<ClPass>& passes) {
  std::vector<ClPass> out;
  for (const ClPass& p : passes) {
    int first = p.first;
    double turned = 0;
    Eigen::Vector3d prev = Eigen::Vector3d::Zero();
    for (int c = p.first + 1; c <= p.last; ++c) {
      const Eigen::Vector3d u = path[c].u_w.normalized();
      Eigen::Vector3d d = path[c].p_w - path[c - 1].p_w;
      d -= d.dot(u) * u;
      if (d.norm() < 1e-9) continue;
      if (!prev.isZero()) {
        turned += std::atan2(prev.cross(d).dot(u), prev.dot(d));
        if (std::abs(turned) >= 2 * kPi && c - 1 > first) {
          out.push_back({first, c - 1});
          first = c - 1;
          turned = 0;
        }
      }
      prev = d;
    }
    if (p.last > first) out.push_back({first, p.last});
  }
  return out;
}

}  // namespace

// Long by design: [AM01] 5.5.4-5.5.5 step by step (passes, the surfaces through the CL points,
// the deviation per point), on shared per-pass arrays.
void clOnlyDeviation(const std::vector<ClPoint>& nominal, const std::vector<ClPoint>& predicted,
                     const std::vector<ToleranceZone>& zones, const std::vector<double>& width_mm,
                     SurfaceSamples* samples, VerifyResult* result) {
  const std::vector<ClPass> passes = clPasses(nominal);
  // The surface's pieces (passes cut at each full turn), and the nodes along them: the CL points,
  // and on a move longer than the typical gap between neighbouring pieces, points along it (a
  // straight move has only its ends, too few to say what lies beside it). A node's nominal and
  // predicted points are interpolated along its move (cl: the move's end; t: the fraction).
  const std::vector<ClPass> pieces = surfacePieces(nominal, passes);
  struct Node {
    int cl = 0;
    double t = 1;  // 1: the CL point itself
  };
  auto at = [&](const std::vector<ClPoint>& path, const Node& q) -> Eigen::Vector3d {
    return q.t >= 1
               ? path[q.cl].p_w
               : Eigen::Vector3d(path[q.cl - 1].p_w + q.t * (path[q.cl].p_w - path[q.cl - 1].p_w));
  };
  std::vector<Node> node;
  std::vector<int> label, start(pieces.size() + 1, 0);        // start: each piece's first node
  auto makeNodes = [&](const std::vector<double>& spacing) {  // per piece; empty: none
    node.clear();
    label.clear();
    for (size_t k = 0; k < pieces.size(); ++k) {
      start[k] = static_cast<int>(node.size());
      for (int c = pieces[k].first; c <= pieces[k].last; ++c) {
        if (c > pieces[k].first && !spacing.empty() && spacing[k] > 0) {
          const double want = (nominal[c].p_w - nominal[c - 1].p_w).norm() / spacing[k];
          const int parts = want > 1 ? static_cast<int>(std::ceil(std::min(want, 1e6))) : 1;
          for (int m = 1; m < parts; ++m) {
            node.push_back({c, static_cast<double>(m) / parts});
            label.push_back(static_cast<int>(k));
          }
        }
        node.push_back({c, 1.0});
        label.push_back(static_cast<int>(k));
      }
    }
    start[pieces.size()] = static_cast<int>(node.size());
  };
  // Each node's side neighbour: the nearest node of an earlier piece (among its 256 nearest:
  // its own piece's come first, as many as the gap holds), no farther than its cutter's width
  // (the passes of a surface overlap; two sides of one contour do not).
  std::vector<Eigen::Vector3d> points;
  std::vector<int> side;
  std::vector<double> gap;
  double typical = 0;
  // The median (the element nth_element puts in the middle); `otherwise` when there is none.
  auto median = [](std::vector<double> v, double otherwise) {
    if (v.empty()) return otherwise;
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    return v[v.size() / 2];
  };
  // A neighbour beside the node, not ahead of it: their pieces run within 45 degrees of
  // parallel (or antiparallel) there and neither along the tool axis, and when it ends its
  // piece the node does not lie past that end (the next side of a contour, a pass after its
  // link, the piece after a lift).
  // Of those, one across the tool axis before one along it: the rows of a level join each
  // other, not the row above (a level 0.1 mm below another, rows 1 mm apart); a wall's
  // contours, with nothing across, join the level above.
  constexpr double cos45 = 0.70710678118654752;
  std::vector<Eigen::Vector3d> tangent, axis;  // per node: unit tangent (or zero), tool axis
  auto beside = [&](int i, int j) {
    // A move along the tool axis (a plunge, a drilled hole) sweeps no surface beside another.
    for (int q : {i, j})
      if (std::abs(tangent[q].dot(axis[q])) > cos45) return false;
    if (std::abs(tangent[i].dot(tangent[j])) < cos45 &&
        !(tangent[i].isZero() || tangent[j].isZero()))
      return false;
    const int k = label[j];
    const bool first = j == start[k], last = j == start[k + 1] - 1;
    if (!first && !last) return true;
    const Eigen::Vector3d out = first ? Eigen::Vector3d(-tangent[j]) : tangent[j];
    const Eigen::Vector3d offset = points[i] - points[j];
    return offset.dot(out) <= cos45 * offset.norm();
  };
  auto cost = [&](int i, int j) {
    if (!beside(i, j)) return -1.0;
    const Eigen::Vector3d offset = points[i] - points[j];
    const double d = offset.norm();
    return std::abs(offset.dot(axis[i])) > cos45 * d ? d + 1e9 : d;
  };
  auto neighbours = [&] {
    points.clear();
    for (const Node& q : node) points.push_back(at(nominal, q));
    tangent.assign(node.size(), Eigen::Vector3d::Zero());
    for (size_t k = 0; k < pieces.size(); ++k)
      for (int i = start[k]; i < start[k + 1]; ++i) {
        const Eigen::Vector3d d =
            points[std::min(i + 1, start[k + 1] - 1)] - points[std::max(i - 1, start[k])];
        if (d.norm() > 0) tangent[i] = d.normalized();
      }
    axis.clear();
    for (const Node& q : node) axis.push_back(nominal[q.cl].u_w.normalized());
    std::vector<double> reach;
    if (!width_mm.empty())
      for (const Node& q : node) reach.push_back(width_mm[q.cl]);
    side = nearestWithLowerLabel(points, label, 256, reach, cost);
    gap.assign(node.size(), INFINITY);
    std::vector<double> gaps;
    for (size_t i = 0; i < node.size(); ++i)
      if (side[i] >= 0 && points[side[i]] != points[i]) {
        gap[i] = (points[side[i]] - points[i]).norm();
        gaps.push_back(gap[i]);
      }
    typical = median(std::move(gaps), 0.0);
  };
  makeNodes({});
  neighbours();
  {
    // A move longer than twice the gap between its piece and the pieces beside it gets nodes a
    // gap apart (the median gap of the pairs its piece is in, else the program's), at most
    // about 250 000 nodes more in all.
    double length = 0;
    for (const ClPass& p : pieces)
      for (int c = p.first + 1; c <= p.last; ++c)
        length += (nominal[c].p_w - nominal[c - 1].p_w).norm();
    std::vector<std::vector<double>> pair_gaps(pieces.size());
    for (size_t i = 0; i < node.size(); ++i)
      if (std::isfinite(gap[i])) {
        pair_gaps[label[i]].push_back(gap[i]);
        pair_gaps[label[side[i]]].push_back(gap[i]);
      }
    std::vector<double> spacing(pieces.size(), 0.0);
    bool long_move = false;
    for (size_t k = 0; k < pieces.size(); ++k) {
      const double near = median(std::move(pair_gaps[k]), typical);
      spacing[k] = near > 0 ? std::max(near, length / 2.5e5) : 0.0;
      for (int c = pieces[k].first + 1; c <= pieces[k].last && !long_move && spacing[k] > 0; ++c)
        long_move = (nominal[c].p_w - nominal[c - 1].p_w).norm() > 2 * spacing[k];
    }
    if (long_move) {
      makeNodes(spacing);
      neighbours();
    }
  }

  SurfaceSamples& s = *samples;
  s = SurfaceSamples();
  s.group_names = {"cl"};
  std::vector<Node> node_of;                   // per sample
  std::unordered_map<int64_t, int> sample_of;  // CL point, or a node along a move -> sample
  auto sampleOf = [&](int i) {
    const Node& q = node[i];
    const int64_t key = q.t >= 1 ? q.cl : -1 - static_cast<int64_t>(i);
    auto [it, fresh] = sample_of.try_emplace(key, static_cast<int>(s.p_w.size()));
    if (fresh) {
      s.p_w.push_back(at(nominal, q));
      s.n_w.push_back(Eigen::Vector3d::Zero());
      s.area.push_back(0.0);
      s.group.push_back(0);
      node_of.push_back(q);
    }
    return it->second;
  };
  for (size_t i = 0; i < node.size(); ++i)
    if (node[i].t >= 1) sampleOf(static_cast<int>(i));

  // Each piece is joined to the pieces cut before it that it lies beside: each run of its nodes
  // whose side neighbours lie in one earlier piece is zipped to the stretch of that piece they
  // face. Not simply the pass before: the pieces of a spiral cut by lifts, or a pass and its
  // link, follow each other end to end, and strips between them spanned the part (a 200 mm disc
  // had 2.4 M mm2); a piece of a turn lies beside two pieces of the turn before.
  auto P = [&](int i) -> const Eigen::Vector3d& { return points[i]; };
  auto zip = [&](const std::vector<int>& A, const std::vector<int>& B, double width) {
    size_t i = 0, j = 0;
    while (i + 1 < A.size() || j + 1 < B.size()) {
      const int a = A[i], b = B[j];
      const bool advance_b =
          i + 1 == A.size() ||
          (j + 1 < B.size() && (P(A[i]) - P(B[j + 1])).norm() < (P(A[i + 1]) - P(B[j])).norm());
      const int c = advance_b ? B[++j] : A[++i];
      if (P(a) == P(b) || P(b) == P(c) || P(a) == P(c)) continue;
      // A side across the pieces longer than the side along one and a few gaps is no surface
      // between neighbours (a safety net: the runs should leave none).
      const double side_along = advance_b ? (P(b) - P(c)).norm() : (P(a) - P(c)).norm();
      const double side_across = advance_b ? (P(a) - P(c)).norm() : (P(b) - P(c)).norm();
      if (std::max(side_across, (P(a) - P(b)).norm()) > side_along + 4.0 * width + 1e-9) continue;
      Eigen::Vector3i t(sampleOf(a), sampleOf(b), sampleOf(c));
      if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) continue;
      const Eigen::Vector3d fn = (s.p_w[t[1]] - s.p_w[t[0]]).cross(s.p_w[t[2]] - s.p_w[t[0]]);
      const Eigen::Vector3d tool_side =
          nominal[node[a].cl].u_w + nominal[node[b].cl].u_w + nominal[node[c].cl].u_w;
      if (fn.dot(tool_side) < 0) std::swap(t[1], t[2]);
      s.faces.push_back(t);
      s.face_group.push_back(0);
      const double area = 0.5 * fn.norm();
      for (int q = 0; q < 3; ++q) {
        s.n_w[t[q]] += (fn.dot(tool_side) < 0 ? -fn : fn);  // area-weighted
        s.area[t[q]] += area / 3.0;
      }
    }
  };
  // A piece's own gap: the median of its nodes' gaps to the pieces before it (infinite for the
  // first of a feature). A node's neighbour is taken when its gap is within 2.5 times that of
  // the neighbour's piece, or of the program's median when that is larger, or when that piece
  // is the first of its feature (the search kept it within the cutter's width): a wall's levels
  // 6.6 mm apart join, in a program whose holes' helices are 0.2 mm apart; the first pass of a
  // level below, or of the next pocket, does not join the last pass before it (1 mm from its
  // own).
  std::vector<double> own(pieces.size(), INFINITY);
  for (size_t k = 0; k < pieces.size(); ++k) {
    std::vector<double> g;
    for (int i = start[k]; i < start[k + 1]; ++i)
      if (std::isfinite(gap[i])) g.push_back(gap[i]);
    own[k] = median(std::move(g), INFINITY);
  }
  auto neighbourPiece = [&](int i) {
    if (side[i] < 0) return -1;
    const int j = label[side[i]];
    if (!std::isfinite(own[j])) return j;  // the first of its feature: the cutter's width bounds
    return gap[i] <= 2.5 * std::max(own[j], typical) ? j : -1;
  };
  for (size_t k = 1; k < pieces.size(); ++k) {
    const int first = start[k], last = start[k + 1] - 1;
    for (int i = first; i <= last;) {
      const int j = neighbourPiece(i);
      int e = i;
      while (e + 1 <= last && neighbourPiece(e + 1) == j) ++e;
      if (j >= 0 && e > i) {  // a lone node is no stretch beside a piece
        // The run, with the nodes either side (its seams with the runs beside it), against the
        // stretch of piece j its nodes face.
        const int lo = std::max(i - 1, first), hi = std::min(e + 1, last);
        int a_lo = start[j + 1], a_hi = start[j] - 1;
        double along = 0, width = 0;
        for (int q = i; q <= e; ++q) {
          a_lo = std::min(a_lo, std::max(side[q] - 1, start[j]));
          a_hi = std::max(a_hi, std::min(side[q] + 1, start[j + 1] - 1));
          const Eigen::Vector3d tb = P(std::min(q + 1, last)) - P(std::max(q - 1, first));
          const Eigen::Vector3d ta =
              P(std::min(side[q] + 1, start[j + 1] - 1)) - P(std::max(side[q] - 1, start[j]));
          along += tb.dot(ta);
          width = std::max(width, gap[q]);
        }
        std::vector<int> A, B;
        for (int q = a_lo; q <= a_hi; ++q) A.push_back(q);
        for (int q = lo; q <= hi; ++q) B.push_back(q);
        if (along < 0) std::reverse(B.begin(), B.end());
        if (A.size() >= 2 || B.size() >= 2) zip(A, B, width);
      }
      i = e + 1;
    }
  }
  // Normals; a point on no strip (a lone pass) takes its tool axis.
  for (size_t i = 0; i < s.p_w.size(); ++i) {
    const double len = s.n_w[i].norm();
    s.n_w[i] = len > 0 ? Eigen::Vector3d(s.n_w[i] / len) : nominal[node_of[i].cl].u_w.normalized();
  }
  VerifyResult& r = *result;
  r = VerifyResult();
  const size_t n = s.p_w.size();
  r.total.assign(n, 0.0);
  r.program.assign(n, 0.0);
  r.machine.assign(n, 0.0);
  r.split.assign(n, Split::Attributable);
  r.total_beyond.assign(n, 0);
  r.machined.assign(n, 1);
  r.cl_index.assign(n, -1);
  r.contact_offset_w.assign(n, Eigen::Vector3f::Zero());  // the surface through the tips
  for (size_t i = 0; i < n; ++i) {
    r.cl_index[i] = node_of[i].cl;
    r.total[i] = r.machine[i] = (at(predicted, node_of[i]) - s.p_w[i]).dot(s.n_w[i]);
  }
  evaluateZones(s, zones, &r);
  r.machine_stats = r.total_stats;
  r.program_stats = DeviationStats();
  r.program_stats.samples = r.total_stats.samples;
}

std::vector<RegionSummary> summariseRegions(const SurfaceSamples& samples,
                                            const VerifyResult& result) {
  std::vector<RegionSummary> out(std::max<size_t>(samples.group_names.size(), 1));
  std::vector<char> machined(out.size(), 0);
  for (size_t g = 0; g < out.size(); ++g) out[g].group = static_cast<int>(g);
  for (size_t i = 0; i < samples.size(); ++i) {
    const int g = samples.group[i];
    if (g < 0 || g >= static_cast<int>(out.size())) continue;
    RegionSummary& r = out[g];
    ++r.samples;
    r.area_mm2 += samples.area[i];
    if (i < result.machined.size() && result.machined[i]) machined[g] = 1;
    if (i >= result.conformance.size()) continue;
    const Conformance c = result.conformance[i];
    if (c == Conformance::Unchecked || c == Conformance::Unmachined) continue;
    ++r.checked;
    r.checked_mm2 += samples.area[i];
    if (c != Conformance::In) {
      ++r.out;
      r.out_mm2 += samples.area[i];
    }
    if (r.worst_sample < 0 || std::abs(result.total[i]) > std::abs(r.worst_mm)) {
      r.worst_mm = result.total[i];
      r.worst_sample = static_cast<int>(i);
    }
  }
  for (size_t g = 0; g < out.size(); ++g)
    out[g].status = out[g].out > 0       ? "out"
                    : out[g].checked > 0 ? "in"
                    : !machined[g]       ? "unmachined"
                                         : "unchecked";
  return out;
}

}  // namespace tolver
