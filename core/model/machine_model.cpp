#include "core/model/machine_model.h"

#include <cctype>

namespace tolver {
namespace {

bool equalsIgnoreCase(std::string_view a, std::string_view b) {
  if (a.size() != b.size()) return false;
  for (size_t i = 0; i < a.size(); ++i) {
    if (std::toupper(static_cast<unsigned char>(a[i])) !=
        std::toupper(static_cast<unsigned char>(b[i])))
      return false;
  }
  return true;
}

std::string thesisLetter(int c) {
  return std::string(c < 3 ? "e_" : "gamma_") + static_cast<char>('x' + c % 3);
}

}  // namespace

void MachineModel::buildParameterLayout(const std::vector<std::array<int, 6>>& motion_degree) {
  blocks.clear();
  effects.clear();
  parameters.clear();
  auto addBlock = [&](ParameterBlock b) {
    b.offset = parameterCount();
    blocks.push_back(b);
    return static_cast<int>(blocks.size()) - 1;
  };
  for (int a = 0; a < static_cast<int>(axes.size()); ++a) {
    const std::string& S = axes[a].name;
    const int bi = addBlock({BlockKind::LinkError, a, -1, 0, 0, 6});
    for (int c = 0; c < 6; ++c) {
      parameters.push_back({thesisLetter(c) + "," + S,
                            std::string(1, kComponentIsoLetters[c]) + "O" + S,
                            isAngularComponent(c), bi});
    }
  }
  for (int a = 0; a < static_cast<int>(axes.size()); ++a) {
    const std::string& S = axes[a].name;
    for (int c = 0; c < 6; ++c) {
      const int d = motion_degree.at(a)[c];
      if (d < 0) continue;
      const int bi = addBlock({BlockKind::MotionError, a, c, d, 0, d + 1});
      for (int k = 0; k <= d; ++k) {
        parameters.push_back(
            {thesisLetter(c) + "(" + S + ").c" + std::to_string(k),
             std::string("E") + kComponentIsoLetters[c] + S + ".c" + std::to_string(k),
             isAngularComponent(c), bi});
      }
    }
  }
  const char* frames[2] = {"w", "t"};
  const char* codes[2] = {"part.", "tool."};
  for (int f = 0; f < 2; ++f) {
    const int bi =
        addBlock({f == 0 ? BlockKind::WorkpieceSetup : BlockKind::ToolSetup, -1, -1, 0, 0, 6});
    for (int c = 0; c < 6; ++c) {
      parameters.push_back({thesisLetter(c) + "," + frames[f],
                            std::string(codes[f]) + kComponentIsoLetters[c], isAngularComponent(c),
                            bi});
    }
  }
}

int MachineModel::axisIndex(std::string_view axis_name) const {
  for (int a = 0; a < static_cast<int>(axes.size()); ++a)
    if (equalsIgnoreCase(axes[a].name, axis_name)) return a;
  return -1;
}

int MachineModel::findParameter(std::string_view n) const {
  for (int i = 0; i < parameterCount(); ++i)
    if (parameters[i].thesis_name == n || parameters[i].iso_code == n) return i;
  for (const ParameterAlias& a : aliases)
    if (a.name == n) return a.parameter;
  return -1;
}

int MachineModel::motionBlock(int axis, int component) const {
  for (int b = 0; b < static_cast<int>(blocks.size()); ++b)
    if (blocks[b].kind == BlockKind::MotionError && blocks[b].axis == axis &&
        blocks[b].component == component)
      return b;
  return -1;
}

Eigen::Isometry3d MachineModel::table_T_w() const {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = setup.part_zero_table;
  T.linear() = Eigen::AngleAxisd(setup.part_rotation, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  return T;
}

Eigen::Isometry3d MachineModel::spindle_T_t() const {
  return translation(Eigen::Vector3d::UnitZ(), -setup.gauge_length);
}

}  // namespace tolver

namespace tolver {

std::array<int, 3> prismaticWordOrder(const MachineModel& model) {
  std::array<int, 3> order = {-1, -1, -1};
  std::vector<int> prismatic;
  for (size_t a = 0; a < model.axes.size(); ++a)
    if (!model.axes[a].isRotary()) prismatic.push_back(static_cast<int>(a));
  if (prismatic.size() != 3) return order;
  std::array<int, 3> by_name = {-1, -1, -1};
  for (int a : prismatic) {
    const std::string& n = model.axes[a].name;
    if (n.size() == 1 && (n[0] == 'X' || n[0] == 'Y' || n[0] == 'Z')) by_name[n[0] - 'X'] = a;
  }
  if (by_name[0] >= 0 && by_name[1] >= 0 && by_name[2] >= 0) return by_name;
  for (int k = 0; k < 3; ++k) order[k] = prismatic[k];
  return order;
}

}  // namespace tolver
