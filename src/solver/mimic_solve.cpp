#include "featherdrive/solver/mimic_solve.hpp"

#include <algorithm>

namespace featherdrive {

MimicSolver::MimicSolver(const Model& model, std::vector<MimicJoint> joints)
    : joints_(std::move(joints)) {
  validate_mimic_joints(model, joints_);
  if (joints_.empty()) return;
  auto slot = [&](int dof) {
    const auto it = std::find(dofs_.begin(), dofs_.end(), dof);
    if (it != dofs_.end()) return static_cast<int>(it - dofs_.begin());
    dofs_.push_back(dof);
    q_index_.push_back(model.links[model.dof_link[dof]].q_index);
    return static_cast<int>(dofs_.size()) - 1;
  };
  for (const MimicJoint& m : joints_) {
    slot_a_.push_back(slot(m.dof_a));
    slot_b_.push_back(slot(m.dof_b));
  }
  rows_.assign(joints_.size(), MimicRow{});
  velocity_change_.assign(joints_.size() * dofs_.size(), 0.0);
  velocity_.assign(dofs_.size(), 0.0);
  impulse_ = scratch_ = VecX::Zero(model.nv);
  sweep_.emplace(model);
  for (const int dof : dofs_) sweep_->has_rows[static_cast<size_t>(dof)] = 1;
}

void MimicSolver::setup(const Model& model, const Data& data, double h, double bias_coefficient) {
  const size_t k = dofs_.size();
  auto fixed_impulse = [this](int dof, double) { return impulse_[dof]; };
  for (size_t j = 0; j < joints_.size(); ++j) {
    const MimicJoint& m = joints_[j];
    // M^-1 J^T: the velocity change of a unit lambda, from rest.
    impulse_[m.dof_a] = 1.0;
    impulse_[m.dof_b] = m.gear_ratio;
    scratch_.setZero();
    gauss_seidel_sweep(model, data, *sweep_, scratch_, fixed_impulse);
    impulse_[m.dof_a] = impulse_[m.dof_b] = 0.0;
    for (size_t s = 0; s < k; ++s) velocity_change_[j * k + s] = scratch_[dofs_[s]];
    const double r = scratch_[m.dof_a] + m.gear_ratio * scratch_[m.dof_b];
    rows_[j] = setup_mimic_row(m, r, h, bias_coefficient);
  }
}

void MimicSolver::solve(const Model& model, const Data& data, const VecX& q, const double* row_bias,
                        bool velocity_iteration, VecX& qd) {
  const size_t k = dofs_.size();
  for (size_t s = 0; s < k; ++s)
    velocity_[s] = qd[dofs_[s]] + (row_bias ? row_bias[dofs_[s]] : 0.0);
  for (size_t j = 0; j < joints_.size(); ++j) {
    const MimicJoint& m = joints_[j];
    const size_t a = static_cast<size_t>(slot_a_[j]), b = static_cast<size_t>(slot_b_[j]);
    const double error = q[q_index_[a]] + m.gear_ratio * q[q_index_[b]] + m.offset;
    const double velocity = velocity_[a] + m.gear_ratio * velocity_[b];
    const double lambda = mimic_impulse(rows_[j], error, velocity, velocity_iteration);
    impulse_[m.dof_a] += lambda;
    impulse_[m.dof_b] += m.gear_ratio * lambda;
    for (size_t s = 0; s < k; ++s) velocity_[s] += lambda * velocity_change_[j * k + s];
  }
  gauss_seidel_sweep(model, data, *sweep_, qd, [this](int dof, double) { return impulse_[dof]; });
  for (const int dof : dofs_) impulse_[dof] = 0.0;
}

}  // namespace featherdrive
