#include "geometry/verification.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <unordered_map>

#include "core/numerics/units.h"

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

// Long by design: [AM01] 5.5.4-5.5.5 step by step (passes, the surfaces through the CL points,
// the deviation per point), on shared per-pass arrays.
void clOnlyDeviation(const std::vector<ClPoint>& nominal, const std::vector<ClPoint>& predicted,
                     const std::vector<ToleranceZone>& zones, SurfaceSamples* samples,
                     VerifyResult* result) {
  const std::vector<ClPass> passes = clPasses(nominal);
  std::unordered_map<int, int> sample_of;  // CL index -> sample
  SurfaceSamples& s = *samples;
  s = SurfaceSamples();
  s.group_names = {"cl"};
  auto sampleOf = [&](int c) {
    auto [it, fresh] = sample_of.try_emplace(c, static_cast<int>(s.p_w.size()));
    if (fresh) {
      s.p_w.push_back(nominal[c].p_w);
      s.n_w.push_back(Eigen::Vector3d::Zero());
      s.area.push_back(0.0);
      s.group.push_back(0);
    }
    return it->second;
  };
  for (const auto& p : passes)
    for (int c = p.first; c <= p.last; ++c) sampleOf(c);

  // Gaps between consecutive passes, to join only neighbours.
  auto gap = [&](const ClPass& a, const ClPass& b) {
    const Eigen::Vector3d m = nominal[(b.first + b.last) / 2].p_w;
    double best = INFINITY;
    for (int c = a.first; c <= a.last; ++c) best = std::min(best, (nominal[c].p_w - m).norm());
    return best;
  };
  std::vector<double> gaps;
  for (size_t k = 1; k < passes.size(); ++k) gaps.push_back(gap(passes[k - 1], passes[k]));
  std::vector<double> sorted = gaps;
  std::sort(sorted.begin(), sorted.end());
  const double median = sorted.empty() ? 0.0 : sorted[sorted.size() / 2];
  for (size_t k = 1; k < passes.size(); ++k) {
    if (gaps[k - 1] > 4.0 * median) continue;
    std::vector<int> A, B;
    for (int c = passes[k - 1].first; c <= passes[k - 1].last; ++c) A.push_back(c);
    for (int c = passes[k].first; c <= passes[k].last; ++c) B.push_back(c);
    auto P = [&](int c) { return nominal[c].p_w; };
    if ((P(A.front()) - P(B.front())).norm() + (P(A.back()) - P(B.back())).norm() >
        (P(A.front()) - P(B.back())).norm() + (P(A.back()) - P(B.front())).norm())
      std::reverse(B.begin(), B.end());
    size_t i = 0, j = 0;
    while (i + 1 < A.size() || j + 1 < B.size()) {
      int a = A[i], b = B[j], c;
      if (i + 1 == A.size() ||
          (j + 1 < B.size() && (P(A[i]) - P(B[j + 1])).norm() < (P(A[i + 1]) - P(B[j])).norm())) {
        c = B[++j];
      } else {
        c = A[++i];
      }
      if (a == b || b == c || a == c) continue;
      Eigen::Vector3i t(sampleOf(a), sampleOf(b), sampleOf(c));
      const Eigen::Vector3d fn = (s.p_w[t[1]] - s.p_w[t[0]]).cross(s.p_w[t[2]] - s.p_w[t[0]]);
      const Eigen::Vector3d axis = nominal[a].u_w + nominal[b].u_w + nominal[c].u_w;
      if (fn.dot(axis) < 0) std::swap(t[1], t[2]);
      s.faces.push_back(t);
      s.face_group.push_back(0);
      const double area = 0.5 * fn.norm();
      for (int q = 0; q < 3; ++q) {
        s.n_w[t[q]] += (fn.dot(axis) < 0 ? -fn : fn);  // area-weighted
        s.area[t[q]] += area / 3.0;
      }
    }
  }
  // Normals; a point on no strip (a lone pass) takes its tool axis.
  std::vector<int> cl_of(s.p_w.size());
  for (const auto& [c, i] : sample_of) cl_of[i] = c;
  for (size_t i = 0; i < s.p_w.size(); ++i) {
    const double len = s.n_w[i].norm();
    s.n_w[i] = len > 0 ? Eigen::Vector3d(s.n_w[i] / len) : nominal[cl_of[i]].u_w.normalized();
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
    const int c = cl_of[i];
    r.cl_index[i] = c;
    r.total[i] = r.machine[i] = (predicted[c].p_w - nominal[c].p_w).dot(s.n_w[i]);
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
