// PhysX's constraint force mixing of a link (computeArticulatedResponseMatrix in
// DyFeatherstoneForwardDynamic.cpp, read in the source): cfmScale times the largest of the three
// world-axis diagonal entries of the response of the link's centre-of-mass velocity to a linear
// impulse at its centre of mass, with the whole articulation free; 0 for a fixed root. From the
// whole-articulation response Lambda_i (articulated_response, docs/math/unit_response.md): a unit
// impulse e_j at c is the spatial force b_j = [c x e_j; e_j] in frame 0 and the centre of mass
// moves by b_j^T Lambda_i b_j along e_j. O(1) per link.
#include <algorithm>

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
    double largest = 0.0;
    for (int j = 0; j < 3; ++j) {
      Vec6 b;
      b.head<3>() = c.cross(Vec3::Unit(j));
      b.tail<3>() = Vec3::Unit(j);
      largest = std::max(largest, b.dot(data.response[i] * b));
    }
    cfm[i] = scale * largest;
  }
}

}  // namespace featherdrive
