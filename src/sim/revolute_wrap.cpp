#include "featherdrive/sim/revolute_wrap.hpp"

#include <algorithm>
#include <numbers>
#include <stdexcept>

namespace featherdrive {

const char* to_string(RevoluteWrap wrap) {
  return wrap == RevoluteWrap::wrapped ? "wrapped" : "unwrapped";
}

RevoluteWrap parse_revolute_wrap(const std::string& text) {
  if (text == "wrapped") return RevoluteWrap::wrapped;
  if (text == "unwrapped") return RevoluteWrap::unwrapped;
  throw std::invalid_argument("revolute = '" + text + "' must be wrapped or unwrapped");
}

double wrap_revolute_position(double q) {
  constexpr double two_pi = 2.0 * std::numbers::pi;
  if (q > two_pi)
    q -= 2.0 * two_pi;
  else if (q < -two_pi)
    q += 2.0 * two_pi;
  return std::clamp(q, -2.0 * two_pi, 2.0 * two_pi);
}

void wrap_revolute_positions(const Model& model, const std::vector<RevoluteWrap>& wrap, VecX& q) {
  for (int d = 0; d < model.nv; ++d)
    if (wrap[static_cast<size_t>(d)] == RevoluteWrap::wrapped) {
      double& x = q[model.links[model.dof_link[d]].q_index];
      x = wrap_revolute_position(x);
    }
}

}  // namespace featherdrive
