// The instruction sets Batch's SIMD lanes are compiled for, chosen at run time.
// docs/simd_batch.md.
#pragma once

#include <string>
#include <vector>

namespace featherdrive {

/// The instruction sets the lane step is compiled for, narrowest first.
enum class SimdIsa { sse2, avx2, avx512 };
const char* to_string(SimdIsa isa);
/// Lanes (doubles) of one vector of the instruction set: 2, 4, 8.
int simd_width(SimdIsa isa);
/// The widest one this CPU runs, or the environment variable FEATHERDRIVE_SIMD (sse2, avx2,
/// avx512) where it names one the CPU has (scalar: sse2, the narrowest; one: sse2, and Batch
/// steps every lane group in one-lane blocks); throws std::invalid_argument naming the value
/// otherwise.
SimdIsa default_simd_isa();
/// FEATHERDRIVE_SIMD=scalar: Batch steps every environment as a Simulation, without lanes.
bool simd_forced_scalar();
/// The instruction sets this CPU runs, narrowest first.
std::vector<SimdIsa> available_simd_isas();
/// Throws std::invalid_argument ("<where> = avx512: this CPU has only up to avx2") unless this
/// CPU runs `isa`.
void check_simd_isa(SimdIsa isa, const std::string& where);

}  // namespace featherdrive
