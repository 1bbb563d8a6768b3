// PhysX's constraint force mixing of a link (computeArticulatedResponseMatrix in
// DyFeatherstoneForwardDynamic.cpp, read in the source): cfmScale times the largest of the three
// world-axis diagonal entries of the response of the link's centre-of-mass velocity to a linear
// impulse at its centre of mass, with the whole articulation free; 0 for a fixed root. From the
// whole-articulation response Lambda_i (articulated_response, docs/math/unit_response.md) by
// link_law::cfm (sim/link_laws.hpp, joint_constraints.md J8), the lanes' law too. O(1) per link.
#include "featherdrive/sim/link_laws.hpp"
#include "physx_stages.hpp"

namespace featherdrive {

void link_cfm(const Model& model, const Data& data, const std::vector<LinkParameters>& parameters,
              VecX& cfm) {
  const Vec3& origin = data.frame_origin;
  for (int i = 0; i < model.num_links(); ++i) {
    const double scale = parameters[static_cast<size_t>(i)].cfm_scale;
    if (scale == 0.0 || (i == 0 && !model.floating_base())) {
      cfm[i] = 0.0;
      continue;
    }
    const Vec3 c = data.world_position[i] + data.world_rotation[i] * data.constants[i].com - origin;
    double Lambda[21];
    link_law::pack_symmetric(data.response[i].data(), Lambda);
    cfm[i] = link_law::cfm(Lambda, c.data(), scale);
  }
}

}  // namespace featherdrive
