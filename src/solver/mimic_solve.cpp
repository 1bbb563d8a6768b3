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
  struct Rows {  // this solver's rows, as mimic_law::solve_rows reads them
    MimicSolver& m;
    const VecX& q;
    const MimicJoint& joint(int j) const { return m.joints_[static_cast<size_t>(j)]; }
    const MimicRow& row(int j) const { return m.rows_[static_cast<size_t>(j)]; }
    double gear(int j) const { return joint(j).gear_ratio; }
    double offset(int j) const { return joint(j).offset; }
    int slot_a(int j) const { return m.slot_a_[static_cast<size_t>(j)]; }
    int slot_b(int j) const { return m.slot_b_[static_cast<size_t>(j)]; }
    double q_a(int j) const { return q[m.q_index_[static_cast<size_t>(slot_a(j))]]; }
    double q_b(int j) const { return q[m.q_index_[static_cast<size_t>(slot_b(j))]]; }
    int dof_a(int j) const { return joint(j).dof_a; }
    int dof_b(int j) const { return joint(j).dof_b; }
    const double* change(int j) const {
      return m.velocity_change_.data() + static_cast<size_t>(j) * m.dofs_.size();
    }
    double* velocity() const { return m.velocity_.data(); }
    double& given(int dof) const { return m.impulse_[dof]; }
  } rows{*this, q};
  mimic_law::solve_rows<double>(rows, static_cast<int>(joints_.size()), static_cast<int>(k),
                                velocity_iteration);
  gauss_seidel_sweep(model, data, *sweep_, qd, [this](int dof, double) { return impulse_[dof]; });
  for (const int dof : dofs_) impulse_[dof] = 0.0;
}

}  // namespace featherdrive
