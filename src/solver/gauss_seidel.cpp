#include "featherdrive/solver/gauss_seidel.hpp"

namespace featherdrive {

SweepWorkspace::SweepWorkspace(const Model& model)
    : link_velocity_change(model.links.size(), Vec6::Zero()),
      subtree_impulse(model.links.size(), Vec6::Zero()),
      parent_impulse_after(model.links.size(), Vec6::Zero()),
      later_velocity_change(model.links.size(), Vec6::Zero()),
      joint_impulse(VecX::Zero(model.nv)),
      entry_velocity_change(VecX::Zero(model.nv)),
      has_rows(model.nv, 0),
      first_child(model.links.size(), 0),
      chain_next(model.links.size(), 0),
      parent_one_dof(model.links.size(), 0),
      finish_on_leave(model.links.size(), 0) {
  const int n = model.num_links();
  std::vector<char> later(model.links.size(), 0);  // it or an ancestor has a later sibling
  for (int i = 0; i < n; ++i) {
    const Link& link = model.links[i];
    if (link.parent >= 0) {
      first_child[i] = model.links[link.parent].children.front() == i;
      parent_one_dof[i] = model.links[link.parent].nv == 1;
    }
    chain_next[i] = link.nv == 1 && i + 1 < n && model.links[i + 1].parent == i &&
                    model.links[i + 1].nv == 1;
    if (link.parent >= 0)
      later[i] = model.links[link.parent].children.back() != i || later[link.parent];
    finish_on_leave[i] = link.nv == 1 && !later[i];
    if (!finish_on_leave[i] && (link.nv > 0 || later[i])) finish_after.push_back(i);
  }
}

}  // namespace featherdrive
