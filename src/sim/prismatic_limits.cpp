// PhysX 5.6.1 clamps a limited prismatic joint's position to its limits whenever it integrates
// joint positions (read in the source, DyFeatherstoneArticulation.cpp / DyFeatherstoneForwardDynamic.cpp):
// PGS once per step, after the velocity iterations (propagateLinksDown), so no row of the step sees
// the clamp; TGS in every sub-step (propagateTransform, from recordDeltaMotion), so the next
// sub-step's limit row and the velocity iterations measure the position change from the clamped
// pose, i.e. see the joint exactly at its limit rather than past it. The velocity is not changed.
// With an exact limit row this never acts; with cfm the limit row lets the joint pass the limit a
// little. Compat::physx only.
#include <algorithm>

#include "physx_stages.hpp"

namespace featherdrive {

void clamp_prismatic_positions(const Model& model, const VecX& lower, const VecX& upper, VecX& q) {
  for (const Link& link : model.links) {
    if (link.joint_type != JointType::prismatic) continue;
    const int d = link.v_index;
    q[link.q_index] = std::clamp(q[link.q_index], lower[d], upper[d]);
  }
}

}  // namespace featherdrive
