// Batch's lane step on one lane, a plain double (compiled as the sse2 unit: baseline instruction
// set, -ffp-contract=off; the top-level CMakeLists.txt): for lane groups too small to fill a
// vector block. docs/simd_batch.md, "One-lane blocks".
#include "simd_lane_step.hpp"

namespace featherdrive::simd {

void run_block_one(const Plan& p, const Block& b, double* scratch, int steps) {
  LaneStep<One, 1>(p, b, scratch).run(steps);
}

}  // namespace featherdrive::simd
