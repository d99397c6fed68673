#pragma once
// Effects: error terms beyond the base model (link errors and Chebyshev motion errors) that a
// diagnosis adds to a machine when its residuals show them (backlash, cyclic error, rotary
// harmonics, thermal drift, ...). Each is a parameter block of the flat vector (BlockKind::Effect)
// and is understood by the forward model, the sensitivity Jacobian, identification, predict and
// verify.
//
// An axis effect adds to one motion-error component c (ex ey ez gx gy gz) of one axis S:
//   e_c,S(s) += sum_k p_k phi_k(s, x, context),
// with s the joint value (mm, rad), x its normalised coordinate (eq. 58) and the configuration's
// context (approach direction, time). Coefficients p_k are in mm (ex, ey, ez) or rad (gx, gy,
// gz). The instrument effect (ball-bar length) has no axis: it adds p_0 to every reading.
//
// Basis functions, per type:
//   chebyshev  T_k(x), k = first_order..last_order (a higher degree than the base model's);
//   reversal   d/2 and, when `varying`, d x / 2, with d = +1/-1 the approach direction of the
//              axis (0 when unknown): p_0 is the reversal value (backlash), p_1 its change
//              from the middle to the end of travel;
//   periodic   sin(2 pi s / period), cos(2 pi s / period) (period in mm, found by search);
//   harmonics  cos(k s), sin(k s) for k = first_order..last_order (a rotary axis);
//   drift      t / 3600 (t in s since the test began; p_0 per hour);
//   warmup     1 - exp(-t / tau) (tau in s, found by search; p_0 the settled drift);
//   bar_length 1 (added to the reading, not to the machine).
// A time-dependent effect contributes nothing when the time is unknown (NaN).
//
// Adding a type: one entry in the table of effects.cpp (size, basis, names, candidates, search
// range of its hyperparameter); nothing else changes.
#include <string>
#include <vector>

#include "core/model/machine_model.h"

namespace tolver {

// The candidate effects of a type on a model (one EffectSpec each, hyperparameter unset).
using EffectCandidates = std::vector<EffectSpec> (*)(const MachineModel&);

// A hyperparameter found by search (the period of a cyclic error, a thermal time constant).
struct HyperparameterRange {
  const char* name = nullptr;  // "period_mm", "tau_s"; nullptr: the type has none
  double min = 0, max = 0;
  bool frequency_grid = false;  // search uniformly in 1 / value (periods) rather than log value
};

struct EffectTraits {
  EffectType type;
  const char* name;         // as in machine files and reports: "reversal"
  const char* description;  // one line, for reports
  const char*
      variable;  // what the effect follows: "position", "direction", "angle", "time", "reading"
  int (*size)(const EffectSpec&);
  // phi: size() values.
  void (*basis)(const EffectSpec&, double s, double x, const MotionContext* ctx, double* phi);
  std::string (*coefficient)(const EffectSpec&, int k);  // suffix of the k-th coefficient's name
  EffectCandidates candidates;
  HyperparameterRange hyper;
};

const std::vector<EffectTraits>& effectTypes();
const EffectTraits& traitsOf(EffectType type);
// nullptr when unknown.
const EffectTraits* findEffectType(const std::string& name);

// The hyperparameter of a spec (period or tau), by reference; nullptr when the type has none.
double* hyperparameter(EffectSpec& spec);
double hyperparameterValue(const EffectSpec& spec);

// Updates the approach directions of ctx for a move from q0 to q1 (an axis that does not move
// keeps its direction), as a control would see them.
void updateDirections(MotionContext& ctx, const JointVector& q0, const JointVector& q1);

// The motion-error component along an axis's own motion (ex of an X axis, gz of a C axis), -1
// when its direction is not a coordinate axis.
int principalComponent(const Axis& a);

// The largest magnitude a coefficient of the effect can plausibly have on a machine tool (mm or
// rad; drift: per hour), beyond which a fitted value says the effect is standing in for
// something else (docs/diagnosis.md, "Plausible effects"): reversal 50 um / 200 urad, cyclic
// error 20 um / 50 urad, rotary harmonics 50 um / 200 urad, drift 50 um/h / 50 urad/h,
// warm-up 100 um / 200 urad, bar length 50 um, a higher Chebyshev degree 0.5 mm / 1 mrad.
double plausibleCoefficientLimit(const EffectSpec& spec);

// "reversal X ex", "periodic X ex (period 10.000 mm)", "bar_length".
std::string describeEffect(const MachineModel& model, const EffectSpec& spec);

}  // namespace tolver
