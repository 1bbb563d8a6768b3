// The joint spring, a row kind (row_kind.hpp): a passive spring and damper on a dof toward its
// reference position, MuJoCo's joint stiffness and springref, solved implicitly as a force drive
// with no bound that is always on beside the dof's own drive (docs/math/joint_constraints.md,
// JS1-JS4). This file is the whole kind; row_kinds.hpp lists it.
#pragma once

#include <array>
#include <cmath>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>

#include "featherdrive/constraint/drive.hpp"
#include "featherdrive/constraint/row_kind.hpp"
#include "featherdrive/core/format.hpp"

namespace featherdrive {

struct JointSpring {
  static constexpr std::string_view name = "joint_spring";
  static constexpr std::string_view force = "spring_force";
  enum Field { stiffness, damping, reference };
  static constexpr std::array<RowField, 3> fields{{
      {"stiffness", 0.0, "N/m or Nm/rad, >= 0"},
      {"damping", 0.0, "Ns/m or Nms/rad, >= 0"},
      {"reference", 0.0, "the position where the spring is at rest (m or rad)"},
  }};

  static void check(std::string_view joint, std::span<const double> v) {
    auto bad = [&](int f, const char* expected) {
      throw std::invalid_argument("joint spring of joint '" + std::string(joint) + "': " +
                                  std::string(fields[f].name) + " = " + format_double(v[f]) +
                                  " " + expected);
    };
    for (const int f : {stiffness, damping})
      if (!(std::isfinite(v[f]) && v[f] >= 0.0)) bad(f, "must be finite and >= 0");
    if (!std::isfinite(v[reference])) bad(reference, "must be finite");
  }
  static bool active(std::span<const double> v) {
    return v[stiffness] != 0.0 || v[damping] != 0.0;
  }

  // The row: a force drive's coefficients (drive.hpp's DriveRowOf) and its impulse.
  enum Slot { bias, velocity_multiplier, impulse_multiplier, bias_coefficient, position_bias,
              impulse, kSlots };
  static constexpr int kImpulse = impulse;

  /// JS2: drive_law::setup of a force drive (k, c, target reference, target velocity 0, no
  /// bound) with response r.
  template <class T, class Slots>
  static void setup(Slots& row, const std::array<T, 3>& v, const RowInputs<T>& in) {
    const T zero(0.0), inf(INFINITY);
    const DriveRowOf<T> d = drive_law::setup(
        DriveTermsOf<T>{v[stiffness], v[damping], v[reference], zero, inf, inf}, zero != zero,
        in.r, in.x0, in.h, in.dt, in.tgs);
    row[bias] = d.target_vel_plus_initial_bias;
    row[velocity_multiplier] = d.vel_multiplier;
    row[impulse_multiplier] = d.impulse_multiplier;
    row[bias_coefficient] = d.bias_coefficient;
    row[position_bias] = d.target_pos_bias;
    row[impulse] = zero;
  }

  /// JS3: the drive's update (eq. 18, TGS eq. 44); frozen in TGS's velocity iterations, as the
  /// drive is.
  template <class T, class Slots>
  static T solve(Slots& row, const T& v, const T& dx, const RowKindPhase& phase) {
    const T accumulated = row[impulse];
    if (phase.tgs && phase.velocity_iteration) return accumulated;
    const T inf(INFINITY);
    const DriveRowOf<T> d{row[bias], row[velocity_multiplier], row[impulse_multiplier],
                          row[bias_coefficient], row[position_bias], inf};
    return phase.tgs ? drive_law::impulse(d, v, accumulated, dx, T(phase.time_to_step_end))
                     : drive_law::impulse_pgs(d, v, accumulated);
  }

  /// JS4: the step guard's bracket (docs/math/step_guard.md, G-10 with the drive's kp, kd).
  static double guard_bracket(std::span<const double> v, double impulse_, double q0, double dq,
                              double h, double spring_credit) {
    const double k = v[stiffness], x = v[reference], q1 = q0 + dq;
    return impulse_ / h * dq + 0.5 * k * ((q1 - x) * (q1 - x) - (q0 - x) * (q0 - x)) +
           v[damping] * (dq / h) * dq - spring_credit * k * dq * dq;
  }
  static double damping_of(std::span<const double> v) { return v[damping]; }
};

}  // namespace featherdrive
