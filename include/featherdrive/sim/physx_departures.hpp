// PhysX 5.6.1's two departures from textbook Gauss-Seidel, active under `compat: physx`
// (../shared/physx/NOTES.md, "Where PhysX departs"; docs/math/physx_departures.md):
//  1. rows see joint velocities measured from link velocities that carry dt times the
//     velocity-product acceleration (the "bias"); for a prismatic row this shifts the velocity by a
//     constant delta, and TGS measures its position change geometrically;
//  2. a floating base gets momentum corrections on the root, in the free-velocity update and at the
//     end of the step, and its pose is integrated about its centre of mass with world velocities.
// All of it is O(n) per call and allocation-free after construction.
#pragma once

#include <vector>

#include "featherdrive/algorithm/data.hpp"

namespace featherdrive {

/// World-frame link state of one pose: rotation, origin, centre of mass.
struct WorldPose {
  explicit WorldPose(const Model& model);
  std::vector<Mat3> R;
  std::vector<Vec3> p, com;
  Vec3 total_com = Vec3::Zero();
};

/// Angular velocity and centre-of-mass velocity of every link, world frame.
struct WorldVelocity {
  explicit WorldVelocity(const Model& model);
  std::vector<Vec3> w, v;
};

/// Workspace and per-step constants of the departures.
struct PhysxDepartures {
  explicit PhysxDepartures(const Model& model);

  WorldPose start, now;           ///< the step's start pose; the current pose (TGS, end of step)
  WorldVelocity vel, scratch;     ///< link velocities (scratch for the momentum passes)
  std::vector<Vec3> bias_w, bias_v;  ///< B_i = dt * velocity-product acceleration at the COM
  std::vector<Vec3> turn;         ///< TGS: sum of h * (biased) angular velocity per link
  VecX row_bias;                  ///< delta per dof: the bias a row sees (0 but for prismatic rows)
  VecX qd_position;               ///< velocity the positions moved with (PGS) / its sub-step mean (TGS)
  double total_mass = 0.0;
  Mat3 root_rotation_start = Mat3::Identity();
};

/// Poses from the configuration q by the kinematics' world_poses (data's constants only).
void world_pose(const Model& model, const Data& data, const VecX& q, WorldPose& pose);

/// Link velocities for pose, joint rates qd (joints of the non-root links) and the root's world
/// angular velocity w0 and origin velocity v0.
void world_velocity(const Model& model, const WorldPose& pose, const VecX& qd, const Vec3& w0,
                    const Vec3& v0, WorldVelocity& out);

/// Root world twist (angular velocity, origin velocity) from its body-frame velocity in qd.
void root_world_twist(const Model& model, const WorldPose& pose, const VecX& qd, Vec3& w0, Vec3& v0);

/// Stage 1 (link_bias.cpp): from the start pose and velocities, the bias B_i of every link and the
/// delta of every prismatic row.
void compute_link_bias(const Model& model, const Data& data, double dt, PhysxDepartures& dep);

/// Stage 1, TGS: the geometric position change of every prismatic dof after a sub-step of h, qd the
/// rates after the sub-step's sweep, q the configuration after it (overwrites delta_x there).
void track_prismatic_position_change(const Model& model, const Data& data, const VecX& q,
                                     const VecX& qd, double h, PhysxDepartures& dep, VecX& delta_x);

/// Stage 2 (momentum_correction.cpp): rescales the angular momentum about the COM after the free
/// velocity update to its magnitude before the velocity-product terms, and restores the linear
/// momentum, by a rigid motion of the root. qd holds the free velocity on entry.
void correct_free_velocity_momentum(const Model& model, const Data& data, const VecX& applied_force,
                                    const std::vector<Vec6>* link_force, double dt,
                                    PhysxDepartures& dep, VecX& qd);

/// Stage 2: the root pose advanced over h about its centre of mass with the world velocity of the
/// step's start frame (PhysX keeps root velocities in the world).
void integrate_root_about_com(const Model& model, const VecX& qd, double h, PhysxDepartures& dep,
                              VecX& q);

/// Stage 2, end of step: velocities in the new pose, linear momentum and angular momentum magnitude
/// of the solver's velocities imposed by a rigid motion, COM moved where the position-iteration
/// momentum puts it. q: the integrated configuration; qd: the solver's final velocities.
void correct_end_of_step_momentum(const Model& model, const Data& data, double dt,
                                  PhysxDepartures& dep, VecX& q, VecX& qd);

}  // namespace featherdrive
