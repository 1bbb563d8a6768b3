// The instruction sets of Batch's SIMD lanes: which this CPU runs, and FEATHERDRIVE_SIMD.
// docs/simd_batch.md.
#include "featherdrive/sim/simd_isa.hpp"

#include <xsimd/config/xsimd_arch.hpp>

#include <algorithm>
#include <cstdlib>
#include <stdexcept>
#include <string>

namespace featherdrive {

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
  const std::vector<SimdIsa> has = available_simd_isas();
  if (std::find(has.begin(), has.end(), isa) == has.end())
    throw std::invalid_argument(where + " = " + to_string(isa) + ": this CPU has only up to " +
                                to_string(has.back()));
}

SimdIsa default_simd_isa() {
  const char* forced = std::getenv("FEATHERDRIVE_SIMD");
  if (!forced || !*forced) {  // the widest, without a vector (Batch::step allocates nothing)
    const auto cpu = xsimd::available_architectures();
    return cpu.avx512f ? SimdIsa::avx512 : cpu.avx2 ? SimdIsa::avx2 : SimdIsa::sse2;
  }
  // the narrowest, for set_isa; one: every lane group in one-lane blocks (lane_engine.hpp)
  if (std::string(forced) == "scalar" || std::string(forced) == "one") return SimdIsa::sse2;
  for (SimdIsa isa : {SimdIsa::sse2, SimdIsa::avx2, SimdIsa::avx512})
    if (std::string(forced) == to_string(isa)) {
      check_simd_isa(isa, "FEATHERDRIVE_SIMD");
      return isa;
    }
  throw std::invalid_argument(std::string("FEATHERDRIVE_SIMD = '") + forced +
                              "': expected scalar, one, sse2, avx2 or avx512");
}

bool simd_forced_scalar() {
  const char* forced = std::getenv("FEATHERDRIVE_SIMD");
  return forced && std::string(forced) == "scalar";
}

}  // namespace featherdrive
