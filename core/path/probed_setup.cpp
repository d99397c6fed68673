#include "core/path/probed_setup.h"

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <stdexcept>

#include "core/kinematics/forward_kinematics.h"
#include "core/kinematics/sensitivity_jacobian.h"

namespace tolver {
namespace {

int rowsOf(const ProbedPoint& p) { return p.tram ? 2 : p.n_w.isZero() ? 3 : 1; }

// The machine with its part set-up taken out (w = the table frame), for trams.
Machine withoutPartSetup(const Machine& machine) {
  Machine m = machine;
  m.model.setup.part_zero_table.setZero();
  m.model.setup.part_rotation = 0.0;
  for (const ParameterBlock& b : m.model.blocks)
    if (b.kind == BlockKind::WorkpieceSetup) m.params.segment(b.offset, b.size).setZero();
  return m;
}

// The tool axis's x and y in w of a machine whose part set-up is already taken out.
Eigen::Vector2d tiltInTable(const Machine& table, const JointVector& q) {
  const ForwardKinematics fk(table.model, table.params);
  return fk.w_T_t(q).linear().col(2).head<2>();
}

// A tram's rows (the model's tilt minus the measured, times kTramLever) and, when J is given,
// their derivatives for columns by central differences (the parameters enter the axis through
// whole rotations; a step of 1e-6 mm or rad leaves errors far below a microradian).
void tramRows(const Machine& machine, const ProbedPoint& p, const std::vector<int>& columns,
              Eigen::Ref<Eigen::VectorXd> r, Eigen::MatrixXd* J, int row) {
  Machine table = withoutPartSetup(machine);
  r = kTramLever * (tiltInTable(table, p.q) - p.tilt);
  if (!J) return;
  constexpr double h = 1e-6;
  for (size_t k = 0; k < columns.size(); ++k) {
    double& v = table.params[columns[k]];
    const double v0 = v;
    v = v0 + h;
    const Eigen::Vector2d plus = tiltInTable(table, p.q);
    v = v0 - h;
    const Eigen::Vector2d minus = tiltInTable(table, p.q);
    v = v0;
    J->block<2, 1>(row, k) = kTramLever * (plus - minus) / (2 * h);
  }
}

// The probe's machine (its tip at the probe length) per distinct length, bound to params.
class ProbeKinematics {
 public:
  explicit ProbeKinematics(const Machine& machine) : machine_(machine) {}
  const ForwardKinematics& at(double length) {
    auto it = fk_.find(length);
    if (it == fk_.end()) {
      auto m = std::make_unique<MachineModel>(machine_.model);
      m->setup.gauge_length = length;
      auto fk = std::make_unique<ForwardKinematics>(*m, machine_.params);
      models_.push_back(std::move(m));
      it = fk_.emplace(length, std::move(fk)).first;
    }
    return *it->second;
  }

