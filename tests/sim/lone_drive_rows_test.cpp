// setup_rows sets up only the drive row of a dof whose only row is its drive, and sorts the dofs
// again when a setter changes what makes one (Simulation::row_kinds_changed_). A setter called
// between steps must act exactly as if it had been called before the first step.
#include <gtest/gtest.h>

#include <functional>
#include <limits>
#include <random>
#include <utility>
#include <vector>

#include "featherdrive/sim/simulation.hpp"
#include "support/models.hpp"

namespace featherdrive {
namespace {

using Change = std::function<void(Simulation&)>;

Simulation driven_chain(SolverType solver) {
  SimulationOptions options;
  options.solver = solver;
  Simulation sim(test::make_planar_chain(4, 1.0, 0.3), options);
  for (int d = 0; d < 4; ++d)
    sim.set_drive(d, Drive{d == 2 ? DriveType::acceleration : DriveType::force, 400.0, 20.0,
                           std::numeric_limits<double>::infinity(), 0.3 * (d + 1), 0.0});
  return sim;
}

// Steps both `steps` times: the same bits in the state and every output force, step by step.
void expect_same_steps(Simulation& a, Simulation& b, int steps) {
  for (int k = 0; k < steps; ++k) {
    a.step();
    b.step();
    ASSERT_EQ(a.q(), b.q()) << "step " << k;
    ASSERT_EQ(a.qd(), b.qd()) << "step " << k;
    ASSERT_EQ(a.drive_force(), b.drive_force()) << "step " << k;
    ASSERT_EQ(a.limit_force(), b.limit_force()) << "step " << k;
    ASSERT_EQ(a.friction_force(), b.friction_force()) << "step " << k;
  }
}

// Steps with the change made after 5 steps, against a simulation that has it from the start and
// begins from the same state: the same bits.
void expect_as_if_set_first(SolverType solver, const Change& change) {
  Simulation late = driven_chain(solver);
  late.step(5);
  change(late);
  Simulation early = driven_chain(solver);
  change(early);
  early.set_q(late.q());
  early.set_qd(late.qd());
  expect_same_steps(late, early, 5);
}

class LoneDriveRows : public ::testing::TestWithParam<SolverType> {};

TEST_P(LoneDriveRows, SettersBetweenStepsActAsBeforeTheFirst) {
  const std::vector<std::pair<const char*, Change>> changes = {
      {"limits", [](Simulation& s) { s.set_joint_limits(1, -0.05, 0.05); }},
      {"friction", [](Simulation& s) { s.set_joint_friction(2, JointFriction{2.0, 1.5, 0.5}); }},
      {"max velocity", [](Simulation& s) { s.set_max_joint_velocity(0, 0.2); }},
      {"friction coefficient", [](Simulation& s) { s.set_friction_coefficient(3, 0.5); }},
      {"envelope", [](Simulation& s) { s.set_actuator_envelope(3, ActuatorEnvelope{5.0, 10.0, 0.1, 0.0}); }},
      {"no drive", [](Simulation& s) { s.set_drive(1, Drive{}); }},
      {"acceleration drive",
       [](Simulation& s) {
         Drive d = s.drive(0);
         d.type = DriveType::acceleration;
         s.set_drive(0, d);
       }},
      {"new gains and targets",
       [](Simulation& s) {
         Drive d = s.drive(3);
         d.stiffness = 900.0;
         d.target_position = -0.4;
         s.set_drive(3, d);
       }},
      {"limits set and removed",
       [](Simulation& s) {
         s.set_joint_limits(2, -0.01, 0.01);
         s.step();
         s.set_joint_limits(2, -std::numeric_limits<double>::infinity(),
                            std::numeric_limits<double>::infinity());
       }},
  };
  for (const auto& [name, change] : changes) {
    SCOPED_TRACE(name);
    expect_as_if_set_first(GetParam(), change);
  }
}

// A setter before every step makes every step set up every field: the same bits as the lone drive
// path.
TEST_P(LoneDriveRows, LoneDrivePathMatchesTheFullSetup) {
  Simulation lone = driven_chain(GetParam());
  Simulation full = driven_chain(GetParam());
  const double inf = std::numeric_limits<double>::infinity();
  for (int k = 0; k < 20; ++k) {
    full.set_joint_limits(0, -inf, inf);  // marks the row kinds changed
    lone.step();
    full.step();
    ASSERT_EQ(lone.q(), full.q()) << "step " << k;
    ASSERT_EQ(lone.qd(), full.qd()) << "step " << k;
    ASSERT_EQ(lone.drive_force(), full.drive_force()) << "step " << k;
  }
}

// With every row a lone drive's, PGS solves them with solve_lone_drive_pgs and leaves runs of only
// children in detail::SweepLeaving::leave_run's tight loop. A velocity limit that never binds puts every dof
// on the general row law (solve_dof_rows) instead: the same bits, on a branching tree.
TEST(LoneDriveSweep, EqualsTheGeneralRowLawBitForBit) {
  std::mt19937 rng(11);
  const auto model = test::make_random_tree(21, 12, /*floating=*/false, /*spherical=*/false);
  const double inf = std::numeric_limits<double>::infinity();
  Simulation lone(model, SimulationOptions{});
  for (int d = 0; d < model->nv; ++d) {
    lone.set_drive(d, Drive{d % 3 == 1 ? DriveType::acceleration : DriveType::force, 300.0, 15.0,
                            inf, 0.2 * (d % 5) - 0.4, 0.0});
    lone.set_joint_limits(d, -inf, inf);
    lone.set_joint_friction(d, JointFriction{});
    lone.set_max_joint_velocity(d, inf);
  }
  lone.set_q(test::random_configuration(*model, rng));
  lone.set_qd(test::random_vector(model->nv, rng));
  Simulation general = lone;
  for (int d = 0; d < model->nv; ++d) general.set_max_joint_velocity(d, 1e30);
  expect_same_steps(lone, general, 50);
  EXPECT_EQ(general.velocity_limit_force(), VecX::Zero(model->nv));  // it never bound
}

INSTANTIATE_TEST_SUITE_P(Solvers, LoneDriveRows, ::testing::Values(SolverType::pgs, SolverType::tgs));

}  // namespace
}  // namespace featherdrive
