#pragma once
// A program's points predicted block by block (a program read in blocks, io/program/apt_reader.h
// ProgramBlocks), each block's bits those of the whole program predicted at once.
#include "core/path/tool_path_prediction.h"
#include "pipeline/inputs.h"

namespace tolver {

// The points of a program read in blocks, each block's with the bits of the whole program
// predicted at once (PredictionCarry): a block's points are predicted up to the last multiple of
// BlockPrediction::kExactEvery with the program's carry, and the rest (the tail) with a copy of
// it, to be written with the block; the tail is predicted again, the same bits, at the start of
// the next block's stretch. So at most kExactEvery - 1 points a block are predicted twice.
class BlockPredictor {
 public:
  explicit BlockPredictor(const Machine& machine) : machine_(machine) {}

  // The block's points (with its commanded joints, G-code) into `out`, one per block point.
  void predict(const ClProgram& block, bool last, PredictedPoints& out);

  // After the last block: the program's failures and summary, and its worst point.
  const PredictionResult& result() const { return committed_; }
  PredictionResult takeResult() {  // the failures and summary, without the last stretch's points
    PredictionResult r;
    r.failures = std::move(committed_.failures);
    r.failed_points = committed_.failed_points;
    r.failures_per_axis = std::move(committed_.failures_per_axis);
    r.summary = committed_.summary;
    return r;
  }
  const PredictedPoint& worst() const { return worst_; }

 private:
  const Machine& machine_;
  PredictionCarry carry_;
  std::vector<ClPoint> stretch_, next_;  // between blocks: the tail
  std::vector<JointVector> joints_, next_joints_;
  PredictionResult committed_, ahead_;
  PredictedPoint worst_;  // the point of the summary's max_index
};

}  // namespace tolver
