// What the ground's contact rows and the self-collision rows share (docs/math/contact.md): PhysX
// 5.6.1's constants and the small laws both row kinds set up with.
#pragma once

#include <cmath>
#include <limits>

#include "featherdrive/spatial/spatial.hpp"

namespace featherdrive::contact_laws {

inline constexpr double kPgsBias = 0.8;            // C3
inline constexpr double kFrictionMassScale = 0.8;  // C11
inline constexpr double kMinNormalShare = 0.25;    // C12
/// PhysX keeps at most four points of a manifold (GU_MANIFOLD_CACHE_SIZE; G3).
inline constexpr int kManifoldPoints = 4;

/// scale / u, or 0 for a direction the link cannot move in (u = 0 without a cfm: a slider's
/// sideways friction rows), which then applies nothing (C22).
inline double row_mass(double scale, double u) {
  return u > 0.0 ? scale / u : 0.0;
}

/// C22a's k: J . Lambda J's own rounding is at most 72 eps |J|^2 max_i Lambda_ii (36 products of
/// |Lambda_ij| <= max_i Lambda_ii), Lambda's from the sweep a few eps per level of the tree.
inline constexpr double kResponseRounding = 1024.0;

/// A row's computed response u, or 0 when it is within the rounding of its own computation, a
/// direction the links cannot move in (C22a); largest: the largest diagonal entry of the
/// responses u was formed from.
inline double row_response(double u, const Vec6& J, double largest) {
  const double rounding =
      kResponseRounding * std::numeric_limits<double>::epsilon() * J.squaredNorm() * largest;
  return u > rounding ? u : 0.0;
}

/// A row's response u = J . Lambda J (lambda_j = Lambda J) on one link, C22a's way.
inline double row_response(const Vec6& J, const Vec6& lambda_j, const Mat6& lambda) {
  return row_response(J.dot(lambda_j), J, lambda.diagonal().maxCoeff());
}

/// The friction direction of a patch at rest, PhysX's (C10a): x cross n, or z cross n when n lies
/// within 45 degrees of x. It fixes which of the two rows comes first in the solve.
inline Vec3 fallback_tangent(const Vec3& n) {
  const Vec3 t = std::abs(n.x()) < 0.70710678 ? Vec3(0, -n.z(), n.y()) : Vec3(-n.y(), n.x(), 0);
  return t.normalized();
}

/// A unit impulse along u at the point r (relative to frame 0's origin) as a spatial force (C21).
inline Vec6 spatial_force(const Vec3& r, const Vec3& u) {
  Vec6 f;
  f.head<3>() = r.cross(u);
  f.tail<3>() = u;
  return f;
}

/// Keeps kManifoldPoints of count > kManifoldPoints points (and their separations) in the first
/// places, as PhysX's reduction of a manifold does (G3); taken: count scratch flags.
void reduce_points(Vec3* points, double* separations, char* taken, int count, const Vec3& n);

}  // namespace featherdrive::contact_laws
