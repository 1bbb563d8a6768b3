// PhysX departure 2: momentum corrections of a floating base (docs/math/physx_departures.md,
// "Floating-base momentum"). PhysX 5.6.1: FeatherstoneArticulation::computeLinkInternalAcceleration
// (after the free velocity), updateRootBody / recordDeltaMotion (the root pose, about its COM) and
// updateBodies (the end of the step). All are rigid motions of the whole articulation, i.e.
// changes of the root's velocity and position only; joint rates are never touched.
#include "featherdrive/sim/physx_departures.hpp"

#include <cmath>

#include "featherdrive/algorithm/link_motion_law.hpp"
#include "featherdrive/sim/integration_law.hpp"
#include "featherdrive/sim/momentum_law.hpp"

namespace featherdrive {
namespace {

// The links of a pose (and, for momentum, their velocities plus the bias where given) as
// momentum_law reads them.
struct PoseLinks {
  const Model& model;
  const WorldPose& pose;
  const WorldVelocity* vel = nullptr;
  const std::vector<Vec3>* bias_w = nullptr;
  const std::vector<Vec3>* bias_v = nullptr;

  double mass(int i) const { return model.links[i].mass; }
  const double* com(int i) const { return pose.com[i].data(); }
  void world_inertia(int i, double* I) const {
    momentum_law::world_inertia(pose.R[i], model.links[i].inertia_com, I);
  }
  void world_inertia_times(int i, const double* w, double* Iw) const {
    momentum_law::world_inertia_times(pose.R[i], model.links[i].inertia_com, w, Iw);
  }
  void velocity(int i, double* w, double* v) const {
    for (int r = 0; r < 3; ++r) {
      w[r] = bias_w ? vel->w[i][r] + (*bias_w)[i][r] : vel->w[i][r];
      v[r] = bias_v ? vel->v[i][r] + (*bias_v)[i][r] : vel->v[i][r];
    }
  }
};

// Linear momentum and angular momentum about pose.total_com of velocities vel + (bw, bv) (eq.
// PD-10); angular null: the linear only.
void momentum(const Model& model, const WorldPose& pose, const WorldVelocity& vel,
              const std::vector<Vec3>* bias_w, const std::vector<Vec3>* bias_v, double mass,
              Vec3& linear, Vec3* angular) {
  const PoseLinks links{model, pose, &vel, bias_w, bias_v};
  momentum_law::momentum(links, model.num_links(), pose.total_com.data(), mass, linear.data(),
                         angular ? angular->data() : nullptr);
}

// The rigid rotation dw about the COM that scales |L| by `ratio`, and the uniform linear velocity
// dv that then makes the linear momentum `target` (eq. PD-4, PD-5). P and L: the current momenta.
void rigid_correction(const Model& model, const WorldPose& pose, const Vec3& P, const Vec3& L,
                      double ratio, const Vec3& target, double mass, Vec3& dw, Vec3& dv) {
  const PoseLinks links{model, pose};
  const int n = model.num_links();
  const double* C = pose.total_com.data();
  double Iinv[9];
  momentum_law::compound_inverse(links, n, C, Iinv);
  momentum_law::rigid_correction(links, n, Iinv, C, mass, P.data(), L.data(), ratio,
                                 target.data(), dw.data(), dv.data());
}

// Writes a root world twist (angular velocity, origin velocity) into qd in the frame R (eq. PD-7
// inverted: R^T, unit_response.md's P1-7), as the lanes' physx_free_momentum.
void store_root_twist(const Model& model, const Mat3& R, const Vec3& w, const Vec3& v, VecX& qd) {
  const int iv = model.links[0].v_index;
  link_motion_law::in_link_axes(R, w.data(), &qd[iv]);
  link_motion_law::in_link_axes(R, v.data(), &qd[iv + 3]);
}

}  // namespace

void correct_free_velocity_momentum(const Model& model, const Data& data, const VecX& applied_force,
                                    const std::vector<Vec6>* link_force, double dt,
                                    PhysxDepartures& dep, VecX& qd) {
  const WorldPose& s = dep.start;
  const Link& root = model.links[0];
  const double M = dep.total_mass;
  // Target: the momentum before the velocity-product terms, i.e. the start momentum plus dt times
  // the external wrench (gravity at the COM; a wrench applied on the root's dofs).
  Vec3 P0, L0;
  momentum(model, s, dep.vel, nullptr, nullptr, M, P0, &L0);
  Vec3 n, f;  // the root's wrench in world axes (eq. PD-7), as the lanes' physx_start
  link_motion_law::in_world_axes(s.R[0], &applied_force[root.v_index], n.data());
  link_motion_law::in_world_axes(s.R[0], &applied_force[root.v_index + 3], f.data());
  momentum_law::add_root_wrench(dt, M, model.gravity.data(), n.data(), f.data(), s.p[0].data(),
                                s.total_com.data(), P0.data(), L0.data());
  // Link damping and link velocity limits act as external forces too (frame 0: torque about the
  // root's origin).
  if (link_force) {
    const Vec3 com = s.total_com - data.world_position[0];
    for (const Vec6& w : *link_force)
      momentum_law::add_link_wrench(dt, w.data(), com.data(), P0.data(), L0.data());
  }
  // The free velocity as PhysX's links carry it: biased.
  Vec3 w0, v0;
  root_world_twist(model, s, qd, w0, v0);
  world_velocity(model, s, qd, w0, v0, dep.scratch);
  Vec3 P1, L1;
  momentum(model, s, dep.scratch, &dep.bias_w, &dep.bias_v, M, P1, &L1);
  const double l1 = L1.norm();
  const double ratio = l1 == 0.0 ? 1.0 : L0.norm() / l1;
  Vec3 dw, dv;
  rigid_correction(model, s, P1, L1, ratio, P0, M, dw, dv);
  momentum_law::move_root(dw.data(), dv.data(), s.p[0].data(), s.total_com.data(), w0.data(),
                          v0.data());
  store_root_twist(model, s.R[0], w0, v0, qd);
}

// The lanes' integrate_root_physx calls the same law (quaternion_update.md, eq. Q-8).
void integrate_root_about_com(const Model& model, const VecX& qd, double h, PhysxDepartures& dep,
                              VecX& q) {
  const Link& root = model.links[0];
  const Mat3& E = root.tree_transform.E;
  double E_rows[9], R0[9];
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) {
      E_rows[3 * a + b] = E(a, b);
      R0[3 * a + b] = dep.root_rotation_start(a, b);
    }
  const Quat QT(Mat3(E.transpose()));  // the joint frame's world rotation
  const double QT_wxyz[4] = {QT.w(), QT.x(), QT.y(), QT.z()};
  const integration_law::RootFrame frame{E_rows, root.tree_transform.r.data(), QT_wxyz,
                                         E == Mat3::Identity()};
  integration_law::root_about_com(frame, root.com.data(), R0, &qd[root.v_index], h,
                                  &q[root.q_index]);
}

