// The checks of a simulation's state vectors, shared by Simulation's setters and by whatever
// checks a state without a Simulation (Batch, the Python kinematics): docs/architecture.md.
#pragma once

#include "featherdrive/model/model.hpp"

namespace featherdrive {

/// Throws std::invalid_argument "what: expected n values, got m" or "what[i] = x is not finite".
void check_state_vector(const VecX& x, Eigen::Index expected, const char* what);

/// q checked (nq finite values; the quaternions of spherical and floating joints of a norm that
/// is neither zero nor overflows, or of norm 1 within 1e-9 with `unit`) and, unless `unit`,
/// normalised: what Simulation::set_q stores. Throws std::invalid_argument naming the joint.
VecX checked_configuration(const Model& model, const VecX& q, bool unit = false);

}  // namespace featherdrive
