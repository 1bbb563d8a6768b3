// The spatial force each joint transmits at the step's start, for PhysX's older joint friction
// (frictionCoefficient). PhysX (computeZAForceInv + computeJointTransmittedFrictionForce, read in
// the source) takes every link's Newton-Euler force I a + Z under the free accelerations (Z: the
// link's gravity, external and velocity-product forces, negated), sums it over the joint's subtree
// with torques about the child link's centre of mass, and uses |torque| + |force| (the
// "magnitude" of PhysX's spatial vector is the sum of its two halves' norms, not the 6-norm).
// docs/math/joint_constraints.md, "Friction that grows with the transmitted force".
#include "physx_stages.hpp"

namespace featherdrive {

void transmitted_force_magnitudes(const Model& model, const Data& data,
                                  const std::vector<Vec6>* external_force,
                                  std::vector<Vec6>& subtree, VecX& magnitude) {
  const int n = model.num_links();
  const Vec3& origin = data.frame_origin;
  // Each link's own force in frame 0, [torque about the origin; force].
  for (int i = 0; i < n; ++i) {
    const Data::LinkConstants& k = data.constants[i];
    const Mat3& R = data.world_rotation[i];
    const Vec3 c = data.world_position[i] + R * k.com - origin;
    const Vec6& v = data.velocity0[i];
    const Vec6& a = data.acceleration0[i];  // gravity as an upward acceleration
    const Vec3 omega = v.head<3>(), alpha = a.head<3>();
    const Vec3 v_com = v.tail<3>() + omega.cross(c);
    const Vec3 a_com = a.tail<3>() + alpha.cross(c) + omega.cross(v_com);
    const Mat3 I_w = R * k.inertia_com * R.transpose();
    const Vec3 f = k.mass * a_com;
    const Vec3 torque = I_w * alpha + omega.cross(I_w * omega);
    Vec6& out = subtree[static_cast<size_t>(i)];
    out.head<3>() = torque + c.cross(f);
    out.tail<3>() = f;
    if (external_force) out -= (*external_force)[static_cast<size_t>(i)];
  }
  // Subtree sums, leaves first (a parent precedes its children in the model order).
  for (int i = n - 1; i > 0; --i) {
    const int p = model.links[i].parent;
    if (p >= 0) subtree[static_cast<size_t>(p)] += subtree[static_cast<size_t>(i)];
  }
  for (int i = 0; i < n; ++i) {
    const Data::LinkConstants& k = data.constants[i];
    const Vec3 c = data.world_position[i] + data.world_rotation[i] * k.com - origin;
    const Vec6& F = subtree[static_cast<size_t>(i)];
    const Vec3 torque_at_com = F.head<3>() - c.cross(F.tail<3>());
    magnitude[i] = torque_at_com.norm() + F.tail<3>().norm();
  }
}

}  // namespace featherdrive
