// Articulated-body algorithm (Featherstone 2008, table 7.1): forward dynamics in O(n).
#pragma once

#include "featherdrive/algorithm/data.hpp"

namespace featherdrive {

/// qdd = M(q)^-1 (tau - c(q, v) + g(q)) under the model's gravity, armature included.
/// Leaves IA, pA, U, D^-1 of this configuration in data. Returns data.qdd.
const VecX& aba(const Model& model, Data& data, const VecX& q, const VecX& v, const VecX& tau);

/// The second and third ABA passes on the kinematics already in data (forward_kinematics with
/// velocities must have run). external_force (null: none) holds a spatial force on every link in
/// frame 0, [torque about the frame origin; force]. Returns data.qdd.
const VecX& aba_from_kinematics(const Model& model, Data& data, const VecX& v, const VecX& tau,
                                const std::vector<Vec6>* external_force = nullptr);

/// ABA's first two passes on the kinematics in data: IA, pA, U, D^-1 and u, everything
/// aba_from_kinematics computes but the accelerations (joint_accelerations, or with the response
/// accelerations_and_response).
void articulated_bodies(const Model& model, Data& data, const VecX& v, const VecX& tau,
                        const std::vector<Vec6>* external_force = nullptr);

/// articulated_bodies in two halves, so that forces that read the velocities (PhysX's link
/// damping) can come between: pass 1 (data.velocity0, c_i, I_i and p_i in frame 0, S_i), then
/// pass 2 with external_force taken off p_i first, the same bits as articulated_bodies.
void body_motions(const Model& model, Data& data, const VecX& v);
void articulate(const Model& model, Data& data, const VecX& tau,
                const std::vector<Vec6>* external_force = nullptr);

/// ABA's third pass after articulated_bodies: qdd and each link's acceleration. Returns data.qdd.
const VecX& joint_accelerations(const Model& model, Data& data);

/// Only the articulated inertias IA, U and D^-1 (no bias forces), on kinematics already in data.
void articulated_inertias(const Model& model, Data& data);

}  // namespace featherdrive
