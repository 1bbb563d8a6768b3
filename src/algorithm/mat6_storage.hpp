// Simulation's Mat6 (all 36 entries, column-major) and MatNN as the laws written once over a
// symmetric 6 x 6's storage read, accumulate and write it (articulated_law.hpp,
// multi_dof_law.hpp, response_law.hpp; aba.cpp, inverse_mass_diagonal.cpp).
#pragma once

#include "featherdrive/spatial/types.hpp"

namespace featherdrive::detail {

// Eigen's fixed-size vectorizable matrices are 16-byte aligned: said so, SSE2 folds their loads
// into the arithmetic (unaligned, each is a load of its own).
template <class X>
[[gnu::always_inline]] inline X* aligned16(X* p) {
  return static_cast<X*>(__builtin_assume_aligned(p, 16));
}

// Read: entry (a, b).
struct Mat6Entries {
  const double* m;
  explicit Mat6Entries(const Mat6& M) : m(aligned16(M.data())) {}
  double operator()(int a, int b) const { return m[a + 6 * b]; }
};

// Written whole: entry (a, b) = f(a, b), column by column, each column formed before it is
// stored, so that rows pair into SSE2 (or AVX) operations (a store between the reads would have
// to be assumed to alias them).
struct Mat6Assigned {
  double* m;
  explicit Mat6Assigned(Mat6& M) : m(aligned16(M.data())) {}
  template <class F>
  [[gnu::always_inline]] void assign(const F& f) {
    // Unrolled: with b a constant, response_law's sums over S's nonzeros fold (a floating root's
    // RotationPair: rolled, its multi_dof_response took 3.6 times the instructions).
    #pragma GCC unroll 6
    for (int b = 0; b < 6; ++b) {
      double col[6];
      for (int a = 0; a < 6; ++a) col[a] = f(a, b);
      for (int a = 0; a < 6; ++a) m[a + 6 * b] = col[a];
    }
  }
};

// A parent's Mat6 as articulated_law accumulates it: all 36 entries, column by column, each
// column's addends formed before any is stored, so that the compiler pairs rows into SSE2 (or
// AVX) operations.
struct Mat6Accumulated {
  double* m;
  explicit Mat6Accumulated(Mat6& M) : m(aligned16(M.data())) {}
  template <class F>
  [[gnu::always_inline]] void accumulate(const F& f) {
    for (int b = 0; b < 6; ++b) {
      double add[6];
      for (int a = 0; a < 6; ++a) add[a] = f(a, b);
      for (int a = 0; a < 6; ++a) m[a + 6 * b] = m[a + 6 * b] + add[a];
    }
  }
};

// An N x N MatNN (column-major, N rows) read entry by entry.
template <int N>
struct ColumnMajor {
  const double* m;
  double operator()(int a, int b) const { return m[a + N * b]; }
};

}  // namespace featherdrive::detail
