// See pipeline/block_predictor.h.
#include "pipeline/block_predictor.h"

#include <algorithm>

#include "pipeline/parallel_prediction.h"

namespace tolver {

void BlockPredictor::predict(const ClProgram& block, bool last, PredictedPoints& out) {
  const MachineModel& model = machine_.model;
  const bool joints = !block.joints.empty();
  const size_t tail = stretch_.size();
  stretch_.insert(stretch_.end(), block.path.begin(), block.path.end());
  if (joints) {
    joints_.resize(tail);  // (a tail without joints: none in a program with them)
    joints_.insert(joints_.end(), block.joints.begin(), block.joints.end());
  } else {
    joints_.clear();
  }
  const size_t n = stretch_.size();
  const size_t e = BlockPrediction::kExactEvery;
  const size_t full = last ? n : n / e * e;
  next_.assign(stretch_.begin() + static_cast<std::ptrdiff_t>(full), stretch_.end());
  stretch_.resize(full);
  next_joints_.clear();
  if (joints) {
    next_joints_.assign(joints_.begin() + static_cast<std::ptrdiff_t>(full), joints_.end());
    joints_.resize(full);
  }
  const size_t base = carry_.points();
  predictToolPathParallel(model, machine_.params, stretch_, committed_, 20,
                          joints ? &joints_ : nullptr, 0, nullptr, &carry_);
  const PredictionSummary& s = committed_.summary;
  if (s.max_index >= 0 && static_cast<size_t>(s.max_index) >= base &&
      static_cast<size_t>(s.max_index) < base + full) {
    worst_ = committed_.points[static_cast<size_t>(s.max_index) - base];
  }
  if (!next_.empty()) {
    PredictionCarry ahead = carry_;
    predictToolPathParallel(model, machine_.params, next_, ahead_, 20,
                            joints ? &next_joints_ : nullptr, 0, nullptr, &ahead);
  }
  // Block point j is stretch point tail + j: the committed stretch's up to full, then the
  // tail's.
  out.resize(block.path.size(), static_cast<int>(model.axes.size()));
  const size_t split = std::max(tail, full);
  if (full > tail) out.copyFrom(committed_.points, tail, full - tail, 0);
  out.copyFrom(ahead_.points, split - full, n - split, split - tail);
  stretch_.swap(next_);
  joints_.swap(next_joints_);
}

}  // namespace tolver
