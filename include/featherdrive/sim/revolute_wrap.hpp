// PhysX 5.6.1's two revolute joint types: eREVOLUTE brings the joint position back into
// [-2 pi, 2 pi] at the end of every step, eREVOLUTE_UNWRAPPED lets it count turns
// (docs/math/revolute_wrap.md).
#pragma once

#include <string>
#include <vector>

#include "featherdrive/model/model.hpp"

namespace featherdrive {

enum class RevoluteWrap { unwrapped, wrapped };
const char* to_string(RevoluteWrap wrap);
/// "wrapped" or "unwrapped"; throws std::invalid_argument naming the value otherwise.
RevoluteWrap parse_revolute_wrap(const std::string& text);

/// eq. (1): q - 4 pi above 2 pi, q + 4 pi below -2 pi, then clamped to [-4 pi, 4 pi].
double wrap_revolute_position(double q);

/// Wraps q (nq) at every dof whose `wrap` entry (nv) is wrapped.
void wrap_revolute_positions(const Model& model, const std::vector<RevoluteWrap>& wrap, VecX& q);

}  // namespace featherdrive
