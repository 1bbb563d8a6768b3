// PhysX's constraint force mixing of a link (computeArticulatedResponseMatrix in
// DyFeatherstoneForwardDynamic.cpp, read in the source): cfmScale times the largest of the three
// world-axis diagonal entries of the response of the link's centre-of-mass velocity to a linear
// impulse at its centre of mass, with the whole articulation free; 0 for a fixed root. From the
// whole-articulation response Lambda_i (articulated_response, docs/math/unit_response.md) by
// link_law::cfm (sim/link_laws.hpp, joint_constraints.md J8), the lanes' law too. O(1) per link.
#include "featherdrive/algorithm/link_motion_law.hpp"
#include "featherdrive/sim/link_laws.hpp"
#include "physx_stages.hpp"

namespace featherdrive {

void link_cfm(const Model& model, const Data& data, const std::vector<LinkParameters>& parameters,
              VecX& cfm) {
  for (int i = 0; i < model.num_links(); ++i) {
    const double scale = parameters[static_cast<size_t>(i)].cfm_scale;
    if (scale == 0.0 || (i == 0 && !model.floating_base())) {
      cfm[i] = 0.0;
      continue;
    }
    // The centre of mass in frame 0 (P1-2), as ABA's pass 1 and the lanes' cg form it.
    const Data::LinkConstants& k = data.constants[i];
    double c[3], mc[3];
    link_motion_law::centre_of_mass(data.world_rotation[i], data.frame_position[i].data(),
                                    k.com.data(), k.mass, c, mc);
    double Lambda[21];
    link_law::pack_symmetric(data.response[i].data(), Lambda);
    cfm[i] = link_law::cfm(Lambda, c, scale);
  }
}

}  // namespace featherdrive
