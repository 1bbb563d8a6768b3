// The instruction sets of Batch's SIMD lanes: which this CPU runs, and FEATHERDRIVE_SIMD.
// docs/simd_batch.md.
#include "featherdrive/sim/simd_isa.hpp"

#include <xsimd/config/xsimd_arch.hpp>

#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <string>

namespace featherdrive {
namespace {

// Without a vector or a string: default_simd_isa runs at every Batch::step, which allocates
// nothing (tests/alloc), FEATHERDRIVE_SIMD set or not.
bool cpu_runs(SimdIsa isa) {
  const auto cpu = xsimd::available_architectures();
  return isa == SimdIsa::sse2 || (isa == SimdIsa::avx2 && cpu.avx2) ||
         (isa == SimdIsa::avx512 && cpu.avx512f);
}

}  // namespace

const char* to_string(SimdIsa isa) {
  switch (isa) {
    case SimdIsa::sse2:
      return "sse2";
    case SimdIsa::avx2:
      return "avx2";
    case SimdIsa::avx512:
      return "avx512";
  }
  return "unknown";
}

int simd_width(SimdIsa isa) {
  return isa == SimdIsa::avx512 ? 8 : isa == SimdIsa::avx2 ? 4 : 2;
}

std::vector<SimdIsa> available_simd_isas() {
  const auto cpu = xsimd::available_architectures();
  std::vector<SimdIsa> out{SimdIsa::sse2};  // every x86-64 CPU
  if (cpu.avx2) out.push_back(SimdIsa::avx2);
  if (cpu.avx512f) out.push_back(SimdIsa::avx512);
  return out;
}

void check_simd_isa(SimdIsa isa, const std::string& where) {
  if (cpu_runs(isa)) return;
  throw std::invalid_argument(where + " = " + to_string(isa) + ": this CPU has only up to " +
                              to_string(available_simd_isas().back()));
}

SimdIsa default_simd_isa() {
  const char* forced = std::getenv("FEATHERDRIVE_SIMD");
  if (!forced || !*forced) {  // the widest, without a vector (Batch::step allocates nothing)
    const auto cpu = xsimd::available_architectures();
    return cpu.avx512f ? SimdIsa::avx512 : cpu.avx2 ? SimdIsa::avx2 : SimdIsa::sse2;
  }
  // the narrowest, for set_isa; one: every lane group in one-lane blocks (lane_engine.hpp)
  if (std::strcmp(forced, "scalar") == 0 || std::strcmp(forced, "one") == 0) return SimdIsa::sse2;
  for (SimdIsa isa : {SimdIsa::sse2, SimdIsa::avx2, SimdIsa::avx512})
    if (std::strcmp(forced, to_string(isa)) == 0) {
      if (!cpu_runs(isa)) check_simd_isa(isa, "FEATHERDRIVE_SIMD");  // throws
      return isa;
    }
  throw std::invalid_argument(std::string("FEATHERDRIVE_SIMD = '") + forced +
                              "': expected scalar, one, sse2, avx2 or avx512");
}

bool simd_forced_scalar() {
  const char* forced = std::getenv("FEATHERDRIVE_SIMD");
  return forced && std::strcmp(forced, "scalar") == 0;
}

}  // namespace featherdrive
