#include "core/model/effects.h"

#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "core/numerics/chebyshev.h"
#include "core/numerics/units.h"

namespace tolver {
namespace {

constexpr double kTwoPi = 6.283185307179586;

double direction(const EffectSpec& e, const MotionContext* ctx) {
  return ctx ? static_cast<double>(ctx->direction[e.axis]) : 0.0;
}

double time(const MotionContext* ctx) {
  return ctx && std::isfinite(ctx->time_s) ? ctx->time_s : NAN;
}

std::string order(const char* prefix, int k) { return prefix + std::to_string(k); }

// Candidate generators.
std::vector<EffectSpec> alongEachAxis(const MachineModel& m, EffectType type, bool prismatic_only,
                                      bool rotary_only) {
  std::vector<EffectSpec> out;
  for (int a = 0; a < static_cast<int>(m.axes.size()); ++a) {
    if ((prismatic_only && m.axes[a].isRotary()) || (rotary_only && !m.axes[a].isRotary()))
      continue;
    const int c = principalComponent(m.axes[a]);
    if (c < 0) continue;
    EffectSpec e;
    e.type = type;
    e.axis = a;
    e.component = c;
    out.push_back(e);
  }
  return out;
}

// Every motion-error component (translations and angles) of every axis: thermal effects can
// move or tilt any carriage.
std::vector<EffectSpec> everyComponent(const MachineModel& m, EffectType type) {
  std::vector<EffectSpec> out;
  for (int a = 0; a < static_cast<int>(m.axes.size()); ++a)
    for (int c = 0; c < 6; ++c) {
      EffectSpec e;
      e.type = type;
      e.axis = a;
      e.component = c;
      out.push_back(e);
    }
  return out;
}

std::vector<EffectSpec> chebyshevCandidates(const MachineModel& m) {
  std::vector<EffectSpec> out;
  for (const ParameterBlock& b : m.blocks) {
    if (b.kind != BlockKind::MotionError) continue;
    int top = b.degree;  // the highest order already in the model for this component
    for (const ParameterBlock& o : m.blocks)
      if (o.kind == BlockKind::Effect && m.effects[o.effect].type == EffectType::Chebyshev &&
          m.effects[o.effect].axis == b.axis && m.effects[o.effect].component == b.component)
        top = std::max(top, m.effects[o.effect].last_order);
    // Two more orders (a smooth residual shape), and five (up to degree 8 over a cubic base:
    // a straightness with a few waves over the travel). Not five on a rotary axis of (nearly) a
    // full turn: its errors repeat with the angle, which the harmonics describe.
    const Axis& ax = m.axes[b.axis];
    const bool full_turn = ax.isRotary() && ax.travel_max - ax.travel_min > 1.6 * kPi;
    for (int extra : {2, 5}) {
      if (extra == 5 && full_turn) continue;
      EffectSpec e;
      e.type = EffectType::Chebyshev;
      e.axis = b.axis;
      e.component = b.component;
      e.first_order = top + 1;
      e.last_order = top + extra;
      out.push_back(e);
    }
  }
  return out;
}

std::vector<EffectSpec> reversalCandidates(const MachineModel& m) {
  std::vector<EffectSpec> out = alongEachAxis(m, EffectType::Reversal, false, false);
  const size_t n = out.size();
  for (size_t i = 0; i < n; ++i) {
    EffectSpec v = out[i];
    v.varying = true;
    out.push_back(v);
  }
  return out;
}

std::vector<EffectSpec> harmonicCandidates(const MachineModel& m) {
  std::vector<EffectSpec> out;
  for (int a = 0; a < static_cast<int>(m.axes.size()); ++a) {
    if (!m.axes[a].isRotary()) continue;
    for (int c = 0; c < 6; ++c) {
      EffectSpec e;
      e.type = EffectType::Harmonics;
      e.axis = a;
      e.component = c;
      // Once per revolution (an eccentric runout, a tilted bearing) and orders 2-4 (a lobed
      // bearing, an out-of-flat table). Where order 1 falls into the span of the link errors
      // the selection reports it confounded.
      e.first_order = 1;
      e.last_order = 1;
      out.push_back(e);
      e.first_order = 2;
      e.last_order = 4;
      out.push_back(e);
    }
  }
  return out;
}

std::vector<EffectSpec> barCandidates(const MachineModel&) {
  EffectSpec e;
  e.type = EffectType::BarLength;
  return {e};
}

const std::vector<EffectTraits>& table() {
  static const std::vector<EffectTraits> types = {
      {EffectType::Chebyshev,
       "chebyshev",
       "a higher Chebyshev degree of one motion-error component",
       "position",
       [](const EffectSpec& e) { return e.last_order - e.first_order + 1; },
       [](const EffectSpec& e, double, double x, const MotionContext*, double* phi) {
         double T[32];
         chebyshevBasis(x, e.last_order, T);
         for (int k = e.first_order; k <= e.last_order; ++k) phi[k - e.first_order] = T[k];
       },
       [](const EffectSpec& e, int k) { return order("c", e.first_order + k); },
       chebyshevCandidates,
       {}},
      {EffectType::Reversal,
       "reversal",
       "reversal (backlash): an offset that depends on the approach direction",
       "direction",
       [](const EffectSpec& e) { return e.varying ? 2 : 1; },
       [](const EffectSpec& e, double, double x, const MotionContext* ctx, double* phi) {
         const double d = direction(e, ctx);
         phi[0] = 0.5 * d;
         if (e.varying) phi[1] = 0.5 * d * x;
       },
       [](const EffectSpec&, int k) { return std::string(k == 0 ? "rev" : "rev.x"); },
       [](const MachineModel& m) { return reversalCandidates(m); },
       {}},
      {EffectType::Periodic,
       "periodic",
       "a cyclic error of a prismatic axis (ball-screw lead), sine and cosine",
       "position",
       [](const EffectSpec&) { return 2; },
       [](const EffectSpec& e, double s, double, const MotionContext*, double* phi) {
         const double w = kTwoPi * s / e.period;
         phi[0] = std::sin(w);
         phi[1] = std::cos(w);
       },
       [](const EffectSpec&, int k) { return std::string(k == 0 ? "cyc.sin" : "cyc.cos"); },
       [](const MachineModel& m) { return alongEachAxis(m, EffectType::Periodic, true, false); },
       {"period_mm", 5.0, 40.0, true}},
      {EffectType::Harmonics,
       "harmonics",
       "rotary-axis harmonics: Fourier terms of the angle",
       "angle",
       [](const EffectSpec& e) { return 2 * (e.last_order - e.first_order + 1); },
       [](const EffectSpec& e, double s, double, const MotionContext*, double* phi) {
         for (int k = e.first_order; k <= e.last_order; ++k) {
           phi[2 * (k - e.first_order)] = std::cos(k * s);
           phi[2 * (k - e.first_order) + 1] = std::sin(k * s);
         }
       },
       [](const EffectSpec& e, int k) {
         return order("h", e.first_order + k / 2) + (k % 2 == 0 ? "c" : "s");
       },
       harmonicCandidates,
       {}},
      {EffectType::Drift,
       "drift",
       "thermal drift, linear in time",
       "time",
       [](const EffectSpec&) { return 1; },
       [](const EffectSpec&, double, double, const MotionContext* ctx, double* phi) {
         const double t_s = time(ctx);
         phi[0] = std::isfinite(t_s) ? t_s / 3600.0 : 0.0;
       },
       [](const EffectSpec&, int) { return std::string("drift"); },
       [](const MachineModel& m) { return everyComponent(m, EffectType::Drift); },
       {}},
      {EffectType::Warmup,
       "warmup",
       "thermal drift settling as a first-order exponential (time constant by search)",
       "time",
       [](const EffectSpec&) { return 1; },
       [](const EffectSpec& e, double, double, const MotionContext* ctx, double* phi) {
         const double t_s = time(ctx);
         phi[0] = std::isfinite(t_s) ? -std::expm1(-t_s / e.tau) : 0.0;
       },
       [](const EffectSpec&, int) { return std::string("warm"); },
       [](const MachineModel& m) { return everyComponent(m, EffectType::Warmup); },
       {"tau_s", 300.0, 4.0 * 3600.0, false}},
      {EffectType::BarLength,
       "bar_length",
       "an error of the ball-bar's own length",
       "reading",
       [](const EffectSpec&) { return 1; },
       [](const EffectSpec&, double, double, const MotionContext*, double* phi) { phi[0] = 1.0; },
       [](const EffectSpec&, int) { return std::string("L"); },
       barCandidates,
       {}},
  };
  return types;
}

}  // namespace

double plausibleCoefficientLimit(const EffectSpec& spec) {
  const bool angular = spec.component >= 3;
  switch (spec.type) {
    case EffectType::Chebyshev:
      return angular ? 1e-3 : 0.5;
    case EffectType::Reversal:
      return angular ? 200e-6 : 0.05;
    case EffectType::Periodic:
      return angular ? 50e-6 : 0.02;
    case EffectType::Harmonics:
      return angular ? 200e-6 : 0.05;
    case EffectType::Drift:
      return angular ? 50e-6 : 0.05;
    case EffectType::Warmup:
      return angular ? 200e-6 : 0.1;
    case EffectType::BarLength:
      return 0.05;
  }
  return INFINITY;
}

int principalComponent(const Axis& a) {
  for (int k = 0; k < 3; ++k)
    if (std::abs(a.direction[k]) == 1.0) return a.isRotary() ? k + 3 : k;
  return -1;
}

const std::vector<EffectTraits>& effectTypes() { return table(); }

const EffectTraits& traitsOf(EffectType type) {
  for (const EffectTraits& t : table())
    if (t.type == type) return t;
  throw std::logic_error("unknown effect type");
}

const EffectTraits* findEffectType(const std::string& name) {
  for (const EffectTraits& t : table())
    if (name == t.name) return &t;
  return nullptr;
}

double* hyperparameter(EffectSpec& spec) {
  if (spec.type == EffectType::Periodic) return &spec.period;
  if (spec.type == EffectType::Warmup) return &spec.tau;
  return nullptr;
}

double hyperparameterValue(const EffectSpec& spec) {
  EffectSpec copy = spec;
  const double* h = hyperparameter(copy);
  return h ? *h : NAN;
}

void updateDirections(MotionContext& ctx, const JointVector& q0, const JointVector& q1) {
  for (int a = 0; a < q1.size(); ++a) {
    const double d = q1[a] - q0[a];
    if (d > 0)
      ctx.direction[a] = 1;
    else if (d < 0)
      ctx.direction[a] = -1;
  }
}

std::string describeEffect(const MachineModel& m, const EffectSpec& e) {
  const EffectTraits& t = traitsOf(e.type);
  std::string out = t.name;
  if (e.axis >= 0) out += " " + m.axes[e.axis].name + " " + kComponentNames[e.component];
  char buf[64];
  switch (e.type) {
    case EffectType::Chebyshev:
    case EffectType::Harmonics:
      std::snprintf(buf, sizeof buf, " (orders %d-%d)", e.first_order, e.last_order);
      out += buf;
      break;
    case EffectType::Reversal:
      if (e.varying) out += " (varying along the axis)";
      break;
    case EffectType::Periodic:
      if (e.period > 0) {
        std::snprintf(buf, sizeof buf, " (period %.3f mm)", e.period);
        out += buf;
      }
      break;
    case EffectType::Warmup:
      if (e.tau > 0) {
        std::snprintf(buf, sizeof buf, " (time constant %.0f s)", e.tau);
        out += buf;
      }
      break;
    default:
      break;
  }
  return out;
}

int MachineModel::addEffect(const EffectSpec& spec) {
  const EffectTraits& t = traitsOf(spec.type);
  ParameterBlock b;
  b.kind = BlockKind::Effect;
  b.axis = spec.axis;
  b.component = spec.component;
  b.effect = static_cast<int>(effects.size());
  b.offset = parameterCount();
  b.size = t.size(spec);
  effects.push_back(spec);
  blocks.push_back(b);
  const int bi = static_cast<int>(blocks.size()) - 1;
  for (int k = 0; k < b.size; ++k) {
    const std::string suffix = t.coefficient(spec, k);
    if (spec.axis < 0) {
      parameters.push_back({"bar." + suffix, "bar." + suffix, false, bi});
      continue;
    }
    const std::string& S = axes[spec.axis].name;
    const int c = spec.component;
    parameters.push_back({std::string(c < 3 ? "e_" : "gamma_") + static_cast<char>('x' + c % 3) +
                              "(" + S + ")." + suffix,
                          std::string("E") + kComponentIsoLetters[c] + S + "." + suffix,
                          isAngularComponent(c), bi});
  }
  return bi;
}

}  // namespace tolver
