// The cross and dot products of 3-vectors as T[3] arrays, over the number type (double, or a pack
// of SIMD lanes), for the laws the scalar step and the lanes share (link_laws.hpp,
// link_bias_law.hpp). No include: the lanes' units compiled for AVX2 and AVX-512 take in no
// inline function of the rest of the library.
#pragma once

namespace featherdrive::vector3_law {

template <class T>
void cross(const T* a, const T* b, T* out) {
  out[0] = a[1] * b[2] - a[2] * b[1];
  out[1] = a[2] * b[0] - a[0] * b[2];
  out[2] = a[0] * b[1] - a[1] * b[0];
}

template <class T>
T dot(const T* a, const T* b) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

}  // namespace featherdrive::vector3_law
