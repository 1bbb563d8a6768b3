// Recursive Newton-Euler inverse dynamics (Featherstone 2008, table 5.1), O(n).
#pragma once

#include "featherdrive/algorithm/data.hpp"

namespace featherdrive {

/// tau = M(q) a + c(q, v) - g(q): the joint forces (nv) that produce joint accelerations a under
/// the model's gravity, armature included. Returns data.tau.
const VecX& rnea(const Model& model, Data& data, const VecX& q, const VecX& v, const VecX& a);

}  // namespace featherdrive
