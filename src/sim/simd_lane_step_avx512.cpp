// Batch's lane step for avx512 (compiled with its instruction set and -ffp-contract=off:
// the top-level CMakeLists.txt). docs/simd_batch.md.
#include "simd_lane_step.hpp"

namespace featherdrive::simd {

void run_block_avx512(const Plan& p, const Block& b, double* scratch, int steps) {
  LaneStep<xsimd::avx512f, 2>(p, b, scratch).run(steps);  // simd::interleave: always 2
}

}  // namespace featherdrive::simd
