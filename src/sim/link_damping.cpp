// PhysX's link damping and link velocity limits (computeLinkStates in
// DyFeatherstoneArticulation.cpp, read in the source): once per step, from the start-of-step
// velocity, each link gets an external force that enters the free velocity like gravity.
// With c = min(damping, 1/dt) and s = 1 - v_max / |v| where |v| > v_max (else 0):
//   force on the centre of mass  -m (c_lin + s_lin / dt) v_com - m c_lin dt g,
//   torque                       -I_w (c_ang + s_ang / dt) omega.
// The gravity term is PhysX's: it scales the link's weight by (1 - c_lin dt).
// docs/math/joint_constraints.md, "Link damping and link velocity limits".
#include <algorithm>
#include <cmath>

#include "physx_stages.hpp"

namespace featherdrive {

bool link_damping_forces(const Model& model, const Data& data,
                         const std::vector<LinkParameters>& parameters, double dt,
                         std::vector<Vec6>& force) {
  bool any = false;
  for (const LinkParameters& p : parameters)
    any = any || p.linear_damping > 0.0 || p.angular_damping > 0.0 ||
          std::isfinite(p.max_linear_velocity) || std::isfinite(p.max_angular_velocity);
  if (!any) return false;
  const Vec3& origin = data.world_position[0];
  for (int i = 0; i < model.num_links(); ++i) {
    const LinkParameters& p = parameters[static_cast<size_t>(i)];
    const Data::LinkConstants& k = data.constants[i];
    const Mat3& R = data.world_rotation[i];
    const Vec6& v = data.velocity[i];  // link frame
    const Vec3 omega = R * v.head<3>();
    const Vec3 v_com = R * (v.tail<3>() + v.head<3>().cross(k.com));
    const Vec3 c = data.world_position[i] + R * k.com - origin;
    const double lin = p.linear_damping > 0.0 ? std::min(p.linear_damping, 1.0 / dt) : 0.0;
    const double ang = p.angular_damping > 0.0 ? std::min(p.angular_damping, 1.0 / dt) : 0.0;
    const double speed = v_com.norm(), spin = omega.norm();
    const double lin_scale = speed > p.max_linear_velocity ? 1.0 - p.max_linear_velocity / speed : 0.0;
    const double ang_scale = spin > p.max_angular_velocity ? 1.0 - p.max_angular_velocity / spin : 0.0;
    const Vec3 f = -k.mass * (lin + lin_scale / dt) * v_com - k.mass * lin * dt * model.gravity;
    const Mat3 I_w = R * k.inertia_com * R.transpose();
    const Vec3 torque = -(ang + ang_scale / dt) * (I_w * omega);
    Vec6& out = force[static_cast<size_t>(i)];
    out.head<3>() = torque + c.cross(f);
    out.tail<3>() = f;
  }
  return true;
}

}  // namespace featherdrive
