// What every fuzz target checks after the code under test returns: a simulation's state and
// reported forces are finite, and a step that throws DivergenceError leaves them bit for bit as
// they were. A failure aborts, so libFuzzer records the input.
#pragma once

#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "featherdrive/sim/simulation.hpp"

namespace featherdrive::fuzz {

[[noreturn]] inline void bug(const char* what) {
  std::fprintf(stderr, "featherdrive fuzz: BUG: %s\n", what);
  std::abort();
}

inline bool same_bits(const VecX& a, const VecX& b) {
  return a.size() == b.size() &&
         (a.size() == 0 ||  // an empty vector's data() may be null, which memcmp must not get
          std::memcmp(a.data(), b.data(), sizeof(double) * static_cast<size_t>(a.size())) == 0);
}

inline void check_finite(const Simulation& sim) {
  if (!sim.q().allFinite()) bug("non-finite q without an error");
  if (!sim.qd().allFinite()) bug("non-finite qd without an error");
  if (!sim.drive_force().allFinite() || !sim.limit_force().allFinite() ||
      !sim.friction_force().allFinite() || !sim.velocity_limit_force().allFinite())
    bug("non-finite reported force without an error");
  if (!std::isfinite(sim.time())) bug("non-finite time");
  for (const Vec3& f : sim.link_contact_force())
    if (!f.allFinite()) bug("non-finite contact force without an error");
  for (const ContactReport& c : sim.contacts())
    if (!std::isfinite(c.normal_impulse) || !c.friction_impulse.allFinite() ||
        !c.position.allFinite())
      bug("non-finite contact report without an error");
}

/// One step: either it succeeds with a finite state, or it throws DivergenceError and leaves the
/// state as it was. Returns false after a divergence.
inline bool checked_step(Simulation& sim) {
  const VecX q = sim.q(), qd = sim.qd(), f = sim.drive_force(), l = sim.limit_force(),
             fr = sim.friction_force(), vl = sim.velocity_limit_force();
  const double t = sim.time();
  const long n = sim.step_count();
  const GuardAccount account = sim.guard_account();
  try {
    sim.step();
  } catch (const DivergenceError&) {
    if (!same_bits(q, sim.q()) || !same_bits(qd, sim.qd()) || !same_bits(f, sim.drive_force()) ||
        !same_bits(l, sim.limit_force()) || !same_bits(fr, sim.friction_force()) ||
        !same_bits(vl, sim.velocity_limit_force()) || sim.time() != t || sim.step_count() != n ||
        std::bit_cast<std::uint64_t>(account.created) !=
            std::bit_cast<std::uint64_t>(sim.guard_account().created))
      bug("a diverging step changed the state");
    return false;
  }
  if (sim.step_count() != n + 1) bug("the step count did not advance");
  check_finite(sim);
  return true;
}

}  // namespace featherdrive::fuzz
