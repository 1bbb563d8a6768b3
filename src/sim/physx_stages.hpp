// Stages of the step that model PhysX 5.6.1's per-link and per-joint parameters
// (link_parameters.hpp). Each is O(n), allocation-free, and lives in its own file.
// docs/math/joint_constraints.md has the math.
#pragma once

#include <vector>

#include <array>

#include "featherdrive/algorithm/data.hpp"
#include "featherdrive/constraint/drive.hpp"
#include "featherdrive/sim/link_parameters.hpp"
#include "featherdrive/sim/physx_departures.hpp"

namespace featherdrive {

/// link_damping.cpp. After body_motions (ABA's pass 1, data.velocity0): the external force PhysX's
/// link damping and link velocity limits put on each link for the free velocity, in frame 0
/// (world axes, origin at the root link's origin), [torque about that origin; force]. Returns
/// false (force untouched) when no link has damping or a finite velocity limit.
bool link_damping_forces(const Model& model, const Data& data,
                         const std::vector<LinkParameters>& parameters, double dt,
                         std::vector<Vec6>& force);

/// transmitted_force.cpp. After articulated_bodies and the free accelerations
/// (accelerations_and_response): |tau_i| + |f_i| of every link i, (tau_i, f_i) the torque about
/// the link's centre of mass and the force its inbound joint transmits to its subtree, external
/// link forces included (articulated_bodies took them).
void transmitted_force_magnitudes(const Model& model, const Data& data, VecX& magnitude);

/// link_cfm.cpp. After articulated_response: cfm_i = cfm_scale_i x the largest diagonal entry of
/// the linear block of link i's whole-articulation response at its centre of mass (world axes);
/// 0 for a root that is not floating.
void link_cfm(const Model& model, const Data& data, const std::vector<LinkParameters>& parameters,
              VecX& cfm);

/// prismatic_limits.cpp. Compat::physx, at the end of the step: every prismatic joint with a
/// finite limit is put back within it (PhysX does this when it writes the step's positions, after
/// the velocity iterations; the rows of the step never see it).
void clamp_prismatic_positions(const Model& model, const VecX& lower, const VecX& upper, VecX& q);

/// spherical_rows.cpp. PhysX's position (twist, swing1 or swing2) of spherical dof `dof` at q.
double spherical_axis_position(const Model& model, const VecX& q, int dof);

/// spherical_rows.cpp. PhysX's drive error (target - position) of spherical dof `dof` at q, given
/// the drives of the joint's three axes (twist first): the driven axes' targets make one target
/// rotation.
double spherical_axis_drive_error(const Model& model, const VecX& q, int dof,
                                  const std::array<const Drive*, 3>& axes);

/// spherical_rows.cpp. Whether the model has a spherical joint.
bool has_spherical_joints(const Model& model);

/// spherical_rows.cpp. After a (sub-)step h moved q: every spherical joint moved again as PhysX
/// moves it (eq. S-7): its link turns by exp(h w) in the world from its rotation before the
/// sub-step (dep.now.R, world_pose of the q before it), w the link's world angular velocity from
/// the joints' frame-0 S of the step's start (data, AP14's angular rows) plus link_bias (if not
/// null); its parent stands where q
/// puts it. Writes the joint's quaternion into q; dep.now.R ends as the rotations after.
void integrate_spherical_joints(const Model& model, const Data& data, const VecX& qd,
                                const std::vector<Vec3>* link_bias, double h,
                                PhysxDepartures& dep, VecX& q);

}  // namespace featherdrive
