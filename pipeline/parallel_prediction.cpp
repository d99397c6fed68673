#include "pipeline/parallel_prediction.h"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <memory>

namespace tolver {

PredictionResult predictToolPathParallel(const MachineModel& model, const Eigen::VectorXd& params,
                                         const std::vector<ClPoint>& path, int max_failures,
                                         const std::vector<JointVector>* commanded, int threads) {
  PredictionResult result;
  predictToolPathParallel(model, params, path, result, max_failures, commanded, threads);
  return result;
}

void predictToolPathParallel(const MachineModel& model, const Eigen::VectorXd& params,
                             const std::vector<ClPoint>& path, PredictionResult& result,
                             int max_failures, const std::vector<JointVector>* commanded,
                             int threads, ParallelPredictionStats* stats, PredictionCarry* carry) {
  ParallelPredictionStats own;
  ParallelPredictionStats& st = stats ? *stats : own;
  st = ParallelPredictionStats{};
  tbb::task_arena arena(threads > 0 ? threads : tbb::task_arena::automatic);
  // Stretches start on points solved with exact angles: whole numbers of kUnit blocks.
  constexpr size_t kUnit = BlockPrediction::kExactEvery / InverseKinematics::kBlock;
  const size_t blocks = (path.size() + InverseKinematics::kBlock - 1) / InverseKinematics::kBlock;
  const size_t stretches =
      std::min<size_t>(static_cast<size_t>(arena.max_concurrency()), blocks / kUnit);
  if (commanded || stretches < 2) {
    predictToolPath(model, params, path, result, max_failures, commanded, true, carry);
    return;
  }
  BlockPrediction bp(model, params, path, result, max_failures, carry);
  if (!bp.batchable()) {
    predictToolPath(model, params, path, result, max_failures, nullptr, true, carry);
    return;
  }
  using Cursor = BlockPrediction::Cursor;
  // The path in consecutive stretches of blocks, one per thread, all at once: the first with
  // the prediction's cursor, each other speculatively from an empty cursor (its first point
  // solved as at the start of a path, with exact angles), keeping its cursor after each of its
  // first kProbe blocks. Then, stretch after stretch, the true cursor at its start is the one
  // the stretch before ended with: its blocks are run again with it until it agrees with the
  // speculative one; on a smooth path that is after the first block, where both took the same
  // candidate. Where the two never agree within kProbe blocks (the speculation on the other
  // candidate: a tool axis both candidates reach), the rest of the stretch is run again: the
  // result is predictToolPath's, bit for bit, in any case.
  constexpr size_t kProbe = 8;
  st.stretches = static_cast<int>(stretches);
  std::vector<size_t> begin(stretches + 1);
  const size_t units = blocks / kUnit;
  for (size_t c = 0; c < stretches; ++c) begin[c] = units * c / stretches * kUnit;
  begin[stretches] = blocks;
  // Each speculative stretch's cursor after its last block (the first stretch's is
  // bp.cursor()).
  std::vector<Cursor> last(stretches);
  std::vector<std::vector<Cursor>> probes(stretches);
  arena.execute([&] {
    tbb::parallel_for(size_t{0}, stretches, [&](size_t c) {
      const std::shared_ptr<BlockPrediction::Work> w = bp.newWork();
      Cursor& cursor = c == 0 ? bp.cursor() : last[c];
      for (size_t k = begin[c]; k < begin[c + 1]; ++k) {
        bp.predict(k, *w, cursor);
        if (c > 0 && k - begin[c] < kProbe) probes[c].push_back(cursor);
      }
    });
  });
  const std::shared_ptr<BlockPrediction::Work> w = bp.newWork();
  Cursor& cursor = bp.cursor();  // the true cursor, at the end of the stretches settled so far
  const Cursor empty{};
  for (size_t c = 1; c < stretches; ++c) {
    size_t k = begin[c];
    for (; k < begin[c + 1]; ++k) {
      const size_t done = k - begin[c];  // blocks of this stretch already run again
      if (done <= kProbe && bp.sameCursor(cursor, done == 0 ? empty : probes[c][done - 1])) break;
      bp.predict(k, *w, cursor);
      ++st.blocks_again;
    }
    if (k < begin[c + 1]) cursor = last[c];  // agreed: the speculative end is the true one
  }
  bp.finish();
}

}  // namespace tolver
