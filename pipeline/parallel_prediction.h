#pragma once
// predictToolPath on several cores, for long programs: the path in one stretch of blocks per
// thread, all predicted at once (BlockPrediction, core/path/tool_path_prediction.h), every
// stretch but the first from a speculative start that is then checked against the true one and
// run again where it differs. The result is predictToolPath's, bit for bit.
#include <vector>

#include "core/path/tool_path_prediction.h"

namespace tolver {

// threads: at most this many (0: TBB's default, the machine's cores). Programs of fewer than
// a few blocks per thread, commanded joints and models the batch path does not cover go to
// predictToolPath on the calling thread.
PredictionResult predictToolPathParallel(const MachineModel& model, const Eigen::VectorXd& params,
                                         const std::vector<ClPoint>& path, int max_failures = 20,
                                         const std::vector<JointVector>* commanded = nullptr,
                                         int threads = 0);
// How the work was shared: the stretches predicted at once, and the blocks (of
// InverseKinematics::kBlock points) predicted again after a speculative start (one per stretch
// after the first on a smooth path).
struct ParallelPredictionStats {
  int stretches = 1;
  size_t blocks_again = 0;
};
// The same into an existing result, reusing its storage (no allocation, no page faults, when
// it already holds as many points): for batch work over many programs. With a carry, path is
// the next stretch of a longer one (core/path/tool_path_prediction.h, PredictionCarry).
void predictToolPathParallel(const MachineModel& model, const Eigen::VectorXd& params,
                             const std::vector<ClPoint>& path, PredictionResult& result,
                             int max_failures = 20,
                             const std::vector<JointVector>* commanded = nullptr, int threads = 0,
                             ParallelPredictionStats* stats = nullptr,
                             PredictionCarry* carry = nullptr);

}  // namespace tolver
