#include "pipeline/parallel_prediction.h"

#include <tbb/parallel_pipeline.h>
#include <tbb/task_arena.h>

#include <memory>

namespace tolver {

PredictionResult predictToolPathParallel(const MachineModel& model, const Eigen::VectorXd& params,
                                         const std::vector<ClPoint>& path, int max_failures,
                                         const std::vector<JointVector>* commanded, int threads) {
  PredictionResult result;
  constexpr size_t kMinBlocks = 8;  // below, the pipeline's overhead is not worth it
  if (commanded || path.size() < kMinBlocks * InverseKinematics::kBlock) {
    predictToolPath(model, params, path, result, max_failures, commanded, true);
    return result;
  }
  BlockPrediction bp(model, params, path, result, max_failures);
  if (!bp.batchable()) {
    predictToolPath(model, params, path, result, max_failures, nullptr, true);
    return result;
  }
  tbb::task_arena arena(threads > 0 ? threads : tbb::task_arena::automatic);
  const int concurrency = arena.max_concurrency();
  // Tokens in flight; block k uses work slot k % tokens, free by then: the last filter runs
  // in order, so when block k enters, block k - tokens has left.
  const size_t tokens = static_cast<size_t>(2 * concurrency + 2);
  std::vector<std::shared_ptr<BlockPrediction::Work>> work;
  for (size_t k = 0; k < tokens; ++k) work.push_back(bp.newWork());
  const size_t blocks = bp.blocks();
  struct Token {
    size_t block;
    BlockPrediction::Work* w;
  };
  size_t next = 0;
  arena.execute([&] {
    tbb::parallel_pipeline(
        tokens,
        tbb::make_filter<void, Token>(tbb::filter_mode::serial_in_order,
                                      [&](tbb::flow_control& fc) -> Token {
                                        if (next == blocks) {
                                          fc.stop();
                                          return {};
                                        }
                                        const size_t k = next++;
                                        return {k, work[k % tokens].get()};
                                      }) &
            tbb::make_filter<Token, Token>(tbb::filter_mode::parallel,
                                           [&](Token t) {
                                             bp.lanes(t.block, *t.w);
                                             return t;
                                           }) &
            tbb::make_filter<Token, Token>(tbb::filter_mode::serial_in_order,
                                           [&](Token t) {
                                             bp.choice(*t.w);
                                             return t;
                                           }) &
            tbb::make_filter<Token, Token>(tbb::filter_mode::parallel,
                                           [&](Token t) {
                                             bp.forward(*t.w);
                                             return t;
                                           }) &
            tbb::make_filter<Token, void>(tbb::filter_mode::serial_in_order,
                                          [&](Token t) { bp.account(*t.w); }));
  });
  bp.finish();
  return result;
}

}  // namespace tolver
