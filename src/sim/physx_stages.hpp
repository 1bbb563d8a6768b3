// Stages of the step that model PhysX 5.6.1's per-link and per-joint parameters
// (link_parameters.hpp). Each is O(n), allocation-free, and lives in its own file.
// docs/math/joint_constraints.md has the math.
#pragma once

#include <vector>

#include "featherdrive/algorithm/data.hpp"
#include "featherdrive/sim/link_parameters.hpp"

namespace featherdrive {

/// link_damping.cpp. After forward_kinematics: the external force PhysX's link damping and link
/// velocity limits put on each link for the free velocity, in frame 0 (world axes, origin at the
/// root link's origin), [torque about that origin; force]. Returns false (force untouched) when
/// no link has damping or a finite velocity limit.
bool link_damping_forces(const Model& model, const Data& data,
                         const std::vector<LinkParameters>& parameters, double dt,
                         std::vector<Vec6>& force);

/// transmitted_force.cpp. After aba_from_kinematics (free accelerations): |tau_i| + |f_i| of every
/// link i, (tau_i, f_i) the torque about the link's centre of mass and the force its inbound joint
/// transmits to its subtree, external link forces (may be null) included. subtree is scratch
/// (num_links entries).
void transmitted_force_magnitudes(const Model& model, const Data& data,
                                  const std::vector<Vec6>* external_force,
                                  std::vector<Vec6>& subtree, VecX& magnitude);

/// link_cfm.cpp. After articulated_response: cfm_i = cfm_scale_i x the largest diagonal entry of
/// the linear block of link i's whole-articulation response at its centre of mass (world axes);
/// 0 for a root that is not floating.
void link_cfm(const Model& model, const Data& data, const std::vector<LinkParameters>& parameters,
              VecX& cfm);

/// prismatic_limits.cpp. Compat::physx, at the end of the step: every prismatic joint with a
/// finite limit is put back within it (PhysX does this when it writes the step's positions, after
/// the velocity iterations; the rows of the step never see it).
void clamp_prismatic_positions(const Model& model, const VecX& lower, const VecX& upper, VecX& q);

}  // namespace featherdrive
