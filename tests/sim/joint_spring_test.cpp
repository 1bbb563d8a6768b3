// The joint spring, a row kind (constraint/joint_spring.hpp; docs/math/joint_constraints.md,
// JS1-JS4): against implicit-Euler recurrences written from the spec, beside a drive on the same
// dof, on spherical axes, in Batch's lanes against the scalar step, with the step guard, and the
// checks of its settings.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "featherdrive/constraint/spherical_axes.hpp"
#include "featherdrive/sim/batch.hpp"
#include "support/compare.hpp"
#include "support/drives.hpp"
#include "support/lanes.hpp"
#include "support/models.hpp"

namespace featherdrive {
namespace {

using test::kInf;

void set_spring(Simulation& sim, int dof, double k, double c, double reference) {
  const double values[] = {k, c, reference};
  sim.set_row_parameters("joint_spring", dof, values);
}

// A slider of mass m with a spring (k, c, reference x_s): each step is n implicit-Euler sub-steps
// toward x_s at rest (JS1), PGS (n = 1) and TGS; the reported force is the step's impulse / dt.
TEST(JointSpring, OneDofEqualsImplicitEulerSubsteps) {
  const double m = 1.7, tau = 0.01, k = 900.0, c = 12.0, xs = 0.3;
  auto model = test::make_slider(m, Vec3(0, 1, 0), Vec3(0, 0, -9.81));  // gravity across the axis
  for (SolverType solver : {SolverType::pgs, SolverType::tgs}) {
    for (int n : {1, 4, 16}) {
      SimulationOptions o;
      o.dt = tau;
      o.solver = solver;
      o.position_iterations = n;
      o.velocity_iterations = 0;
      Simulation sim(model, o);
      set_spring(sim, 0, k, c, xs);
      sim.set_qd(VecX::Constant(1, -0.8));
      test::OneDofState s{0.0, -0.8};
      for (int step = 0; step < 300; ++step) {
        sim.step();
        // PGS solves the whole step at once however many iterations: one implicit-Euler step.
        const int substeps = solver == SolverType::tgs ? n : 1;
        const double impulse = test::tgs_one_dof_step(s, m, k, c, xs, 0.0, 0.0, tau, substeps);
        ASSERT_NEAR(sim.q()[0], s.x, 1e-12) << to_string(solver) << " n " << n << " step " << step;
        ASSERT_NEAR(sim.qd()[0], s.v, 1e-12) << to_string(solver) << " n " << n << " step " << step;
        ASSERT_NEAR(sim.row_force("joint_spring")[0], impulse / tau,
                    1e-9 * (1 + std::abs(impulse / tau)));
        ASSERT_EQ(sim.drive_force()[0], 0.0);
      }
    }
  }
}

// A spring beside a force drive on one dof: Gauss-Seidel over the two rows converges to one
// implicit-Euler step with both springs and dampers, (m + dt (c + kd) + dt^2 (k + kp)) v1 =
// m v0 - dt (k (x0 - x_s) + kp (x0 - x_T)) + dt kd v_T.
TEST(JointSpring, BesideADriveConvergesToBothImplicitly) {
  const double m = 2.0, dt = 0.01, k = 400.0, c = 5.0, xs = -0.2;
  const double kp = 250.0, kd = 8.0, xT = 0.5, vT = 0.3;
  auto model = test::make_slider(m, Vec3(1, 0, 0), Vec3(0, 0, 0));
  SimulationOptions o;
  o.dt = dt;
  o.position_iterations = 200;
  o.velocity_iterations = 0;
  Simulation sim(model, o);
  set_spring(sim, 0, k, c, xs);
  sim.set_drive(0, Drive{DriveType::force, kp, kd, kInf, xT, vT});
  double x = 0.0, v = 0.4;
  sim.set_qd(VecX::Constant(1, v));
  for (int step = 0; step < 100; ++step) {
    sim.step();
    const double v1 = (m * v - dt * (k * (x - xs) + kp * (x - xT)) + dt * kd * vT) /
                      (m + dt * (c + kd) + dt * dt * (k + kp));
    const double spring_impulse = -dt * (k * (x + dt * v1 - xs) + c * v1);
    v = v1;
    x += dt * v1;
    ASSERT_NEAR(sim.q()[0], x, 1e-12) << step;
    ASSERT_NEAR(sim.qd()[0], v, 1e-12) << step;
    ASSERT_NEAR(sim.row_force("joint_spring")[0], spring_impulse / dt, 1e-8) << step;
  }
}

// On a tree whose only rows are springs, each spring is the force drive toward its reference with
// no bound (JS2-JS3) that the drive tests check against the spec: revolute and prismatic joints,
// PGS and TGS, fixed and floating roots. (A spherical axis's drive takes its error from the
// rotation, its spring from the axis's position: the next test.)
TEST(JointSpring, IsTheUnboundedForceDriveTowardItsReference) {
  for (const bool floating : {false, true})
    for (SolverType solver : {SolverType::pgs, SolverType::tgs}) {
      auto model = test::make_random_tree(7, 10, floating, false, 0.01);
      const SimulationOptions o = test::lane_test_options(solver);
      Simulation springs(model, o), drives(model, o);
      std::mt19937 rng(3);
      std::uniform_real_distribution<double> u(-1.0, 1.0);
      int sprung = 0;
      for (int d = 0; d < model->nv; ++d) {
        if (!dof_has_rows(*model, d)) continue;
        const double k = 200.0 + 100.0 * u(rng), c = 4.0 + 2.0 * u(rng), xs = 0.5 * u(rng);
        set_spring(springs, d, k, c, xs);
        drives.set_drive(d, Drive{DriveType::force, k, c, kInf, xs, 0.0});
        ++sprung;
      }
      ASSERT_GT(sprung, 5);
      std::mt19937 state(11);
      const VecX q = test::random_configuration(*model, state);
      springs.set_q(q);
      drives.set_q(q);
      for (int step = 0; step < 300; ++step) {
        springs.step();
        drives.step();
      }
      const std::string what = std::string(floating ? "floating " : "fixed ") + to_string(solver);
      EXPECT_LE(test::relative_difference(springs.q(), drives.q()), 1e-12) << what;
      EXPECT_LE(test::relative_difference(springs.qd(), drives.qd()), 1e-12) << what;
      EXPECT_LE(test::relative_difference(springs.row_force("joint_spring"), drives.drive_force()),
                1e-10)
          << what;
    }
}

// On a spherical joint's axis the spring pulls the axis's position (PhysX's twist or swing angle,
// the one its limits bound) toward the reference: one step of an isotropic rotor turned about one
// axis is I v1 = h (k (x_s - x0 - h v1) - c v1) about that axis alone.
TEST(JointSpring, OnASphericalAxisPullsItsPosition) {
  const double I = 0.1, k = 50.0, c = 2.0, h = 1.0 / 60.0, xs = 0.4;
  ModelBuilder b;
  b.set_gravity(Vec3::Zero());
  b.add_link(make_link("base", "", 1.0, Vec3::Zero(), Mat3::Identity(), fixed_joint("fix")));
  b.add_link(make_link("rotor", "base", 2.0, Vec3::Zero(), I * Mat3::Identity(),
                       spherical_joint("ball", Vec3(0, 0, 1), Vec3(0.3, -0.2, 0.5))));
  auto model = std::make_shared<const Model>(b.build());
  for (const SolverType solver : {SolverType::pgs, SolverType::tgs})
    for (int axis = 0; axis < 3; ++axis) {
      SimulationOptions o;
      o.solver = solver;
      o.position_iterations = solver == SolverType::tgs ? 1 : 4;
      Simulation sim(model, o);
      const Quat turn(Eigen::AngleAxisd(-0.3, Vec3::Unit(axis)));
      VecX q = sim.q();
      q.segment<4>(0) << turn.w(), turn.x(), turn.y(), turn.z();
      sim.set_q(q);
      const char* names[] = {"ball:twist", "ball:swing1", "ball:swing2"};
      const double values[] = {k, c, xs};
      sim.set_row_parameters("joint_spring", names[axis], values);
      const double x0 = spherical_joint_positions(turn)[axis];
      sim.step();
      const double v1 = h * k * (xs - x0) / (I + h * h * k + h * c);
      EXPECT_NEAR(sim.qd()[axis], v1, 1e-12) << to_string(solver) << " axis " << axis;
      EXPECT_NEAR(sim.qd().norm(), std::abs(v1), 1e-12);
      EXPECT_NEAR(sim.row_force("joint_spring")[axis], I * v1 / h, 1e-9);
    }
}

// Springs beside drives (force and acceleration), limits and viscous friction on random trees
// with two spherical joints, fixed and floating (compat none and physx), in Batch's lanes against
// the scalar step over 1000 steps (issue 32's criterion, tests/support/lanes.hpp).
TEST(JointSpring, LanesAsAlone) {
  struct Case {
    bool floating;
    Compat compat;
  };
  for (const Case c : {Case{false, Compat::none}, Case{true, Compat::none},
                       Case{true, Compat::physx}})
    for (SolverType solver : {SolverType::pgs, SolverType::tgs}) {
      // compat physx, whose rows see the link bias and TGS's tracked motion: TGS (the test's
      // time is mostly the nine scalar runs of that case).
      if (c.compat == Compat::physx && solver == SolverType::pgs) continue;
      const bool floating = c.floating;
      std::shared_ptr<const Model> model;
      for (unsigned seed = 1; !model; ++seed) {
        auto m = test::make_random_tree(seed, 9, floating, true, 0.01);
        int balls = 0;
        for (const Link& l : m->links) balls += l.joint_type == JointType::spherical;
        if (balls >= 2) model = m;
      }
      SimulationOptions options = test::lane_test_options(solver);
      options.compat = c.compat;
      if (c.compat == Compat::physx) {  // a free fall is ill-conditioned under compat physx
        auto still = std::make_shared<Model>(*model);  // (lane_spherical_test.cpp)
        still->gravity.setZero();
        model = still;
      }
      Simulation sim(model, options);
      std::mt19937 rng(17);
      std::uniform_real_distribution<double> u(-1.0, 1.0);
      int sprung = 0;
      for (int d = 0; d < model->nv; ++d) {
        if (!dof_has_rows(*model, d)) continue;
        sim.set_drive(d, Drive{d % 4 == 1 ? DriveType::acceleration : DriveType::force, 200.0,
                               15.0, kInf, 0.5 * u(rng), 0.2 * u(rng)});
        if (d % 2 == 0) {
          set_spring(sim, d, 150.0 + 50.0 * u(rng), 3.0, 0.3 * u(rng));
          ++sprung;
        }
        if (d % 3 == 0) sim.set_joint_limits(d, -1.2, 1.3);
        sim.set_joint_friction(d, JointFriction{0.0, 0.0, 0.2});
      }
      ASSERT_GE(sprung, 4);
      sim.set_qd(test::random_vector(model->nv, rng, 0.5));
      test::expect_lanes_as_alone(sim, 1000,
                                  std::string("springs, ") + (floating ? "floating " : "fixed ") +
                                      to_string(solver) + ", compat " + to_string(c.compat));
    }
}

// A floating tree with spherical joints, a mimic pair and springs of its own in every environment:
// the same bits, q, qd and the springs' forces, at every SIMD width the CPU has, in calls of any
// size (docs/simd_batch.md: an environment's bits do not depend on the batch's layout).
TEST(JointSpring, SameBitsAtEveryWidth) {
  std::shared_ptr<const Model> model;
  for (unsigned seed = 1; !model; ++seed) {
    auto m = test::make_random_tree(seed, 9, true, true, 0.01);
    int balls = 0, one_dof = 0;
    for (const Link& l : m->links) {
      balls += l.joint_type == JointType::spherical;
      one_dof += l.nv == 1;
    }
    if (balls >= 1 && one_dof >= 2) model = m;
  }
  Simulation sim(model, test::lane_test_options(SolverType::pgs));
  std::vector<int> one_dof, sprung;
  for (int d = 0; d < model->nv; ++d) {
    if (!dof_has_rows(*model, d)) continue;
    sim.set_drive(d, Drive{DriveType::force, 200.0, 15.0, kInf, 0.2, 0.0});
    sprung.push_back(d);
    if (model->links[model->dof_link[d]].nv == 1) one_dof.push_back(d);
  }
  sim.set_mimic_joints({MimicJoint{one_dof[1], one_dof[0], -0.5, 0.01}});
  sim.set_qd(VecX::Constant(model->nv, 0.3));
  const int n = 11;
  RowMatrix k = RowMatrix::Zero(n, model->nv);
  RowMatrix reference_position = RowMatrix::Zero(1, model->nv);  // a floating root's dofs: 0
  for (int d : sprung) reference_position(0, d) = -0.1;
  for (int e = 0; e < n; ++e)
    for (int d : sprung) k(e, d) = e % 3 == 0 ? 0.0 : 50.0 + 20.0 * e + d;  // some without
  std::vector<int> all(n);
  for (int e = 0; e < n; ++e) all[static_cast<size_t>(e)] = e;
  auto run = [&](SimdIsa isa, int first_call) {
    Batch batch(sim, n);
    batch.set_isa(isa);
    batch.set_row_parameter("joint_spring", "stiffness", all, k);
    batch.set_row_parameter("joint_spring", "reference", all, reference_position);
    EXPECT_EQ(batch.step_path(), std::string(to_string(isa)) + " lanes");
    batch.step(first_call);
    for (int s = first_call; s < 100; ++s) batch.step(1);
    RowMatrix out(n, model->nq + 2 * model->nv);
    out << batch.q(), batch.qd(), batch.row_force("joint_spring");
    return out;
  };
  const RowMatrix reference = run(SimdIsa::sse2, 100);
  EXPECT_NE(reference.rightCols(model->nv).norm(), 0.0);
  for (SimdIsa isa : available_simd_isas())
    for (int first_call : {100, 37})
      EXPECT_TRUE(test::same_bits(run(isa, first_call), reference))
          << to_string(isa) << ", calls after " << first_call << " steps";
}

// The guard's energy test counts the spring's work and stored energy (JS4): a stiff implicit
// spring never creates energy, so the guard redoes no step of a pendulum held by one (started
// close enough to its reference that no step moves more than max_joint_step).
TEST(JointSpring, StepGuardCountsTheSpring) {
  auto model = test::make_pendulum(1.0, 0.5);
  SimulationOptions o;
  o.dt = 0.01;
  o.guard.enabled = true;
  Simulation sim(model, o);
  set_spring(sim, 0, 5e4, 0.0, 0.4);
  sim.set_q(VecX::Constant(1, 0.3));  // within max_joint_step of the reference
  for (int step = 0; step < 500; ++step) sim.step();
  EXPECT_EQ(sim.guard_triggers(), 0);
  EXPECT_TRUE(std::isfinite(sim.q()[0]));
}

// The reported force is the last step's: 0 once the spring is gone, and after a state whose
// forces were not (a step without kinds writes them once, then leaves the zeros alone).
TEST(JointSpring, TheForceIsTheLastSteps) {
  auto model = test::make_slider(1.0, Vec3(1, 0, 0), Vec3::Zero());
  Simulation sim(model);
  set_spring(sim, 0, 100.0, 0.0, 0.5);
  sim.step();
  const double first = sim.row_force("joint_spring")[0];
  EXPECT_GT(first, 0.0);
  const State with_force = sim.state();
  set_spring(sim, 0, 0.0, 0.0, 0.5);
  sim.step();
  EXPECT_EQ(sim.row_force("joint_spring")[0], 0.0);
  sim.set_state(with_force);
  EXPECT_EQ(sim.row_force("joint_spring")[0], first);
  sim.step(2);
  EXPECT_EQ(sim.row_force("joint_spring")[0], 0.0);
  // In a Batch's lanes too, environment by environment.
  set_spring(sim, 0, 100.0, 0.0, 0.5);
  Batch lanes(sim, 3);
  lanes.step(1);
  EXPECT_EQ(lanes.row_force("joint_spring")(1, 0), lanes.row_force("joint_spring")(0, 0));
  EXPECT_GT(lanes.row_force("joint_spring")(1, 0), 0.0);
  const RowMatrix none = RowMatrix::Zero(1, 1);
  const int second[] = {1};
  lanes.set_row_parameter("joint_spring", "stiffness", second, none);
  lanes.step(1);
  EXPECT_EQ(lanes.row_force("joint_spring")(1, 0), 0.0);
  EXPECT_GT(lanes.row_force("joint_spring")(0, 0), 0.0);
}

TEST(JointSpring, SettingsAreChecked) {
  auto model = test::make_random_tree(2, 6, true, true);
  Simulation sim(model);
  auto message = [&](auto&& f) {
    try {
      f();
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  int revolute = -1;
  for (int d = 0; d < model->nv; ++d)
    if (model->links[model->dof_link[d]].joint_type == JointType::revolute) revolute = d;
  ASSERT_GE(revolute, 0);
  const std::string joint = model->links[model->dof_link[revolute]].joint_name;
  EXPECT_EQ(message([&] { set_spring(sim, revolute, -1.0, 0.0, 0.0); }),
            "joint spring of joint '" + joint + "': stiffness = -1 must be finite and >= 0");
  EXPECT_EQ(message([&] { set_spring(sim, revolute, 1.0, NAN, 0.0); }),
            "joint spring of joint '" + joint + "': damping = nan must be finite and >= 0");
  EXPECT_EQ(message([&] { set_spring(sim, revolute, 1.0, 0.0, INFINITY); }),
            "joint spring of joint '" + joint + "': reference = inf must be finite");
  EXPECT_NE(message([&] { set_spring(sim, 0, 1.0, 0.0, 0.0); }).find("is floating"),
            std::string::npos);
  const double two[] = {1.0, 2.0};
  EXPECT_EQ(message([&] { sim.set_row_parameters("joint_spring", revolute, two); }),
            "joint_spring: expected 3 values, got 2");
  EXPECT_EQ(message([&] { sim.set_row_parameters("spring", revolute, two); }),
            "unknown row kind 'spring' (row kinds: joint_spring)");
  // Refused settings change nothing; Settings::validate refuses what the setter does.
  EXPECT_EQ(sim.row_parameters("joint_spring", revolute), (std::vector<double>{0.0, 0.0, 0.0}));
  Settings s = sim.settings();
  s.row_parameters(revolute, 0) = -2.0;
  EXPECT_EQ(message([&] { s.validate(*model); }),
            "joint spring of joint '" + joint + "': stiffness = -2 must be finite and >= 0");
}

}  // namespace
}  // namespace featherdrive
