// The row kinds the step solves after each dof's drive, in order (row_kind.hpp): adding a kind is
// its own file and its line here. The faces, Settings and the checkpoint reach the kinds through
// the table below, by name.
#pragma once

#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "featherdrive/constraint/joint_spring.hpp"
#include "featherdrive/constraint/row_kind.hpp"

namespace featherdrive {

using RowKinds = RowKindList<JointSpring>;

/// A row kind as the faces see it: its name, its output's, its fields, and where its fields lie
/// in Settings::row_parameters' columns.
struct RowKindInfo {
  std::string_view name;
  std::string_view force;
  std::span<const RowField> fields;
  int index = 0;
  int offset = 0;  ///< its first column in Settings::row_parameters
  /// K::check and K::active.
  void (*check)(std::string_view joint, std::span<const double> values) = nullptr;
  bool (*active)(std::span<const double> values) = nullptr;
};

/// Every kind, in RowKinds' order.
std::span<const RowKindInfo> row_kinds();
/// The kind of that name; throws std::invalid_argument listing the kinds for another.
const RowKindInfo& row_kind(std::string_view name);
/// The column of a kind's field in Settings::row_parameters; throws std::invalid_argument naming
/// the kind's fields for another.
int row_field_column(const RowKindInfo& kind, std::string_view field);
/// "joint_spring, ..." for messages.
std::string row_kind_names();

}  // namespace featherdrive
