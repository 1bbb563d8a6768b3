// The position of one dof as a number: the one map from a configuration q to the per-dof
// coordinates that the trajectory CSV's q:<dof> columns, simulate's summary, sweep's objective,
// fit, the viewer and the compare tables show. A revolute or prismatic dof is its q entry; an
// axis of a spherical joint is PhysX's position of that axis (the rotation vector of the joint's
// quaternion, constraint/spherical_axes.hpp), not a quaternion entry. A floating root's six dofs
// have no such number: its position is its seven q entries.
#pragma once

#include "featherdrive/model/model.hpp"

namespace featherdrive {

/// Whether dof `dof` has a position of its own (a 1-dof joint or a spherical axis).
bool has_dof_position(const Model& model, int dof);

/// The position of dof `dof` in configuration q (size nq). Throws std::invalid_argument for a dof
/// out of range or a floating root's dof.
double dof_position(const Model& model, const double* q, int dof);
inline double dof_position(const Model& model, const VecX& q, int dof) {
  return dof_position(model, q.data(), dof);
}

/// Sets dof `dof`'s position in q: the q entry, or for a spherical axis the joint's quaternion
/// rebuilt as exp(theta) with that axis of theta = its positions replaced (so setting the three
/// axes in turn poses the joint as a scene's initial q does). Same errors as dof_position.
void set_dof_position(const Model& model, double* q, int dof, double value);

}  // namespace featherdrive
