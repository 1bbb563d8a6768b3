// Batch's lane step for sse2 (compiled with its instruction set and -ffp-contract=off:
// the top-level CMakeLists.txt). docs/simd_batch.md.
#include "simd_lane_step.hpp"

namespace featherdrive::simd {

void run_block_sse2(const Plan& p, const Block& b, double* scratch, int steps) {
  LaneStep<xsimd::sse2, 2>(p, b, scratch).run(steps);  // simd::interleave: always 2
}

}  // namespace featherdrive::simd
