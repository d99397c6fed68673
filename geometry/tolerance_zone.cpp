#include "geometry/tolerance_zone.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <stdexcept>

namespace tolver {
namespace {

std::string mm(double v, bool sign = false) {
  char buf[48];
  std::snprintf(buf, sizeof buf, sign ? "%+.6g" : "%.6g", v);
  return buf;
}

void checkTolerance(double t) {
  if (!(t > 0) || !std::isfinite(t))
    throw std::invalid_argument("the tolerance must be a positive number of mm, not " + mm(t));
}

}  // namespace

ToleranceZone bilateralZone(double t) {
  checkTolerance(t);
  ToleranceZone z;
  z.tolerance = t;
  z.lower = -0.5 * t;
  z.upper = 0.5 * t;
  z.spec = "profile " + mm(t);
  return z;
}

ToleranceZone isoUzZone(double t, double offset) {
  checkTolerance(t);
  if (!std::isfinite(offset)) throw std::invalid_argument("the UZ offset must be a number");
  ToleranceZone z;
  z.tolerance = t;
  z.lower = offset - 0.5 * t;
  z.upper = offset + 0.5 * t;
  z.spec = "profile " + mm(t) + " UZ" + mm(offset, true);
  return z;
}

ToleranceZone asmeUZone(double t, double u) {
  checkTolerance(t);
  if (!(u >= 0 && u <= t))
    throw std::invalid_argument("the ASME U value must lie between 0 and the tolerance " + mm(t) +
                                ", not " + mm(u));
  ToleranceZone z;
  z.tolerance = t;
  z.lower = u - t;
  z.upper = u;
  z.spec = "profile " + mm(t) + " U " + mm(u);
  return z;
}

const char* conformanceName(Conformance c) {
  switch (c) {
    case Conformance::In:
      return "in";
    case Conformance::Excess:
      return "excess";
    case Conformance::Gouge:
      return "gouge";
    case Conformance::Unmachined:
      return "unmachined";
    case Conformance::Unchecked:
      return "unchecked";
  }
  return "?";
}

Conformance classify(double deviation, bool machined, const ToleranceZone& zone) {
  if (!machined) return Conformance::Unmachined;
  if (deviation > zone.upper) return Conformance::Excess;
  if (deviation < zone.lower) return Conformance::Gouge;
  return Conformance::In;
}

std::vector<int> assignZones(const SurfaceSamples& samples,
                             const std::vector<ToleranceZone>& zones) {
  std::vector<int> zone_of(samples.size(), -1);
  for (int z = 0; z < static_cast<int>(zones.size()); ++z) {
    const ToleranceZone& zone = zones[z];
    // The groups the zone's region names: by name, or by an alias (a CAD face's name or
    // colour, which several faces may share); all of them when "*".
    const bool any = zone.region == "*" || zone.region.empty();
    std::vector<char> named(samples.group_names.size(), 0);
    if (!zone.has_box && !any)
      for (size_t g = 0; g < named.size(); ++g) {
        named[g] = samples.group_names[g] == zone.region;
        if (g < samples.group_aliases.size())
          for (const std::string& a : samples.group_aliases[g])
            if (a == zone.region) named[g] = 1;
      }
    for (size_t i = 0; i < samples.size(); ++i) {
      const int g = samples.group[i];
      const bool in = zone.has_box
                          ? zone.box_w.contains(samples.p_w[i])
                          : (any || (g >= 0 && g < static_cast<int>(named.size()) && named[g]));
      if (in) zone_of[i] = z;
    }
  }
  return zone_of;
}

std::vector<OutOfToleranceRegion> outOfToleranceRegions(const SurfaceSamples& samples,
                                                        const std::vector<double>& deviation,
                                                        const std::vector<Conformance>& conformance,
                                                        const std::vector<int>& zone_of,
                                                        const std::vector<ToleranceZone>& zones) {
  const size_t n = samples.size();
  std::vector<int> parent(n);
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](int x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  auto bad = [&](int i) {
    return conformance[i] == Conformance::Excess || conformance[i] == Conformance::Gouge;
  };
  for (const auto& f : samples.faces)
    for (int e = 0; e < 3; ++e) {
      const int a = f[e], b = f[(e + 1) % 3];
      if (bad(a) && bad(b) && conformance[a] == conformance[b]) parent[find(a)] = find(b);
    }
  std::vector<int> region_of(n, -1);
  std::vector<OutOfToleranceRegion> regions;
  for (size_t i = 0; i < n; ++i) {
    if (!bad(static_cast<int>(i))) continue;
    const int root = find(static_cast<int>(i));
    if (region_of[root] < 0) {
      region_of[root] = static_cast<int>(regions.size());
      regions.emplace_back();
      regions.back().kind = conformance[i];
      regions.back().zone = zone_of[i];
    }
    OutOfToleranceRegion& r = regions[region_of[root]];
    const ToleranceZone& z = zones[zone_of[i]];
    const double excursion =
        conformance[i] == Conformance::Excess ? deviation[i] - z.upper : z.lower - deviation[i];
    ++r.samples;
    r.area_mm2 += samples.area[i];
    if (excursion > r.worst_excursion || r.worst_sample < 0) {
      r.worst_excursion = excursion;
      r.worst_deviation = deviation[i];
      r.worst_sample = static_cast<int>(i);
      r.where_w = samples.p_w[i];
      r.normal_w = samples.n_w[i];
    }
  }
  std::sort(regions.begin(), regions.end(),
            [](const auto& a, const auto& b) { return a.worst_excursion > b.worst_excursion; });
  return regions;
}

}  // namespace tolver
