// The rows of one dof solved in PhysX's order, written once over the number type: the scalar
// step's solve_all_dof_rows (dof_rows.cpp, T = double) and the SIMD lanes' solve_row
// (sim/simd_lane_step.hpp, T a pack of environments) both run row_sequence::solve.
// docs/math/joint_constraints.md; docs/architecture.md, "Where each row kind lives".
#pragma once

#include "featherdrive/constraint/drive.hpp"
#include "featherdrive/constraint/row_kinds.hpp"
#include "featherdrive/constraint/row_laws.hpp"
#include "featherdrive/core/select.hpp"

namespace featherdrive::row_sequence {

/// The rows a dof may have, in the order they are solved.
enum class Row { transmission_friction, drive, friction, limit, velocity_limit };

/// Where in the step the rows are solved (RowPhase's part the laws read; one value for all lanes).
struct Phase {
  bool tgs = false;
  bool velocity_iteration = false;
  double time_to_step_end = 0.0;  ///< TGS: tau - i rho (eq. 41)
  row_law::LimitPhase limit;
};

/// Every row of one dof at joint velocity v, dx its TGS position change (0 in PGS): transmitted-
/// force friction, the drive (clipped by the dof's envelope or actuator), the row kinds
/// (row_kinds.hpp, in RowKinds' order), friction, the position limit, the velocity limit. Each sees the velocity the one before left; returns the dof's
/// impulse change. Rows is the dof's rows over T (a double, or a pack and its mask M):
///   bool any(Row)   some lane has the row (the row is skipped otherwise);
///   bool all(Row)   every lane has it (no select needed; drive and friction ask);
///   M has(Row)      the lanes that have it;
///   bool any_of(M)  some lane's mask is set;
///   optionally bool limit_may_act(low, high, v, dx, limit phase): any_of(row_law::limit_may_act)
///     by the Rows' own means (the lanes': knowing where limit_held is false);
///   T response(), recip(): r and 1 / (r + cfm);
///   the row's accumulators as T& and its coefficients (tf_*, drive(), drive_impulse(),
///   friction_*, low(), high(), error_low(), error_high(), max_velocity(), velocity_limit());
///   T clip_drive(next, accumulated, v, dx): the envelope's and the actuator's clips;
///   bool any_kinds(), any_kind(i)   some lane has a row kind (kind i);
///   M has_kind(i)                   the lanes that have kind i;
///   kind_slots(offset)              a kind's row (T& operator[](int)), from its slot offset.
/// A lane without a row keeps total and v exactly (a select, not + 0), so its bits do not depend
/// on whether a neighbour has that row.
template <class T, class Rows>
T solve(Rows& rows, T v, const T& dx, const Phase& phase) {
  const T zero(0.0);
  T total = zero;
  const T r = rows.response();
  auto apply = [&](const auto& present, const T& delta) {
    total = select(present, total + delta, total);
    v = select(present, v + r * delta, v);
  };
  auto apply_all = [&](const T& delta) {  // apply where every lane has the row: no select
    total = total + delta;
    v = v + r * delta;
  };
  const T recip = rows.recip();
  if (rows.any(Row::transmission_friction)) {
    // PhysX re-applies it whole in every TGS solve (solveInternalJointConstraintRecursive).
    const auto transmitting = rows.has(Row::transmission_friction);
    const T applied = phase.tgs ? zero : rows.tf_impulse();
    const T next = row_law::transmission_friction(applied, v, recip, rows.tf_bound());
    rows.tf_impulse() = select(transmitting, next, rows.tf_impulse());
    rows.tf_applied() =
        select(transmitting, rows.tf_applied() + (next - applied), rows.tf_applied());
    apply(transmitting, next - applied);
  }
  if (rows.any(Row::drive) && !(phase.tgs && phase.velocity_iteration)) {  // TGS freezes it
    const T accumulated = rows.drive_impulse();
    T next = phase.tgs ? drive_law::impulse(rows.drive(), v, accumulated, dx,
                                            T(phase.time_to_step_end))
                       : drive_law::impulse_pgs(rows.drive(), v, accumulated);
    next = rows.clip_drive(next, accumulated, v, dx);
    const T delta = next - accumulated;
    if (rows.all(Row::drive)) {
      rows.drive_impulse() = next;
      apply_all(delta);
    } else {
      const auto driven = rows.has(Row::drive);
      rows.drive_impulse() = select(driven, next, accumulated);
      apply(driven, delta);
    }
  }
  if (rows.any_kinds()) {
    const RowKindPhase kind_phase{phase.tgs, phase.velocity_iteration, phase.time_to_step_end};
    RowKinds::for_each([&]<class E>(E, int, int slot) {
      if (!rows.any_kind(E::index)) return;
      const auto present = rows.has_kind(E::index);
      auto row = rows.kind_slots(slot);
      apply(present, solve_row_kind<typename E::Kind>(row, present, v, dx, kind_phase));
    });
  }
  if (rows.any(Row::friction)) {
    T impulse = rows.friction_impulse();
    const T delta = row_law::friction(impulse, v, recip, rows.friction_static(),
                                      rows.friction_dynamic(), rows.friction_viscous());
    if (rows.all(Row::friction)) {
      rows.friction_impulse() = impulse;
      apply_all(delta);
    } else {
      const auto rubbing = rows.has(Row::friction);
      rows.friction_impulse() = select(rubbing, impulse, rows.friction_impulse());
      apply(rubbing, delta);
    }
  }
  if (rows.any(Row::limit)) {
    T low = rows.low(), high = rows.high();
    // Far inside both limits with nothing accumulated the law changes nothing (J4).
    bool may_act;
    if constexpr (requires { rows.limit_may_act(low, high, v, dx, phase.limit); })
      may_act = rows.limit_may_act(low, high, v, dx, phase.limit);  // the Rows' own test of it
    else
      may_act = rows.any_of(row_law::limit_may_act(low, high, v, rows.error_low(),
                                                   rows.error_high(), dx, phase.limit));
    if (may_act) {
      const auto limited = rows.has(Row::limit);
      const T delta = row_law::limit(low, high, v, recip, rows.error_low(), rows.error_high(), dx,
                                     phase.limit);
      rows.low() = select(limited, low, rows.low());
      rows.high() = select(limited, high, rows.high());
      apply(limited, delta);
    }
  }
  if (rows.any(Row::velocity_limit)) {
    const auto beyond = row_law::beyond(v, rows.max_velocity());
    if (rows.any_of(beyond)) {  // the law changes nothing on a lane within its limit
      T impulse = rows.velocity_limit();
      apply(beyond, row_law::velocity_limit(impulse, v, recip, rows.max_velocity()));
      rows.velocity_limit() = impulse;
    }
  }
  return total;
}

}  // namespace featherdrive::row_sequence
