// Batch's lane step for avx2 (compiled with its instruction set and -ffp-contract=off:
// the top-level CMakeLists.txt). docs/simd_batch.md.
#include "simd_lane_step.hpp"

namespace featherdrive::simd {

void run_block_avx2(const Plan& p, const Block& b, double* scratch, int steps) {
  if (b.interleave == 4)
    LaneStep<xsimd::avx2, 4>(p, b, scratch).run(steps);
  else
    LaneStep<xsimd::avx2, 2>(p, b, scratch).run(steps);
}

}  // namespace featherdrive::simd
