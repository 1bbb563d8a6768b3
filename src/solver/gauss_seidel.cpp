#include "featherdrive/solver/gauss_seidel.hpp"

namespace featherdrive {

SweepWorkspace::SweepWorkspace(const Model& model)
    : link_velocity_change(model.links.size(), Vec6::Zero()),
      subtree_impulse(model.links.size(), Vec6::Zero()),
      parent_impulse_after(model.links.size(), Vec6::Zero()),
      later_velocity_change(model.links.size(), Vec6::Zero()),
      joint_impulse(VecX::Zero(model.nv)),
      entry_velocity_change(VecX::Zero(model.nv)),
      has_rows(model.nv, 0) {}

}  // namespace featherdrive