 private:
  const Machine& machine_;
  std::vector<std::unique_ptr<MachineModel>> models_;
  std::map<double, std::unique_ptr<ForwardKinematics>> fk_;
};

// Residuals (tip - nominal, along n or in full) and, when J is given, their rows for columns.
void evaluate(const Machine& machine, const std::vector<ProbedPoint>& points,
              const std::vector<int>& columns, Eigen::VectorXd* r, Eigen::MatrixXd* J) {
  int m = 0;
  for (const ProbedPoint& p : points) m += rowsOf(p);
  if (r) r->resize(m);
  if (J) J->resize(m, columns.size());
  ProbeKinematics kin(machine);
  Eigen::MatrixXd Jt(6, machine.model.parameterCount());
  int row = 0;
  for (const ProbedPoint& p : points) {
    if (p.tram) {
      Eigen::Vector2d rt;
      tramRows(machine, p, columns, rt, J, row);
      if (r) r->segment<2>(row) = rt;
      row += 2;
      continue;
    }
    const ForwardKinematics& fk = kin.at(p.probe_length);
    const Eigen::Isometry3d T = fk.w_T_t(p.q);
    const Eigen::Vector3d d = T.translation() - p.p_w;
    Eigen::MatrixXd cols;
    if (J) {
      Jt.setZero();
      sensitivityJacobian(fk, p.q, Jt);
      cols.resize(3, columns.size());
      for (size_t k = 0; k < columns.size(); ++k)
        cols.col(k) = T.linear() * Jt.block<3, 1>(0, columns[k]);
    }
    if (p.n_w.isZero()) {
      if (r) r->segment<3>(row) = d;
      if (J) J->middleRows(row, 3) = cols;
      row += 3;
    } else {
      if (r) (*r)[row] = p.n_w.dot(d);
      if (J) J->row(row) = p.n_w.transpose() * cols;
      row += 1;
    }
  }
}

std::vector<double> perPoint(const std::vector<ProbedPoint>& points, const Eigen::VectorXd& r) {
  std::vector<double> out;
  int row = 0;
  for (const ProbedPoint& p : points) {
    const int k = rowsOf(p);
    out.push_back(p.tram   ? r.segment<2>(row).norm() / kTramLever
                  : k == 3 ? r.segment<3>(row).norm()
                           : std::abs(r[row]));
    row += k;
  }
  return out;
}

// The touches' RMS and largest residual (mm) and the trams' largest disagreement (rad).
void summarise(const std::vector<ProbedPoint>& points, const Eigen::VectorXd& r, double* rms,
               double* max, double* tram_max) {
  const std::vector<double> each = perPoint(points, r);
  double ss = 0, mx = 0, tm = 0;
  int touches = 0;
  for (size_t i = 0; i < points.size(); ++i)
    if (points[i].tram) {
      tm = std::max(tm, each[i]);
    } else {
      ss += each[i] * each[i];
      mx = std::max(mx, each[i]);
      ++touches;
    }
  if (rms) *rms = touches ? std::sqrt(ss / touches) : 0.0;
  if (max) *max = mx;
  if (tram_max) *tram_max = tm;
}

}  // namespace

Eigen::Vector2d tramTilt(const Machine& machine, const JointVector& q) {
  return tiltInTable(withoutPartSetup(machine), q);
}

ProbedPoint simulatedTram(const Machine& machine, const JointVector& q, int line) {
  ProbedPoint p;
  p.tram = true;
  p.line = line;
  p.q = q;
  p.tilt = tramTilt(machine, q);
  return p;
}

bool hasTram(const std::vector<ProbedPoint>& points) {
  return std::any_of(points.begin(), points.end(), [](const ProbedPoint& p) { return p.tram; });
}

std::vector<int> probedSetupColumns(const MachineModel& model, Eigen::VectorXd* scale,
                                    bool with_tram) {
  std::vector<int> cols;
  std::vector<double> sc;
  for (const ParameterBlock& b : model.blocks)
    if (b.kind == BlockKind::WorkpieceSetup)
      for (int c = 0; c < 6; ++c) {
        cols.push_back(b.offset + c);
        sc.push_back(c < 3 ? 1.0 : 100.0);
      }
  if (cols.empty()) return cols;
  for (const ParameterBlock& b : model.blocks)
    if (b.kind == BlockKind::ToolSetup)
      for (int c = 0; c < 3; ++c) {
        cols.push_back(b.offset + c);
        sc.push_back(1000.0);
      }
  if (with_tram)
    for (const ParameterBlock& b : model.blocks)
      if (b.kind == BlockKind::ToolSetup)
        for (int c = 3; c < 5; ++c) {
          cols.push_back(b.offset + c);
          sc.push_back(100.0);
        }
  if (scale) *scale = Eigen::Map<const Eigen::VectorXd>(sc.data(), sc.size());
  return cols;
}

void probedRows(const Machine& machine, const std::vector<ProbedPoint>& points,
                const std::vector<int>& columns, Eigen::MatrixXd* rows) {
  evaluate(machine, points, columns, nullptr, rows);
}

ProbedSetupFit fitProbedSetup(Machine& machine, const std::vector<ProbedPoint>& points) {
  Eigen::VectorXd scale;
  const std::vector<int> cols = probedSetupColumns(machine.model, &scale, hasTram(points));
  if (cols.empty())
    throw std::invalid_argument("fitProbedSetup: the machine has no part set-up block");
  if (points.empty()) throw std::invalid_argument("fitProbedSetup: no probed point");
  const int n = static_cast<int>(cols.size());
  ProbedSetupFit fit;
  fit.columns = n;
  Eigen::VectorXd r;
  Eigen::MatrixXd J;
  evaluate(machine, points, cols, &r, &J);
  summarise(points, r, &fit.rms_before, nullptr, &fit.tram_before);
  // Which set-up directions the touches constrain: the rank of the column-scaled rows.
  Eigen::MatrixXd Js = J * scale.cwiseInverse().asDiagonal();
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(Js, Eigen::ComputeThinU | Eigen::ComputeThinV);
  svd.setThreshold(1e-6);
  fit.observed = static_cast<int>(svd.rank());
  if (fit.observed < n) {
    static const char* names[11] = {"x",
                                    "y",
                                    "z",
                                    "rotation about x",
                                    "rotation about y",
                                    "rotation about z",
                                    "spindle offset x (touch at other table orientations)",
                                    "spindle offset y (touch at other table orientations)",
                                    "spindle offset z (touch at other table orientations)",
                                    "spindle tilt about x (tram at other positions)",
                                    "spindle tilt about y (tram at other positions)"};
    // A set-up value is unobserved when its unit vector lies (mostly) in the null space.
    const Eigen::MatrixXd N = svd.matrixV().rightCols(n - fit.observed);
    for (int c = 0; c < n; ++c)
      if (N.row(c).norm() > 0.5) fit.unobserved.push_back(names[c]);
  }
  for (int it = 0; it < 30; ++it) {
    fit.iterations = it + 1;
    // Minimum-norm step in the scaled space: the directions the touches do not constrain stay
    // where the machine file put them.
    const Eigen::VectorXd step = svd.solve(-r).cwiseQuotient(scale);
    for (int c = 0; c < n; ++c) machine.params[cols[c]] += step[c];
    fit.change += step.head<6>();
    if (n >= 9) fit.spindle_change += step.segment<3>(6);
    if (n == 11) fit.spindle_tilt_change += step.tail<2>();
    evaluate(machine, points, cols, &r, &J);
    if (step.cwiseProduct(scale).norm() < 1e-10) break;
    Js = J * scale.cwiseInverse().asDiagonal();
    svd.compute(Js, Eigen::ComputeThinU | Eigen::ComputeThinV);
  }
  fit.residual = perPoint(points, r);
  summarise(points, r, &fit.rms, &fit.max, &fit.tram_max);
  fit.trams = static_cast<int>(
      std::count_if(points.begin(), points.end(), [](const ProbedPoint& p) { return p.tram; }));
  return fit;
}

}  // namespace tolver
