// PhysX 5.6.1 clamps a limited prismatic joint's position to its limits when it writes the step's
// joint positions (enforcePrismaticLimits, from propagateLinksDown for PGS and
// computeAndEnforceJointPositions for TGS, in DyFeatherstoneForwardDynamic.cpp, read in the
// source): after the velocity iterations, so no row of the step sees the clamp. With an exact limit row this never acts; with cfm the limit row lets the
// joint pass the limit a little, and PhysX's positions stop at it. Compat::physx only.
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
