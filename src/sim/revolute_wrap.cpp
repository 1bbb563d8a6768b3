#include "featherdrive/sim/revolute_wrap.hpp"

#include <stdexcept>

#include "featherdrive/sim/revolute_wrap_law.hpp"

namespace featherdrive {

const char* to_string(RevoluteWrap wrap) {
  return wrap == RevoluteWrap::wrapped ? "wrapped" : "unwrapped";
}

RevoluteWrap parse_revolute_wrap(const std::string& text) {
  if (text == "wrapped") return RevoluteWrap::wrapped;
  if (text == "unwrapped") return RevoluteWrap::unwrapped;
  throw std::invalid_argument("revolute = '" + text + "' must be wrapped or unwrapped");
}

double wrap_revolute_position(double q) { return wrap_law::wrapped(q); }

void wrap_revolute_positions(const Model& model, const std::vector<RevoluteWrap>& wrap, VecX& q) {
  for (int d = 0; d < model.nv; ++d)
    if (wrap[static_cast<size_t>(d)] == RevoluteWrap::wrapped) {
      double& x = q[model.links[model.dof_link[d]].q_index];
      x = wrap_revolute_position(x);
    }
}

}  // namespace featherdrive
