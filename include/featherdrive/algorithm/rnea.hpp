// Recursive Newton-Euler inverse dynamics (Featherstone 2008, table 5.1), O(n).
//
// Sign convention (Pinocchio's and MuJoCo's): M(q) qdd + b(q, v) = tau, with the bias
// b = C(q, v) v + g(q) and g(q) the joint forces that hold the robot still against gravity (the
// negative of gravity's generalized force). b is MuJoCo's qfrc_bias, Pinocchio's nle.
#pragma once

#include "featherdrive/algorithm/data.hpp"

namespace featherdrive {

/// tau = M(q) a + C(q, v) v + g(q): the joint forces (nv) that produce joint accelerations a
/// under the model's gravity, armature included. Returns data.tau.
const VecX& rnea(const Model& model, Data& data, const VecX& q, const VecX& v, const VecX& a);

/// The bias forces b = C(q, v) v + g(q) = rnea(q, v, 0). Returns data.tau.
const VecX& nonlinear_effects(const Model& model, Data& data, const VecX& q, const VecX& v);

/// g(q) = rnea(q, 0, 0): the joint forces that hold q still against gravity. Returns data.tau.
/// Leaves data.velocity and data.bias_acceleration zero (the kinematics of v = 0).
const VecX& generalized_gravity(const Model& model, Data& data, const VecX& q);

}  // namespace featherdrive
