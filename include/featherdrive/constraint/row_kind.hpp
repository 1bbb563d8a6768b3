// What a row kind is: one dof's row added to the step in one file (docs/architecture.md, "Adding
// a row kind"). A kind K declares its settings as named per-dof fields, its check, its per-step
// row as slots over the number type, and its set-up and solve over that type. The step (the
// scalar step for double, Batch's lanes for packs), Settings, the checkpoint, the scene reader and
// the C++ and Python faces read kinds only through this interface and the list in row_kinds.hpp.
// docs/math/joint_constraints.md ("Row kinds").
#pragma once

#include <array>
#include <span>
#include <string_view>

#include "featherdrive/core/select.hpp"

namespace featherdrive {

/// One per-dof setting of a row kind: its name (the key in a scene, a checkpoint and the faces),
/// the value a dof has by default (the row then does nothing), and a one-line description.
struct RowField {
  std::string_view name;
  double default_value = 0.0;
  std::string_view doc;
};

/// What a kind's set-up reads besides its settings, per dof and (sub)step.
template <class T>
struct RowInputs {
  T r;        ///< the dof's unit response (M^-1)_jj
  T r_cfm;    ///< r + the link's cfm (joint_constraints.md, J8)
  T x0;       ///< the dof's position at the step's start (a spherical axis's, PhysX's)
  double h;   ///< the step of one solve: tau (PGS) or rho = tau / n (TGS)
  double dt;  ///< the whole step tau
  bool tgs;
};

/// Where in the step a kind's row is solved (one value for all lanes).
struct RowKindPhase {
  bool tgs = false;
  bool velocity_iteration = false;
  double time_to_step_end = 0.0;  ///< TGS: tau - i rho (eq. 41)
};

// A row kind K provides (constraint/joint_spring.hpp is one):
//   static constexpr std::string_view name;          "joint_spring"
//   static constexpr std::string_view force;         its output: "spring_force", impulse / dt
//   static constexpr std::array<RowField, N> fields;
//   static void check(std::string_view joint, std::span<const double> values);
//       throws std::invalid_argument naming the joint, the field and the value (the step has
//       checked that the dof carries rows: revolute, prismatic, a spherical axis);
//   static bool active(std::span<const double> values);   whether the dof has the row
//   static constexpr int kSlots; static constexpr int kImpulse;
//       its per-step row: kSlots numbers, slot kImpulse its impulse accumulated over the step;
//   template <class T, class Slots>
//   static void setup(Slots& row, const std::array<T, N>& values, const RowInputs<T>& in);
//       writes every slot (the impulse 0); Slots: T& operator[](int);
//   template <class T, class Slots>
//   static T solve(Slots& row, const T& v, const T& dx, const RowKindPhase&);
//       the new accumulated impulse at joint velocity v and TGS position change dx (0 in PGS);
//       it chooses only through select (core/select.hpp), so a lane runs what a lone dof runs;
//   static double guard_bracket(std::span<const double> values, double impulse, double q0,
//                               double dq, double h, double spring_credit);
//       the step guard's eq. (G-10) for the row: its work beyond what it stores and dissipates,
//       less spring_credit times its stiffness dq^2 (G-11; 0 in PGS);
//   static double damping_of(std::span<const double> values);   its damper c (G-7), 0 for none.
// The step solves the kinds after the drive, in the list's order, each where it is active; a lane
// without the row keeps its velocity and the row's impulse bit for bit.

/// The row kinds in the order the step solves them, with each one's place in the flat per-dof
/// arrays: its first field in Settings::row_parameters' columns, its first slot in a dof's rows.
template <class... Kinds>
struct RowKindList {
  static constexpr int size = sizeof...(Kinds);
  static constexpr int fields = (0 + ... + static_cast<int>(Kinds::fields.size()));
  static constexpr int slots = (0 + ... + Kinds::kSlots);

  template <int I, class K>
  struct Entry {
    using Kind = K;
    static constexpr int index = I;
  };

  /// f(Entry<i, K>{}, field_offset, slot_offset) for each kind K, in order.
  template <class F>
  static constexpr void for_each(F&& f) {
    visit<0, 0, 0, Kinds...>(f);
  }

 private:
  template <int I, int Field, int Slot, class K, class... Rest, class F>
  static constexpr void visit(F& f) {
    f(Entry<I, K>{}, Field, Slot);
    if constexpr (sizeof...(Rest) > 0)
      visit<I + 1, Field + static_cast<int>(K::fields.size()), Slot + K::kSlots, Rest...>(f);
  }
  template <int I, int Field, int Slot, class F>
  static constexpr void visit(F&) {}
};

/// One solve of a kind's row at joint velocity v: returns the impulse change; the accumulated
/// impulse moves only where `present` holds (elsewhere it keeps its bits, and the caller adds the
/// change nowhere).
template <class K, class T, class Slots, class Mask>
T solve_row_kind(Slots& row, const Mask& present, const T& v, const T& dx,
                 const RowKindPhase& phase) {
  const T before = row[K::kImpulse];
  const T next = K::solve(row, v, dx, phase);
  row[K::kImpulse] = select(present, next, before);
  return next - before;
}

}  // namespace featherdrive
