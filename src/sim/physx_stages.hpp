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

/// transmitted_force.cpp. After aba_from_kinematics (free accelerations): |F_i| of every link i,
/// F_i the spatial force its inbound joint transmits to its subtree (force and torque about the
/// link's centre of mass, one 6-vector), external link forces (may be null) included. subtree is
/// scratch (num_links entries).
void transmitted_force_magnitudes(const Model& model, const Data& data,
                                  const std::vector<Vec6>* external_force,
                                  std::vector<Vec6>& subtree, VecX& magnitude);

/// link_cfm.cpp. After articulated_response: cfm_i = cfm_scale_i x the largest diagonal entry of
/// the linear block of link i's whole-articulation response at its centre of mass (world axes);
/// 0 for a root that is not floating.
void link_cfm(const Model& model, const Data& data, const std::vector<LinkParameters>& parameters,
              VecX& cfm);

}  // namespace featherdrive
