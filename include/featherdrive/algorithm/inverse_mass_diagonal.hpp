// The diagonal of M^-1 in O(n), without forming or factoring M: the unit response of every dof
// (spec ERRATA item 6). Derivation: docs/math/unit_response.md.
#pragma once

#include "featherdrive/algorithm/data.hpp"

namespace featherdrive {

/// From the articulated inertias in data (after aba or articulated_inertias): each link's
/// whole-articulation response Lambda_i, the coupling W_i, the diagonal blocks (M^-1)_ii and
/// diag(M^-1). Returns data.inverse_mass_diagonal.
const VecX& articulated_response(const Model& model, Data& data);

/// joint_accelerations and articulated_response in one pass root to tip, after
/// articulated_bodies: both read a link's S, U and D^-1, and the step needs both. The same bits as
/// the two in turn. Returns data.qdd.
const VecX& accelerations_and_response(const Model& model, Data& data);

/// diag(M(q)^-1) (nv), computed from scratch at q. Returns data.inverse_mass_diagonal.
const VecX& inverse_mass_diagonal(const Model& model, Data& data, const VecX& q);

}  // namespace featherdrive
