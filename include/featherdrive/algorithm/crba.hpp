// Composite-rigid-body algorithm (Featherstone 2008, table 6.2): the joint-space inertia matrix.
#pragma once

#include "featherdrive/algorithm/data.hpp"

namespace featherdrive {

/// M(q) (nv x nv, armature on the diagonal), dense. Returns data.M.
const MatX& crba(const Model& model, Data& data, const VecX& q);

}  // namespace featherdrive
