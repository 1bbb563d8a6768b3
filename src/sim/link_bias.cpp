// PhysX departure 1: the biased joint velocity of prismatic rows (docs/math/physx_departures.md,
// "The link bias"). PhysX's free-velocity update moves each link's velocity by dt times its
// velocity-product acceleration (FeatherstoneArticulation::computeLinkInternalAcceleration adds the
// Coriolis vectors of computeLinkStates); a row measures its joint velocity from the two links'
// velocities at the joint point, so a prismatic row sees qd + delta.
#include "featherdrive/sim/physx_departures.hpp"

#include "featherdrive/algorithm/joint_motion.hpp"
#include "featherdrive/algorithm/kinematics.hpp"
#include "featherdrive/algorithm/link_motion_law.hpp"
#include "featherdrive/sim/link_bias_law.hpp"

namespace featherdrive {

WorldPose::WorldPose(const Model& model)
    : R(model.links.size(), Mat3::Identity()), p(model.links.size(), Vec3::Zero()),
      com(model.links.size(), Vec3::Zero()) {}

WorldVelocity::WorldVelocity(const Model& model)
    : w(model.links.size(), Vec3::Zero()), v(model.links.size(), Vec3::Zero()) {}

PhysxDepartures::PhysxDepartures(const Model& model)
    : start(model), now(model), vel(model), scratch(model),
      bias_w(model.links.size(), Vec3::Zero()), bias_v(model.links.size(), Vec3::Zero()),
      turn(model.links.size(), Vec3::Zero()), row_bias(VecX::Zero(model.nv)),
      qd_position(VecX::Zero(model.nv)) {
  for (const Link& l : model.links) total_mass += l.mass;
}

// The kinematics' own poses (world_poses, docs/math/joint_transform.md), as the lanes' link_pose
// forms them; each centre of mass p + R c summed left to right, as the lanes' link_com.
void world_pose(const Model& model, const Data& data, const VecX& q, WorldPose& pose) {
  const int n = model.num_links();
  world_poses(data, q, pose.R.data(), pose.p.data());
  double mass = 0.0;
  pose.total_com.setZero();
  for (int i = 0; i < n; ++i) {
    const Link& link = model.links[i];
    pose.com[i] = pose.p[i] + pose.R[i] * link.com;
    pose.total_com += link.mass * pose.com[i];
    mass += link.mass;
  }
  if (mass > 0.0) pose.total_com /= mass;
}

void root_world_twist(const Model& model, const WorldPose& pose, const VecX& qd, Vec3& w0, Vec3& v0) {
  const Link& root = model.links[0];
  if (root.joint_type != JointType::floating) {
    w0.setZero();
    v0.setZero();
    return;
  }
  link_motion_law::in_world_axes(pose.R[0], &qd[root.v_index], w0.data());
  link_motion_law::in_world_axes(pose.R[0], &qd[root.v_index + 3], v0.data());
}

// Eq. PD-6 link by link, as the lanes' world_velocity.
void world_velocity(const Model& model, const WorldPose& pose, const VecX& qd, const Vec3& w0,
                    const Vec3& v0, WorldVelocity& out) {
  using link_motion_law::JointRates;
  const int n = model.num_links();
  const double* none = nullptr;
  link_motion_law::world_velocity(w0.data(), v0.data(), none, pose.R[0], pose.p[0].data(),
                                  pose.com[0].data(), JointRates::none, none, none,
                                  out.w[0].data(), out.v[0].data());
  for (int i = 1; i < n; ++i) {
    const Link& link = model.links[i];
    const int p = link.parent;
    const JointRates joint = link.joint_type == JointType::revolute    ? JointRates::about_axis
                             : link.joint_type == JointType::prismatic ? JointRates::along_axis
                             : link.joint_type == JointType::spherical ? JointRates::ball
                                                                       : JointRates::none;
    link_motion_law::world_velocity(out.w[p].data(), out.v[p].data(), pose.com[p].data(),
                                    pose.R[i], pose.p[i].data(), pose.com[i].data(), joint,
                                    link.axis.data(), qd.data() + link.v_index, out.w[i].data(),
                                    out.v[i].data());
  }
}

void compute_link_bias(const Model& model, const Data& data, double dt, PhysxDepartures& dep) {
  const int n = model.num_links();
  WorldPose& s = dep.start;
  // The start pose and velocities, from the kinematics of the step's start and ABA's pass 1
  // (frame 0): each centre of mass's velocity by eq. P1-6 (unit_response.md), as the lanes'.
  double mass = 0.0;
  s.total_com.setZero();
  for (int i = 0; i < n; ++i) {
    const Link& link = model.links[i];
    s.R[i] = data.world_rotation[i];
    s.p[i] = data.world_position[i];
    s.com[i] = s.p[i] + s.R[i] * link.com;
    s.total_com += link.mass * s.com[i];
    mass += link.mass;
    const double* v = data.velocity0[i].data();
    const Vec3& p0 = data.frame_position[i];  // frame 0's, as the lanes'
    double c[3], mc[3];
    link_motion_law::centre_of_mass(s.R[i], p0.data(), link.com.data(), link.mass, c, mc);
    dep.vel.w[i] = data.velocity0[i].head<3>();
    link_motion_law::point_velocity(v, c, dep.vel.v[i].data());
  }
  if (mass > 0.0) s.total_com /= mass;
  dep.root_rotation_start = s.R[0];
  // B_i: the parent's B moved rigidly to the link's COM, plus dt times the link's own
  // velocity-product acceleration at zero joint and root accelerations: with r = c_i - c_p,
  // mu_w = w_i - w_p and mu_v = v_i - v_p - w_p x r (the joint's share of the link's velocity),
  // a_w = w_p x mu_w, a_v = w_p x (w_p x r) + 2 w_p x mu_v + mu_w x mu_v (eq. PD-1, the classical
  // acceleration of the COM; PhysX's Coriolis vector in computeLinkStates).
  dep.bias_w[0].setZero();
  dep.bias_v[0].setZero();
  for (int i = 1; i < n; ++i) {
    const int p = model.links[i].parent;
    const Vec3 r = s.com[i] - s.com[p];
    link_bias_law::link_bias(dep.vel.w[p].data(), dep.vel.v[p].data(), dep.bias_w[p].data(),
                             dep.bias_v[p].data(), dep.vel.w[i].data(), dep.vel.v[i].data(),
                             r.data(), dt, dep.bias_w[i].data(), dep.bias_v[i].data());
  }
  // delta = u . (B_child - B_parent) at the joint point (eq. PD-2); zero for revolute rows, whose
  // angular bias has no component along the axis.
  dep.row_bias.setZero();
  for (int i = 1; i < n; ++i) {
    const Link& link = model.links[i];
    // A spherical joint's rows are angular about its child's axes, which its angular bias does
    // not leave alone (docs/math/spherical_joints.md, eq. S-8).
    if (link.joint_type == JointType::spherical)
      for (int k = 0; k < 3; ++k)
        dep.row_bias[link.v_index + k] =
            s.R[i].col(k).dot(dep.bias_w[i] - dep.bias_w[link.parent]);
    if (link.joint_type != JointType::prismatic) continue;
    const int p = link.parent;
    const Vec3 u = s.R[i] * link.axis;
    dep.row_bias[link.v_index] = link_bias_law::prismatic_row_bias(
        u.data(), s.p[i].data(), s.com[i].data(), s.com[p].data(), dep.bias_w[i].data(),
        dep.bias_v[i].data(), dep.bias_w[p].data(), dep.bias_v[p].data());
  }
  for (int i = 0; i < n; ++i) dep.turn[i].setZero();
}

void track_prismatic_position_change(const Model& model, const Data& data, const VecX& q,
                                     const VecX& qd, double h, PhysxDepartures& dep,
                                     VecX& delta_x) {
  const int n = model.num_links();
  world_pose(model, data, q, dep.now);
  // The sub-step's link angular velocities in the step's frozen start frame, biased.
  Vec3 w0, v0;
  root_world_twist(model, dep.start, qd, w0, v0);
  world_velocity(model, dep.start, qd, w0, v0, dep.scratch);
  for (int i = 0; i < n; ++i) dep.turn[i] += h * (dep.scratch.w[i] + dep.bias_w[i]);
  // Position change of a prismatic joint: its child's COM displacement relative to its parent's,
  // less the parent's accumulated turn applied to the COM-to-COM offset, along the start axis
  // (eq. PD-3).
  const WorldPose& s = dep.start;
  for (int i = 1; i < n; ++i) {
    const Link& link = model.links[i];
    if (link.joint_type != JointType::prismatic) continue;
    const int p = link.parent;
    const Vec3 u = s.R[i] * link.axis;
    delta_x[link.v_index] = link_bias_law::prismatic_position_change(
        u.data(), dep.now.com[i].data(), s.com[i].data(), dep.now.com[p].data(), s.com[p].data(),
        dep.turn[p].data());
  }
}

}  // namespace featherdrive