void correct_end_of_step_momentum(const Model& model, const Data& data, double dt,
                                  PhysxDepartures& dep, VecX& q, VecX& qd) {
  const WorldPose& s = dep.start;
  const Link& root = model.links[0];
  const double M = dep.total_mass;
  // Targets, from the solver's biased velocities in the start pose: the final ones (linear
  // momentum and |angular momentum|) and those the positions moved with (where the COM goes).
  Vec3 w0, v0, P_target, L_target, P_position;
  root_world_twist(model, s, qd, w0, v0);
  world_velocity(model, s, qd, w0, v0, dep.scratch);
  momentum(model, s, dep.scratch, &dep.bias_w, &dep.bias_v, M, P_target, &L_target);
  {
    Vec3 pw, pv;
    root_world_twist(model, s, dep.qd_position, pw, pv);
    world_velocity(model, s, dep.qd_position, pw, pv, dep.scratch);
    momentum(model, s, dep.scratch, nullptr, &dep.bias_v, M, P_position, nullptr);
  }
  // Velocities in the new pose: the root keeps its world angular velocity and COM velocity.
  world_pose(model, data, q, dep.now);
  const WorldPose& n = dep.now;
  Vec3 v_origin;
  momentum_law::keep_root_com_velocity(w0.data(), v0.data(), s.com[0].data(), s.p[0].data(),
                                       n.com[0].data(), n.p[0].data(), v_origin.data());
  world_velocity(model, n, qd, w0, v_origin, dep.scratch);
  Vec3 P1, L1;
  momentum(model, n, dep.scratch, nullptr, nullptr, M, P1, &L1);
  const double l1 = L1.norm();
  const double ratio = l1 == 0.0 ? 0.0 : L_target.norm() / l1;
  Vec3 dw, dv;
  rigid_correction(model, n, P1, L1, ratio, P_target, M, dw, dv);
  momentum_law::move_root(dw.data(), dv.data(), n.p[0].data(), n.total_com.data(), w0.data(),
                          v_origin.data());
  // The COM where the position-iteration momentum puts it: a shift of every link.
  double shift[3], joint_shift[3];
  momentum_law::com_shift(s.total_com.data(), P_position.data(), dt / M, n.total_com.data(), shift);
  link_motion_law::in_world_axes(root.tree_transform.E, shift, joint_shift);
  for (int r = 0; r < 3; ++r) q[root.q_index + r] += joint_shift[r];
  store_root_twist(model, n.R[0], w0, v_origin, qd);
}

}  // namespace featherdrive
