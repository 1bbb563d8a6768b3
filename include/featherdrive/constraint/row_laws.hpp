// The laws of a dof's rows, written once over a number type T: double in the step (dof_rows.cpp,
// step.cpp) and a pack of environments in the SIMD lanes (sim/simd_lane_step.hpp). They branch on
// nothing T holds: every choice is a select, so a lane runs the operations a lone dof runs and
// its bits do not depend on its neighbours. Each law returns the change of the row's accumulated
// impulse and updates the accumulator; whether the dof has the row is the caller's business.
// docs/math/joint_constraints.md (J1-J7); the drive's law is constraint/drive.hpp's drive_law.
#pragma once

#include <limits>

#include "featherdrive/core/select.hpp"

namespace featherdrive::row_law {

/// Joint friction (J1): the impulse that would stop the joint is applied whole while it stays
/// within the static threshold; beyond it the accumulated friction is clamped to
/// dynamic + viscous |v|. recip = 1 / (r + cfm); static_, dynamic_ and viscous are per step (x dt).
template <class T>
T friction(T& accumulated, const T& v, const T& recip, const T& static_, const T& dynamic_,
           const T& viscous) {
  const T stopping = accumulated - v * recip;
  const T bound = dynamic_ + viscous * magnitude(v);
  const T next = select(static_ < magnitude(stopping), clamp_select(stopping, -bound, bound), stopping);
  const T delta = next - accumulated;
  accumulated = next;
  return delta;
}

/// Where in the step a position limit is solved.
struct LimitPhase {
  double h = 0.0;                  ///< the step of one solve: tau (PGS) or rho (TGS)
  double recip_h = 0.0;            ///< 1 / h (PhysX's recipDt: a product, not a division)
  double erp = 0.8;                ///< share of a violation corrected per (sub-)step
  bool velocity_iteration = false; ///< no Baumgarte correction in velocity iterations
};

/// The position limit (J2-J4): speculative (acts when the limit would be crossed by the end of the
/// (sub-)step), with Baumgarte correction of a violation in position iterations, and separately
/// accumulated one-signed impulses low >= 0 and high <= 0. error_low = x0 - lower,
/// error_high = upper - x0, dx the position change accumulated over TGS sub-steps (0 in PGS).
template <class T>
T limit(T& low, T& high, const T& v, const T& recip, const T& error_low, const T& error_high,
        const T& dx, const LimitPhase& phase) {
  const T zero(0.0), h(phase.h), recip_h(phase.recip_h), erp(phase.erp);
  const T future = dx + v * h;
  const T low_now = error_low + dx, low_next = error_low + future;
  const T high_now = error_high - dx, high_next = error_high - future;
  const auto low_case = (low_now < zero) | (low_next < zero);
  const auto high_case = (high_now < zero) | (high_next < zero);
  // Beyond the lower limit (hold it, or pull back by erp of the violation) or about to cross it
  // (arrive exactly at it); likewise the upper.
  const T hold_low = phase.velocity_iteration ? v : -low_now * recip_h * erp;
  const T target_low = select(low_now < zero, hold_low, -low_now * recip_h);
  const T push_low = low + (target_low - v) * recip;
  const T delta_low = select(push_low < zero, zero, push_low) - low;
  const T hold_high = phase.velocity_iteration ? v : high_now * recip_h * erp;
  const T target_high = select(high_now < zero, hold_high, high_now * recip_h);
  const T push_high = high + (target_high - v) * recip;
  const T delta_high = select(zero < push_high, zero, push_high) - high;
  // Inside both: a limit that pushed in an earlier iteration gives back what it overshot, at most
  // down to zero velocity and zero accumulated impulse (the low side when moving up).
  const T to_rest = -v * recip;
  const T back_low = select(to_rest < -low, -low, to_rest);
  const T back_high = select(-high < to_rest, -high, to_rest);
  const auto inside = !(low_case | high_case);
  const auto on_low = low_case | (inside & (zero < v));
  const T d_low = select(low_case, delta_low, back_low);
  const T d_high = select(high_case, delta_high, back_high);
  low = select(on_low, low + d_low, low);
  high = select(on_low, high, high + d_high);
  return select(on_low, d_low, d_high);
}

/// limit_may_act's terms that do not depend on v: the joint is past a limit, or an earlier
/// iteration of the step left an impulse. Where no lane has them, a solver that knows so may test
/// limit_crossing alone.
template <class T>
auto limit_held(const T& low, const T& high, const T& error_low, const T& error_high,
                const T& dx) {
  const T zero(0.0);
  return ((error_low + dx < zero) | (error_high - dx < zero)) | ((low != zero) | (high != zero));
}
/// limit_may_act's terms in v: the joint would cross a limit by the end of the (sub-)step.
template <class T>
auto limit_crossing(const T& v, const T& error_low, const T& error_high, const T& dx,
                    const LimitPhase& phase) {
  const T zero(0.0);
  const T future = dx + v * T(phase.h);
  return (error_low + future < zero) | (error_high - future < zero);
}
/// Where limit() can change anything: the joint is past a limit or would cross one by the end of
/// the (sub-)step, or an earlier iteration of the step left an impulse. Elsewhere limit() gives
/// -0 or +0 and leaves low and high as they are (J4 with l = u = 0), which changes no sum it
/// enters, so a solver may skip it.
template <class T>
auto limit_may_act(const T& low, const T& high, const T& v, const T& error_low,
                   const T& error_high, const T& dx, const LimitPhase& phase) {
  return limit_held(low, high, error_low, error_high, dx) |
         limit_crossing(v, error_low, error_high, dx, phase);
}

/// The step's velocity scale (joint_constraints.md, "Velocity limits"): ratio lowered to
/// max_velocity / |v| where the dof is beyond its limit and that is lower (std::min's choice).
/// Where it is not beyond, the quotient (inf or NaN at v = 0) is never chosen.
template <class T>
T velocity_scale(const T& ratio, const T& v, const T& max_velocity) {
  const T speed = magnitude(v);
  const T candidate = max_velocity / speed;
  return select((max_velocity < speed) & (candidate < ratio), candidate, ratio);
}

/// The joint velocity limit (J5): back to +-max_velocity when beyond it, else nothing.
template <class T>
auto beyond(const T& v, const T& max_velocity) {
  return (max_velocity < v) | (v < -max_velocity);
}
template <class T>
T velocity_limit(T& accumulated, const T& v, const T& recip, const T& max_velocity) {
  const auto beyond = row_law::beyond(v, max_velocity);
  const T delta = select(beyond, (clamp_select(v, -max_velocity, max_velocity) - v) * recip, T(0.0));
  accumulated = select(beyond, accumulated + delta, accumulated);
  return delta;
}

/// PhysX's older joint friction (frictionCoefficient, J6): the impulse that stops the joint, within
/// +-bound. applied is what the row had applied before this solve (its accumulator in PGS, 0 in
/// TGS, which re-applies it whole each solve); returns the new impulse.
template <class T>
T transmission_friction(const T& applied, const T& v, const T& recip, const T& bound) {
  return clamp_select(applied - v * recip, -bound, bound);
}

/// An actuator envelope's settings over T (ActuatorEnvelope's fields).
template <class T>
struct EnvelopeOf {
  T max_effort, max_actuator_velocity, speed_effort_gradient, velocity_dependent_resistance;
};

/// The drive's new accumulated impulse `unclamped` clamped to what the actuator envelope allows
/// (J7): the step's effort E = (lambda + external) / dt within
/// |E| <= max_effort - resistance |v| and |v| <= max_actuator_velocity - gradient |E|, at the
/// velocity v(lambda) = v + r (lambda - accumulated) the impulse leads to. The envelope only ever
/// scales the effort down, never reverses it; where no effort is available it gives none.
template <class T>
T envelope(const EnvelopeOf<T>& e, const T& unclamped, const T& accumulated, const T& v,
           const T& r, const T& external, double dt_step) {
  const T zero(0.0), dt(dt_step);
  // Both bounds are affine in lambda for the effort's sign s; in its direction s E >= 0.
  const T sign = select(unclamped + external >= zero, T(1.0), T(-1.0));
  // lambda between E = 0 and E_unclamped, then each constraint alpha lambda <= beta intersected.
  T lo = select(unclamped < -external, unclamped, -external);  // std::min(-external, unclamped)
  T hi = select(-external < unclamped, unclamped, -external);  // std::max(-external, unclamped)
  auto infeasible = zero < zero;
  const T v_free = v - r * accumulated;  // v(lambda) = v_free + r lambda
  const auto speed_bounded = e.max_actuator_velocity < T(std::numeric_limits<double>::infinity());
  auto add = [&](const T& alpha, const T& beta, const auto& active) {
    const T bound = beta / alpha;
    hi = select(active & (zero < alpha) & (bound < hi), bound, hi);
    lo = select(active & (alpha < zero) & (lo < bound), bound, lo);
    infeasible = infeasible | (active & (alpha == zero) & (beta < zero));
  };
  const auto always = zero == zero;
  for (const double vs_value : {1.0, -1.0}) {
    const T vs(vs_value);
    // s E + resistance (vs v) <= max_effort
    add(sign / dt + e.velocity_dependent_resistance * vs * r,
        e.max_effort - sign * external / dt - e.velocity_dependent_resistance * vs * v_free, always);
    // vs v + gradient s E <= max_actuator_velocity
    add(vs * r + e.speed_effort_gradient * sign / dt,
        e.max_actuator_velocity - vs * v_free - e.speed_effort_gradient * sign * external / dt,
        speed_bounded);
  }
  return select(infeasible | (hi < lo), -external, clamp_select(unclamped, lo, hi));
}

}  // namespace featherdrive::row_law
