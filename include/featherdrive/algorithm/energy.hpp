// Energy and momentum of the whole articulation, on kinematics already in data
// (forward_kinematics with velocities). Used by tests as conservation laws and by users.
#pragma once

#include "featherdrive/algorithm/data.hpp"

namespace featherdrive {

/// Kinetic energy 1/2 sum v_i^T I_i v_i, plus 1/2 armature qd^2 for every dof.
double kinetic_energy(const Model& model, const Data& data, const VecX& qd);

/// Gravitational potential energy -sum m_i g . c_i (world-frame centres of mass).
double potential_energy(const Model& model, const Data& data);

/// Total spatial momentum [angular about the world origin; linear], world coordinates.
Vec6 momentum(const Model& model, const Data& data);

/// Centre of mass of the whole articulation, world coordinates.
Vec3 center_of_mass(const Model& model, const Data& data);

}  // namespace featherdrive
