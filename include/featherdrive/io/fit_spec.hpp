// A scene's `fit:` section: the parameters `featherdrive fit` identifies from a logged trajectory
// (docs/fitting.md), with their bounds and starting values, and how the log is read.
#pragma once

#include <string>
#include <vector>

namespace featherdrive {

enum class FitQuantity {
  stiffness,             ///< the drive's (drives.J.stiffness)
  damping,               ///< the drive's
  max_force,             ///< the drive's force limit
  armature,              ///< joints.J.armature
  friction_static,       ///< joints.J.friction.static
  friction_dynamic,      ///< joints.J.friction.dynamic
  friction_viscous,      ///< joints.J.friction.viscous
  friction_coefficient,  ///< joints.J.friction_coefficient
  delay,                 ///< drives.J.delay, integer steps; one value for all its joints
  mass_scale,            ///< a factor on a link's mass (its inertia scales with it)
  row_field,             ///< a row kind's field, "<kind>.<field>" (joints.J.<kind>.<field>)
};

/// The spelling in scenes: "stiffness", "friction.static", ...
const char* to_string(FitQuantity quantity);

/// One entry of fit.parameters: a quantity on some joints (links for mass_scale).
struct FitParameter {
  FitQuantity quantity = FitQuantity::stiffness;
  std::vector<std::string> names;  ///< joints, or links for mass_scale, in the order given
  std::vector<int> indices;        ///< their dofs, or model link indices for mass_scale
  double lower = 0.0, upper = 0.0;
  /// One value shared by all names (a single unknown), or one unknown per name. delay is
  /// always shared.
  bool shared = false;
  /// Starting values, one per unknown (1 if shared): `initial` from the file, else the scene's
  /// own value (the first name's if shared; mass_scale 1; delay the lower bound). Within bounds.
  std::vector<double> initial;
  std::string key;  ///< "fit.parameters[i]", for messages
  /// row_field: the kind's and the field's names and the field's column in
  /// Settings::row_parameters (constraint/row_kinds.hpp).
  std::string row_kind, row_field_name;
  int row_column = -1;
  /// The spelling in scenes: to_string(quantity), or "<kind>.<field>" for a row kind's field.
  std::string spelling() const;
};

/// fit.data: how the log is read.
struct FitData {
  /// exact: the log's time steps must be the scene's dt (relative 1e-6); linear: q and qd are
  /// interpolated linearly at t0 + k dt, the targets held from the last row at or before it.
  enum class Resample { exact, linear };
  Resample resample = Resample::exact;
  /// Multiple shooting: each segment of this many steps starts from the logged q and qd
  /// (0: one segment from the log's first row).
  int segment_steps = 0;
  /// Residual on qd as well as q, qd weighted by this factor (0: q only).
  double qd_weight = 0.0;
};

struct FitSpec {
  std::vector<FitParameter> parameters;
  FitData data;
  /// Number of continuous unknowns (delay excluded).
  int num_unknowns() const;
};

}  // namespace featherdrive
