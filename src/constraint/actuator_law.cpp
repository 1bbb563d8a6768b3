#include "featherdrive/constraint/actuator_law.hpp"

#include <algorithm>

namespace featherdrive {

const char* to_string(ActuatorKind kind) {
  switch (kind) {
    case ActuatorKind::none: return "none";
    case ActuatorKind::ideal_pd: return "ideal_pd";
    case ActuatorKind::dc_motor: return "dc_motor";
    case ActuatorKind::remotized_pd: return "remotized_pd";
  }
  return "unknown";
}

const char* to_string(ActuatorIntegration integration) {
  switch (integration) {
    case ActuatorIntegration::explicit_law: return "explicit";
    case ActuatorIntegration::implicit_law: return "implicit";
  }
  return "unknown";
}

// eq. (6): linear between the table's points, the end values beyond them. A NaN q (a diverging
// iterate, which the step then reports) reads the first value: the search below would run off the
// table's end.
double lookup_effort_limit(const std::vector<std::pair<double, double>>& lookup, double q) {
  if (!(q > lookup.front().first)) return lookup.front().second;
  if (q >= lookup.back().first) return lookup.back().second;
  // The first point above q; the one before it is at or below q.
  const auto hi = std::upper_bound(lookup.begin(), lookup.end(), q,
                                   [](double x, const auto& p) { return x < p.first; });
  const auto lo = hi - 1;
  const double w = (q - lo->first) / (hi->first - lo->first);
  return lo->second + w * (hi->second - lo->second);
}

double actuator_effort(const ExplicitActuator& a, double q, double qd, const ActuatorCommand& c) {
  if (a.kind == ActuatorKind::none) return 0.0;
  // eq. (1)
  const double computed =
      a.stiffness * (c.position - q) + a.damping * (c.velocity - qd) + c.effort;
  double low = -a.effort_limit, high = a.effort_limit;  // eq. (2)
  if (a.kind == ActuatorKind::dc_motor) {
    // eq. (3)-(5): the velocity held within the corner speeds, where the line meets the limit.
    const double S = a.saturation_effort, v_max = a.velocity_limit, E = a.effort_limit;
    const double corner = v_max * (1.0 + E / S);
    const double v = std::clamp(qd, -corner, corner);
    high = std::min(S * (1.0 - v / v_max), E);
    low = std::max(S * (-1.0 - v / v_max), -E);
  } else if (a.kind == ActuatorKind::remotized_pd) {
    high = std::min(a.effort_limit, lookup_effort_limit(a.lookup, q));  // eq. (7)
    low = -high;
  }
  return std::min(std::max(computed, low), high);
}

}  // namespace featherdrive
