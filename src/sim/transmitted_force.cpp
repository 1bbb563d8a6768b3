// The spatial force each joint transmits at the step's start, for PhysX's older joint friction
// (frictionCoefficient). PhysX (computeZAForceInv + computeJointTransmittedFrictionForce, read in
// the source) sums every link's Newton-Euler force I a + Z under the free accelerations over the
// joint's subtree (Z: the link's gravity, external and velocity-product forces, negated). That
// sum is the articulated-body equation's IA_i a_i + pA_i of the joint's child link (ABA's
// articulated inertia and bias force, external forces included, and the free acceleration), read
// off in O(1) a link by link_law::transmitted_force_magnitude (sim/link_laws.hpp), the lanes'
// law too: |torque about the child's centre of mass| + |force| (the "magnitude" of PhysX's spatial
// vector is the sum of its two halves' norms, not the 6-norm). docs/math/joint_constraints.md,
// "Friction that grows with the transmitted force" (J9).
#include "featherdrive/algorithm/link_motion_law.hpp"
#include "featherdrive/sim/link_laws.hpp"
#include "physx_stages.hpp"

namespace featherdrive {

void transmitted_force_magnitudes(const Model& model, const Data& data, VecX& magnitude) {
  for (int i = 0; i < model.num_links(); ++i) {
    // The centre of mass in frame 0 (P1-2), as ABA's pass 1 and the lanes' cg form it.
    const Data::LinkConstants& k = data.constants[i];
    double c[3], mc[3];
    link_motion_law::centre_of_mass(data.world_rotation[i], data.frame_position[i].data(),
                                    k.com.data(), k.mass, c, mc);
    double IA[21];
    link_law::pack_symmetric(data.articulated_inertia[i].data(), IA);
    magnitude[i] = link_law::transmitted_force_magnitude(IA, data.acceleration0[i].data(),
                                                         data.articulated_bias[i].data(), c);
  }
}

}  // namespace featherdrive
