#include "core/calibration/ballbar.h"

#include "core/kinematics/sensitivity_jacobian.h"

namespace tolver {

double ballbarLength(const ForwardKinematics& fk, const JointVector& q, const BallbarSetup& s,
                     const BallErrors& e, const MotionContext* ctx) {
  const Eigen::Isometry3d T = fk.w_T_t(q, ctx);
  return (T * (s.tool_ball_t + e.tool_t) - (s.table_ball_w + e.table_w)).norm() +
         fk.barLengthError();
}

Eigen::VectorXd ballbarResiduals(const ForwardKinematics& fk, const BallbarTest& test,
                                 const std::vector<BallErrors>& balls) {
  Eigen::VectorXd r(test.readings.size());
  for (size_t i = 0; i < test.readings.size(); ++i) {
    const BallbarReading& b = test.readings[i];
    r[i] = b.length - ballbarLength(fk, b.q, test.setups[b.setup], balls[b.setup], &b.context);
  }
  return r;
}

ResidualStats residualStats(const Eigen::VectorXd& r) {
  ResidualStats s;
  s.readings = static_cast<int>(r.size());
  if (r.size() == 0) return s;
  s.rms = std::sqrt(r.squaredNorm() / static_cast<double>(r.size()));
  s.max = r.cwiseAbs().maxCoeff();
  return s;
}

namespace {

// Reading change per tool twist in t: n^T R_wt [I, -[b_t x]] (see the header); *length: the
// ball-to-ball distance (as ballbarLength).
Eigen::Matrix<double, 1, 6> readingPerTwist(const ForwardKinematics& fk, const JointVector& q,
                                            const BallbarSetup& s, const BallErrors& e,
                                            const MotionContext* ctx, Eigen::Vector3d* n_w,
                                            Eigen::RowVector3d* nR_t, double* length = nullptr) {
  const Eigen::Isometry3d T = fk.w_T_t(q, ctx);
  const Eigen::Vector3d bt = s.tool_ball_t + e.tool_t;
  const Eigen::Vector3d d = T * bt - (s.table_ball_w + e.table_w);
  if (length) *length = d.norm() + fk.barLengthError();
  *n_w = d.normalized();
  *nR_t = n_w->transpose() * T.linear();  // bar direction in t
  Eigen::Matrix<double, 3, 6> P;
  P.leftCols<3>().setIdentity();
  P.rightCols<3>() << 0, bt.z(), -bt.y(), -bt.z(), 0, bt.x(), bt.y(), -bt.x(), 0;
  return *nR_t * P;
}

}  // namespace

void ballbarComponentGradient(const ForwardKinematics& fk, const JointVector& q,
                              const BallbarSetup& s, const BallErrors& e,
                              Eigen::Ref<Eigen::RowVectorXd> J_length_components,
                              Eigen::MatrixXd& scratch, const MotionContext* ctx) {
  Eigen::Vector3d n;
  Eigen::RowVector3d nR;
  const Eigen::Matrix<double, 1, 6> w = readingPerTwist(fk, q, s, e, ctx, &n, &nR);
  scratch.resize(6, 6 * fk.model().axes.size());
  componentSensitivities(fk, q, scratch, ctx);
  J_length_components = w * scratch;
}

double ballbarGradient(const ForwardKinematics& fk, const JointVector& q, const BallbarSetup& s,
                       const BallErrors& e, Eigen::Ref<Eigen::RowVectorXd> J_params,
                       Eigen::RowVector3d* J_table, Eigen::RowVector3d* J_tool,
                       const MotionContext* ctx) {
  Eigen::Vector3d n;
  Eigen::RowVector3d nR;
  double length = 0.0;
  const Eigen::Matrix<double, 1, 6> w = readingPerTwist(fk, q, s, e, ctx, &n, &nR, &length);
  sensitivityRow(fk, q, w, J_params, ctx);
  const MachineModel& m = fk.model();
  for (const ParameterBlock& b : m.blocks)  // the instrument's length adds to the reading
    if (b.kind == BlockKind::Effect && m.effects[b.effect].axis < 0) J_params[b.offset] = 1.0;
  if (J_tool) *J_tool = nR;
  if (J_table) *J_table = -n.transpose();
  return length;
}

Eigen::MatrixXd identificationJacobian(const ForwardKinematics& fk, const BallbarTest& test,
                                       const std::vector<BallErrors>& balls,
                                       const std::vector<int>& unknowns,
                                       Eigen::VectorXd* residuals) {
  const int np = static_cast<int>(unknowns.size());
  const int n = np + 6 * static_cast<int>(test.setups.size());
  const int pc = fk.model().parameterCount();
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(test.readings.size(), n);
  if (residuals) residuals->resize(test.readings.size());
  Eigen::RowVectorXd row(pc);
  for (size_t i = 0; i < test.readings.size(); ++i) {
    const BallbarReading& rd = test.readings[i];
    const BallbarSetup& s = test.setups[rd.setup];
    Eigen::RowVector3d jt, jb;
    const double length = ballbarGradient(fk, rd.q, s, balls[rd.setup], row, &jt, &jb, &rd.context);
    for (int k = 0; k < np; ++k) J(i, k) = row[unknowns[k]];
    J.block<1, 3>(i, np + 6 * rd.setup) = jt;
    J.block<1, 3>(i, np + 6 * rd.setup + 3) = jb;
    if (residuals) (*residuals)[i] = rd.length - length;
  }
  return J;
}

void deriveDirections(BallbarTest& test) {
  for (size_t i = 0; i < test.readings.size(); ++i) {
    BallbarReading& r = test.readings[i];
    for (int a = 0; a < r.q.size(); ++a) {
      if (r.context.direction[a] != 0) continue;
      if (i == 0) continue;
      const BallbarReading& p = test.readings[i - 1];
      const double dq = r.q[a] - p.q[a];
      r.context.direction[a] = dq > 0 ? 1 : (dq < 0 ? -1 : p.context.direction[a]);
    }
  }
}

}  // namespace tolver
