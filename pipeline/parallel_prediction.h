#pragma once
// predictToolPath on several cores, for long programs: BlockPrediction's stages
// (core/path/tool_path_prediction.h) in a TBB pipeline; the IK lane stage and the forward
// stage of different blocks run at once, the continuity choice and the bookkeeping block after
// block. The result is predictToolPath's, bit for bit.
#include <vector>

#include "core/path/tool_path_prediction.h"

namespace tolver {

// threads: at most this many (0: TBB's default, the machine's cores). Programs of fewer than
// a few blocks, commanded joints and models the batch path does not cover go to
// predictToolPath on the calling thread.
PredictionResult predictToolPathParallel(const MachineModel& model, const Eigen::VectorXd& params,
                                         const std::vector<ClPoint>& path, int max_failures = 20,
                                         const std::vector<JointVector>* commanded = nullptr,
                                         int threads = 0);

}  // namespace tolver
