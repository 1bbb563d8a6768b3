// Centre of mass of the whole articulation: velocity and Jacobian, O(n) on kinematics already
// in data (its position: center_of_mass in energy.hpp). World coordinates.
#pragma once

#include "featherdrive/algorithm/data.hpp"

namespace featherdrive {

/// d/dt of center_of_mass (forward_kinematics with velocities must have run).
Vec3 center_of_mass_velocity(const Model& model, const Data& data);

/// J_com (3 x nv), J_com v = center_of_mass_velocity; zero for a massless model. Fills
/// data.subtree_mass and data.subtree_moment. J is resized to 3 x nv if it has another size.
void center_of_mass_jacobian(const Model& model, Data& data, MatX& J);

}  // namespace featherdrive
