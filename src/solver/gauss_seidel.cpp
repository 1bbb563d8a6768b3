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
      links(model.links.size()) {
  const int n = model.num_links();
  first_child_free_.assign(links.size(), false);
  std::vector<char> later(model.links.size(), 0);  // it or an ancestor has a later sibling
  for (int i = 0; i < n; ++i) {
    const featherdrive::Link& link = model.links[i];
    Link& l = links[static_cast<size_t>(i)];
    l.parent = link.parent;
    l.v_index = link.v_index;
    l.nv = static_cast<signed char>(link.nv);
    if (link.parent >= 0) {
      const featherdrive::Link& parent = model.links[link.parent];
      l.last_child = parent.children.back() == i;
      l.first_child = parent.children.front() == i;
      first_child_free_[static_cast<size_t>(i)] = l.first_child;
      l.parent_one_dof = parent.nv == 1;
    }
    l.chain_next = link.nv == 1 && i + 1 < n && model.links[i + 1].parent == i &&
                   model.links[i + 1].nv == 1;
    if (link.parent >= 0)
      later[i] = model.links[link.parent].children.back() != i || later[link.parent];
    l.finish_on_leave = link.nv == 1 && !later[i];
    if (!l.finish_on_leave && (link.nv > 0 || later[i])) finish_after.push_back(i);
    l.chain_up = sweep_walk::chain_up<true>(l.finish_on_leave, l.parent, l.parent_one_dof,
                                            l.first_child, l.last_child);
  }
  chain_next_free_.resize(links.size());
  for (size_t i = 0; i < links.size(); ++i) chain_next_free_[i] = links[i].chain_next;
}

void SweepWorkspace::set_contact_links(const std::vector<char>& has_contacts) {
  const int n = static_cast<int>(links.size());
  any_contacts = false;
  for (int i = 0; i < n; ++i) {
    Link& l = links[static_cast<size_t>(i)];
    l.contacts = has_contacts[static_cast<size_t>(i)] != 0;
    any_contacts = any_contacts || l.contacts;
  }
  for (int i = 0; i < n; ++i) {
    Link& l = links[static_cast<size_t>(i)];
    const bool parent_contacts = l.parent >= 0 && links[static_cast<size_t>(l.parent)].contacts;
    // The first child of a link with contacts adds to the pA its contacts started.
    l.first_child = l.parent >= 0 && !parent_contacts && first_child_free_[static_cast<size_t>(i)];
    // A run of 1-dof links stops after a link with contacts: its child must see them.
    l.chain_next = chain_next_free_[static_cast<size_t>(i)] && !l.contacts;
    l.chain_up = sweep_walk::chain_up<true>(l.finish_on_leave, l.parent, l.parent_one_dof,
                                            l.first_child, l.last_child);
  }
}

}  // namespace featherdrive
