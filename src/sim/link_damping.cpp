// PhysX's link damping and link velocity limits (computeLinkStates in
// DyFeatherstoneArticulation.cpp, read in the source): once per step, from the start-of-step
// velocity (frame 0, ABA's pass 1), each link gets an external force that enters the free
// velocity like gravity, by link_law::damping_force (sim/link_laws.hpp,
// docs/math/joint_constraints.md J10), the lanes' law too. The gravity term is PhysX's: it scales
// the link's weight by (1 - c_lin dt).
#include <cmath>

#include "featherdrive/algorithm/link_motion_law.hpp"
#include "featherdrive/sim/link_laws.hpp"
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
  using RowMajor3 = Eigen::Matrix<double, 3, 3, Eigen::RowMajor>;
  for (int i = 0; i < model.num_links(); ++i) {
    const LinkParameters& p = parameters[static_cast<size_t>(i)];
    const Data::LinkConstants& k = data.constants[i];
    const Mat3& R = data.world_rotation[i];
    const double* v = data.velocity0[i].data();  // frame 0, ABA's pass 1 (body_motions)
    // c (P1-2), v_c (P1-6) and omega in the link's axes (P1-7), as the lanes' link_damping.
    const Vec3& p0 = data.frame_position[i];
    double c[3], mc[3], v_com[3], local[3];
    link_motion_law::centre_of_mass(R, p0.data(), k.com.data(), k.mass, c, mc);
    link_motion_law::point_velocity(v, c, v_com);
    link_motion_law::in_link_axes(R, v, local);
    RowMajor3 RI;  // R Ic, as ABA's pass 1 forms it (unit_response.md, P1-1)
    if (data.info[i].inertia_diagonal)
      link_motion_law::rotate_principal(R, k.inertia_com(0, 0), k.inertia_com(1, 1),
                                        k.inertia_com(2, 2), RI);
    else
      link_motion_law::rotate_full(R, k.inertia_com, RI);
    const link_law::Damping<double> d{p.linear_damping, p.angular_damping, p.max_linear_velocity,
                                      p.max_angular_velocity};
    link_law::damping_force(d, v, local, v_com, RI.data(), c, k.mass, model.gravity.data(), dt,
                            force[static_cast<size_t>(i)].data());
  }
  return true;
}

}  // namespace featherdrive
