// A symmetric 6 x 6 as the laws written once over its storage read and write it (articulated_law,
// response_law): the full 36 entries (Simulation's Mat6) and the packed 21 (the lanes'), and
// random inputs for their tests.
#pragma once

#include <random>
#include <utility>

#include "featherdrive/sim/link_laws.hpp"
#include "featherdrive/spatial/types.hpp"

namespace featherdrive::test {

/// All 36 entries, column-major.
struct FullSymmetric {
  Mat6 m;
  double operator()(int a, int b) const { return m(a, b); }
  template <class F>
  void accumulate(const F& f) {
    for (int b = 0; b < 6; ++b)
      for (int a = 0; a < 6; ++a) m(a, b) = m(a, b) + f(a, b);
  }
  template <class F>
  void assign(const F& f) {
    for (int b = 0; b < 6; ++b)
      for (int a = 0; a < 6; ++a) m(a, b) = f(a, b);
  }
};

/// Where entry (a, b) is in the packed 21 (link_law::pack_symmetric's layout, the lanes' kSym).
inline int packed_index(int a, int b) {
  if (a > b) std::swap(a, b);
  if (b < 3) return a == b ? a : (a == 0 ? (b == 1 ? 3 : 4) : 5);
  if (a < 3) return 6 + 3 * a + (b - 3);
  return packed_index(a - 3, b - 3) + 15;
}

/// The packed 21, upper triangle only.
struct PackedSymmetric {
  double e[21];
  double operator()(int a, int b) const { return e[packed_index(a, b)]; }
  template <class F>
  void accumulate(const F& f) {
    for (int a = 0; a < 6; ++a)
      for (int b = a; b < 6; ++b) e[packed_index(a, b)] = e[packed_index(a, b)] + f(a, b);
  }
  template <class F>
  void assign(const F& f) {
    for (int a = 0; a < 6; ++a)
      for (int b = a; b < 6; ++b) e[packed_index(a, b)] = f(a, b);
  }
};

inline PackedSymmetric pack(const Mat6& m) {
  PackedSymmetric p;
  link_law::pack_symmetric(m.data(), p.e);
  return p;
}

/// A random symmetric positive definite 6 x 6, symmetric to the bit.
inline Mat6 random_spd(std::mt19937_64& rng) {
  std::normal_distribution<double> n;
  Mat6 A;
  for (int c = 0; c < 6; ++c)
    for (int r = 0; r < 6; ++r) A(r, c) = n(rng);
  const Mat6 M = A * A.transpose() + 0.1 * Mat6::Identity();
  return 0.5 * (M + M.transpose());
}

inline Vec6 random_vec6(std::mt19937_64& rng) {
  std::normal_distribution<double> n;
  return Vec6(n(rng), n(rng), n(rng), n(rng), n(rng), n(rng));
}

}  // namespace featherdrive::test
