// compat: physx, PhysX's two departures from textbook Gauss-Seidel (docs/math/physx_departures.md),
// against expectations derived independently of the implementation.
#include <gtest/gtest.h>

#include "featherdrive/algorithm/energy.hpp"
#include "featherdrive/algorithm/kinematics.hpp"
#include "featherdrive/sim/simulation.hpp"
#include "support/models.hpp"
#include "support/compare.hpp"

namespace featherdrive {
namespace {

using test::kInf;

// A slider on a spinning arm, no gravity: a revolute joint about z at the origin carries an arm
// (mass centre at (a, 0, 0)); a prismatic joint along x at (d, 0, 0) on the arm carries a block
// (mass centre at (e, 0, 0) in its frame). With the arm turning at w and the block at rest, PhysX's
// links after the free-velocity update carry dt times their centripetal accelerations,
// -w^2 (d + e) x for the block's centre and -w^2 a x for the arm's, which the row measures at the
// joint point with the arm's moved rigidly there: delta = -dt w^2 (d + e - a) along x.
TEST(PhysxDepartures, PrismaticRowOnSpinningArmSeesCentripetalDelta) {
  const double a = 0.2, d = 0.5, e = 0.1, w = 3.0, dt = 1.0 / 60.0, kd = 50.0;
  ModelBuilder b;
  b.set_gravity(Vec3::Zero());
  b.add_link(make_link("base", "", 1.0, Vec3::Zero(), Mat3::Identity() * 1e-2, fixed_joint("fix")));
  b.add_link(make_link("arm", "base", 2.0, Vec3(a, 0, 0), Vec3(0.01, 0.05, 0.05).asDiagonal(),
                       revolute_joint("spin", Vec3(0, 0, 1))));
  b.add_link(make_link("block", "arm", 0.7, Vec3(e, 0, 0), Vec3(0.002, 0.003, 0.003).asDiagonal(),
                       prismatic_joint("slide", Vec3(1, 0, 0), Vec3(d, 0, 0))));
  auto model = std::make_shared<const Model>(b.build());
  auto run = [&](Compat compat) {
    SimulationOptions o;
    o.dt = dt;
    o.position_iterations = 1;
    o.velocity_iterations = 0;
    o.compat = compat;
    Simulation sim(model, o);
    sim.set_drive("slide", Drive{DriveType::force, 0.0, kd, kInf, 0.0, 0.0});
    VecX qd = VecX::Zero(2);
    qd[0] = w;
    sim.set_qd(qd);
    sim.step();
    return sim;
  };
  const Simulation textbook = run(Compat::none), physx = run(Compat::physx);
  const int slide = model->dof_index("slide");
  // One damping row, one iteration: lambda = -kd dt v / (1 + kd dt r) for the velocity v it sees
  // (spec eq. 18 with kp = 0), r = (M^-1)_jj; compat shifts v by delta.
  const double r = physx.data().inverse_mass_diagonal[slide];
  const double delta = -dt * w * w * (d + e - a);
  const double expected = -kd * delta / (1.0 + kd * dt * r);
  EXPECT_NEAR(physx.drive_force()[slide] - textbook.drive_force()[slide], expected,
              1e-12 * std::abs(expected) + 1e-12);
  EXPECT_GT(std::abs(expected), 1e-2);
}

// A free-floating tree without gravity, its joints driven along sine targets: the drive impulses
// are internal, so the exact flow keeps the linear momentum and the angular momentum about the COM.
// compat physx imposes both (the angular one by magnitude) at the end of every step, so they hold to
// round-off over the trajectory; the textbook semi-implicit step drifts at O(dt^2) per step.
struct Momenta {
  Vec3 linear, angular_about_com;
};

Momenta momenta(const Simulation& sim) {
  Data data(sim.model());
  forward_kinematics(sim.model(), data, sim.q(), sim.qd());
  const Vec6 h = momentum(sim.model(), data);
  const Vec3 c = center_of_mass(sim.model(), data);
  return {h.tail<3>(), h.head<3>() - c.cross(h.tail<3>())};
}

std::pair<double, double> drift(Compat compat, SolverType solver) {
  Model zero_g = *test::make_random_tree(13, 10, true, /*spherical=*/false);
  zero_g.gravity = Vec3::Zero();
  auto model = std::make_shared<const Model>(zero_g);
  SimulationOptions o;
  o.solver = solver;
  o.compat = compat;
  Simulation sim(model, o);
  // Link damping and link velocity limits are external forces: off, so momentum has no source.
  for (int i = 0; i < model->num_links(); ++i) {
    LinkParameters p = sim.link_parameters(i);
    p.linear_damping = p.angular_damping = 0.0;
    p.max_linear_velocity = p.max_angular_velocity = kInf;
    sim.set_link_parameters(i, p);
  }
  VecX q = sim.q(), qd = sim.qd();
  for (const Link& l : model->links)
    if (l.nv == 1) {
      sim.set_joint_limits(l.v_index, -kInf, kInf);
      sim.set_max_joint_velocity(l.v_index, kInf);
      sim.set_joint_friction(l.v_index, JointFriction{});
      sim.set_drive(l.v_index, Drive{DriveType::force, 600, 20, kInf, 0.0, 0.0});
      q[l.q_index] = 0.3;
      qd[l.v_index] = -0.8;
    }
  qd.head<6>() << 0.5, -0.7, 1.1, 0.2, -0.1, 0.3;
  sim.set_q(q);
  sim.set_qd(qd);
  const Momenta m0 = momenta(sim);
  double linear = 0.0, angular = 0.0;
  for (int k = 0; k < 300; ++k) {
    for (const Link& l : model->links)
      if (l.nv == 1) sim.set_drive_target(l.v_index, 0.4 * std::sin(0.1 * k + l.v_index), 0.0);
    sim.step();
    const Momenta m = momenta(sim);
    linear = std::max(linear, (m.linear - m0.linear).norm() / m0.linear.norm());
    angular = std::max(angular, std::abs(m.angular_about_com.norm() - m0.angular_about_com.norm()) /
                                    m0.angular_about_com.norm());
  }
  return {linear, angular};
}

TEST(PhysxDepartures, FloatingTreeKeepsMomentumToRoundOff) {
  for (SolverType solver : {SolverType::pgs, SolverType::tgs}) {
    const auto [linear, angular] = drift(Compat::physx, solver);
    EXPECT_LT(linear, 1e-12) << to_string(solver);
    EXPECT_LT(angular, 1e-12) << to_string(solver);
    // The textbook step does not: the same run drifts visibly.
    const auto [linear_textbook, angular_textbook] = drift(Compat::none, solver);
    EXPECT_GT(std::max(linear_textbook, angular_textbook), 1e-6) << to_string(solver);
  }
}

// The random tree has prismatic joints on moving parents: compat physx changes its motion, compat
// none is the textbook step the rest of the suite checks.
TEST(PhysxDepartures, CompatChangesTreesWithPrismaticJointsOnMovingParents) {
  auto model = test::make_random_tree(7, 9, false, false);
  auto run = [&](Compat compat) {
    SimulationOptions o;
    o.compat = compat;
    Simulation sim(model, o);
    for (const Link& l : model->links)
      if (l.nv == 1) sim.set_drive(l.v_index, Drive{DriveType::force, 300, 10, kInf, 0.2, 0.0});
    sim.set_qd(VecX::Constant(model->nv, 1.5));
    sim.step(50);
    return VecX(sim.qd());  // a copy: sim.qd() is a view of sim, which dies here
  };
  EXPECT_GT((run(Compat::none) - run(Compat::physx)).norm(), 1e-9);
}

}  // namespace
}  // namespace featherdrive
