// PhysX's per-link and per-joint parameters (link_parameters.hpp) against expectations derived by
// hand from the 1-dof formulas (docs/math/joint_constraints.md), and Compat::physx's defaults.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>

#include "featherdrive/sim/simulation.hpp"
#include "support/models.hpp"
#include "support/compare.hpp"

namespace featherdrive {
namespace {

using test::kInf;

SimulationOptions options(SolverType solver, int position_iterations, int velocity_iterations,
                          double dt = 1.0 / 60.0) {
  SimulationOptions o;
  o.solver = solver;
  o.position_iterations = position_iterations;
  o.velocity_iterations = velocity_iterations;
  o.dt = dt;
  return o;
}

LinkParameters cfm_only(double scale) {
  LinkParameters p;
  p.cfm_scale = scale;
  return p;
}

// A slider of mass m on a fixed base: r = 1/m, and its link's linear response at the centre of
// mass is 1/m along the axis, 0 across it, so cfm = s / m and r + cfm = (1 + s) / m. One PGS
// iteration of an acceleration drive (eq. 35-37 with 1/(r + cfm)) gives
//   v1 = v0 + (dt kp (xT - x0) + dt kd vT - a v0) / ((1 + a)(1 + s)),  a = dt (dt kp + kd);
// iterated to convergence, the fixed point of lambda = x (c - a v(lambda)) / (r + cfm) + (1 - x) lambda
// is v = v0 + (c - a v0) / (1 + a + s).
TEST(PhysxParameters, AccelerationDriveWithCfmMatchesTheOneDofFormula) {
  const double m = 1.7, s = 0.2, kp = 200.0, kd = 15.0, xT = 0.5, vT = 0.3, dt = 1.0 / 60.0;
  const double x0 = 0.1, v0 = -0.4;
  auto model = test::make_slider(m, Vec3(1, 0, 0), Vec3(0, 0, -9.81));  // gravity across the axis
  const double a = dt * (dt * kp + kd);
  const double c = dt * kp * (xT - x0) + dt * kd * vT;
  for (int iterations : {1, 200}) {
    Simulation sim(model, options(SolverType::pgs, iterations, 0));
    sim.set_link_parameters("slider", cfm_only(s));
    sim.set_drive("slide", Drive{DriveType::acceleration, kp, kd, kInf, xT, vT});
    sim.set_q(VecX::Constant(1, x0));
    sim.set_qd(VecX::Constant(1, v0));
    sim.step();
    const double expected = iterations == 1 ? v0 + (c - a * v0) / ((1.0 + a) * (1.0 + s))
                                            : v0 + (c - a * v0) / (1.0 + a + s);
    EXPECT_NEAR(sim.qd()[0], expected, 1e-12) << iterations << " iterations";
    EXPECT_NEAR(sim.q()[0], x0 + dt * expected, 1e-12);
  }
  // A force drive ignores cfm: the same step as without it.
  Simulation with(model, options(SolverType::pgs, 4, 1)), without(model, options(SolverType::pgs, 4, 1));
  with.set_link_parameters(1, cfm_only(0.9));
  for (Simulation* sim : {&with, &without}) {
    sim->set_drive("slide", Drive{DriveType::force, kp, kd, kInf, xT, vT});
    sim->step(5);
  }
  EXPECT_EQ(with.qd()[0], without.qd()[0]);
}

// A body spinning about a hinge without gravity: the bob of mass m at distance l (inertia I_c about
// its centre) is damped by -m c_l v_com and -I_c c_a omega, i.e. a hinge torque
// -(m l^2 c_l + I_c c_a) omega, applied to the free velocity of each step:
//   omega_{k+1} = omega_k (1 - dt kappa),  kappa = (m l^2 c_l + I_c c_a) / (m l^2 + I_c).
TEST(PhysxParameters, LinkDampingOnASpinningPendulumIsGeometric) {
  const double m = 1.3, l = 0.7, Ic = 0.02, cl = 0.8, ca = 3.0, omega0 = 2.0, dt = 1.0 / 60.0;
  ModelBuilder b;
  b.set_gravity(Vec3::Zero());
  b.add_link(make_link("base", "", 1.0, Vec3::Zero(), test::box_inertia(1.0, Vec3(0.1, 0.1, 0.1)),
                       fixed_joint("world_joint")));
  b.add_link(make_link("bob", "base", m, Vec3(0, 0, -l), Mat3::Identity() * Ic,
                       revolute_joint("hinge", Vec3::UnitY())));
  auto model = std::make_shared<const Model>(b.build());
  for (SolverType solver : {SolverType::pgs, SolverType::tgs}) {
    Simulation sim(model, options(solver, 4, 1, dt));
    LinkParameters p;
    p.linear_damping = cl;
    p.angular_damping = ca;
    sim.set_link_parameters("bob", p);
    sim.set_qd(VecX::Constant(1, omega0));
    const double kappa = (m * l * l * cl + Ic * ca) / (m * l * l + Ic);
    double angle = 0.0, omega = omega0;
    for (int k = 0; k < 120; ++k) {
      sim.step();
      omega *= 1.0 - dt * kappa;
      angle += dt * omega;
    }
    EXPECT_NEAR(sim.qd()[0], omega, 1e-12 * omega0) << to_string(solver);
    EXPECT_NEAR(sim.q()[0], angle, 1e-11) << to_string(solver);
  }
}

// Linear damping scales the link's weight by (1 - c dt) (PhysX's zero-acceleration force), so a
// slider falling along its axis from rest follows v_{k+1} = v_k - dt ((1 - c dt) g + c v_k):
//   v_k = v_inf (1 - (1 - c dt)^k),  v_inf = -(1 - c dt) g / c.
TEST(PhysxParameters, LinearDampingScalesTheWeight) {
  const double m = 2.0, g = 9.81, c = 1.5, dt = 0.01;
  auto model = test::make_slider(m, Vec3(0, 0, 1), Vec3(0, 0, -g));
  Simulation sim(model, options(SolverType::pgs, 1, 0, dt));
  LinkParameters p;
  p.linear_damping = c;
  sim.set_link_parameters("slider", p);
  const int steps = 200;
  sim.step(steps);
  const double v_inf = -(1.0 - c * dt) * g / c;
  EXPECT_NEAR(sim.qd()[0], v_inf * (1.0 - std::pow(1.0 - c * dt, steps)), 1e-10);
}

// Link velocity limits: past them the free velocity gets the force that brings an isolated link
// back in one step, -I_c (1 - W / |omega|) omega / dt and -m (1 - V / |v_com|) v_com / dt. On the
// spinning pendulum (v_com = l omega) that is a hinge velocity change of
//   -I_c (omega - W) / (m l^2 + I_c)   and   -m l^2 (omega - V / l) / (m l^2 + I_c).
TEST(PhysxParameters, LinkVelocityLimitsPullBackInOneStep) {
  const double m = 1.3, l = 0.7, Ic = 0.05, omega0 = 4.0, dt = 1.0 / 60.0;
  ModelBuilder b;
  b.set_gravity(Vec3::Zero());
  b.add_link(make_link("base", "", 1.0, Vec3::Zero(), test::box_inertia(1.0, Vec3(0.1, 0.1, 0.1)),
                       fixed_joint("world_joint")));
  b.add_link(make_link("bob", "base", m, Vec3(0, 0, -l), Mat3::Identity() * Ic,
                       revolute_joint("hinge", Vec3::UnitY())));
  auto model = std::make_shared<const Model>(b.build());
  const double total = m * l * l + Ic;
  {
    Simulation sim(model, options(SolverType::pgs, 4, 1, dt));
    LinkParameters p;
    p.max_angular_velocity = 3.0;
    sim.set_link_parameters("bob", p);
    sim.set_qd(VecX::Constant(1, omega0));
    sim.step();
    EXPECT_NEAR(sim.qd()[0], omega0 - Ic * (omega0 - 3.0) / total, 1e-12);
  }
  {
    Simulation sim(model, options(SolverType::tgs, 4, 1, dt));
    LinkParameters p;
    p.max_linear_velocity = 1.5;  // m/s of the centre of mass
    sim.set_link_parameters("bob", p);
    sim.set_qd(VecX::Constant(1, omega0));
    sim.step();
    EXPECT_NEAR(sim.qd()[0], omega0 - m * l * l * (omega0 - 1.5 / l) / total, 1e-12);
  }
}

// A level slider carrying its weight transmits |F| = m g (force through its centre of mass, no
// torque about it). The friction coefficient mu bounds the stopping impulse by mu h m g per solve:
// PGS accumulates it over the iterations (Coulomb friction: v1 = v0 - mu g dt); TGS applies it
// afresh in each of the n sub-steps and each velocity iteration (v1 = v0 - mu g dt (n + k) / n).
TEST(PhysxParameters, FrictionCoefficientGrowsWithTheTransmittedForce) {
  const double m = 2.0, g = 9.81, mu = 0.3, v0 = 1.0, dt = 1.0 / 60.0;
  auto model = test::make_slider(m, Vec3(1, 0, 0), Vec3(0, 0, -g));
  struct Setting {
    SolverType solver;
    int n, k;
    double expected;
  };
  const Setting settings[] = {{SolverType::pgs, 4, 2, v0 - mu * g * dt},
                              {SolverType::tgs, 4, 0, v0 - mu * g * dt},
                              {SolverType::tgs, 4, 2, v0 - mu * g * dt * 6.0 / 4.0}};
  for (const Setting& s : settings) {
    Simulation sim(model, options(s.solver, s.n, s.k, dt));
    sim.set_friction_coefficient("slide", mu);
    sim.set_qd(VecX::Constant(1, v0));
    sim.step();
    EXPECT_NEAR(sim.qd()[0], s.expected, 1e-12) << to_string(s.solver) << " " << s.k;
    EXPECT_NEAR(sim.friction_force()[0] * dt, m * (s.expected - v0), 1e-12);
  }
  // Below the bound it stops the joint.
  Simulation sim(model, options(SolverType::pgs, 4, 1, dt));
  sim.set_friction_coefficient("slide", mu);
  sim.set_qd(VecX::Constant(1, 0.5 * mu * g * dt));
  sim.step();
  EXPECT_NEAR(sim.qd()[0], 0.0, 1e-15);
  // Static or viscous friction set: PhysX uses those instead.
  sim.set_joint_friction("slide", JointFriction{0.0, 0.0, 1e-9});
  sim.set_qd(VecX::Constant(1, v0));
  sim.step();
  EXPECT_NEAR(sim.qd()[0], v0, 1e-6);
}

TEST(PhysxParameters, CompatPhysxTakesPhysxDefaults) {
  ModelBuilder b;
  b.add_link(make_link("base", "", 1.0, Vec3::Zero(), test::box_inertia(1.0, Vec3(0.1, 0.1, 0.1)),
                       fixed_joint("world_joint")));
  JointSpec limited = revolute_joint("a", Vec3::UnitY());
  limited.velocity_limit = 2.5;  // a model's velocity limit counts as set
  b.add_link(make_link("l1", "base", 1.0, Vec3(0, 0, -0.3), Mat3::Identity() * 1e-2, limited));
  b.add_link(make_link("l2", "l1", 1.0, Vec3(0, 0, -0.3), Mat3::Identity() * 1e-2,
                       prismatic_joint("b", Vec3::UnitX())));
  auto model = std::make_shared<const Model>(b.build());
  SimulationOptions o;
  Simulation plain(model, o);
  o.compat = Compat::physx;
  Simulation physx(model, o);
  for (int i = 0; i < model->num_links(); ++i) {
    const LinkParameters& p = physx.link_parameters(i);
    EXPECT_EQ(p.cfm_scale, 0.025);
    EXPECT_EQ(p.linear_damping, 0.05);
    EXPECT_EQ(p.angular_damping, 0.05);
    EXPECT_EQ(p.max_linear_velocity, 100.0);
    EXPECT_EQ(p.max_angular_velocity, 50.0);
    const LinkParameters& q = plain.link_parameters(i);
    EXPECT_EQ(q.cfm_scale, 0.0);
    EXPECT_EQ(q.linear_damping, 0.0);
    EXPECT_EQ(q.angular_damping, 0.0);
    EXPECT_EQ(q.max_linear_velocity, kInf);
    EXPECT_EQ(q.max_angular_velocity, kInf);
  }
  EXPECT_EQ(physx.friction_coefficient(0), 0.05);
  EXPECT_EQ(physx.friction_coefficient(1), 0.05);
  EXPECT_EQ(physx.max_joint_velocity(0), 2.5);
  EXPECT_EQ(physx.max_joint_velocity(1), 100.0);
  EXPECT_EQ(plain.friction_coefficient(1), 0.0);
  EXPECT_EQ(plain.max_joint_velocity(1), kInf);
  // Set values replace the defaults, and stay mutable between steps.
  physx.set_friction_coefficient("b", 0.0);
  physx.step();
  physx.set_link_parameters("l2", LinkParameters{});
  EXPECT_EQ(physx.link_parameters("l2").cfm_scale, 0.0);
  EXPECT_EQ(physx.friction_coefficient(1), 0.0);
}

void expect_error(const std::function<void()>& f, const std::string& text) {
  try {
    f();
    ADD_FAILURE() << "no error; expected: " << text;
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(text), std::string::npos) << e.what();
  }
}

TEST(PhysxParameters, ValidationNamesLinkFieldAndValue) {
  auto model = test::make_slider(1.0, Vec3(1, 0, 0), Vec3(0, 0, -9.81));
  Simulation sim(model);
  auto with = [](auto field, double v) {
    LinkParameters p;
    field(p, v);
    return p;
  };
  expect_error([&] { sim.set_link_parameters("slider", with([](LinkParameters& p, double v) { p.cfm_scale = v; }, 1.5)); },
               "link 'slider': cfm_scale = 1.5 must be in [0, 1]");
  expect_error([&] { sim.set_link_parameters("slider", with([](LinkParameters& p, double v) { p.cfm_scale = v; }, -0.1)); },
               "link 'slider': cfm_scale = -0.1 must be in [0, 1]");
  expect_error([&] { sim.set_link_parameters(1, with([](LinkParameters& p, double v) { p.linear_damping = v; }, -2)); },
               "link 'slider': linear_damping = -2 must be finite and >= 0");
  expect_error([&] { sim.set_link_parameters(0, with([](LinkParameters& p, double v) { p.angular_damping = v; }, kInf)); },
               "link 'base': angular_damping = inf must be finite and >= 0");
  expect_error([&] { sim.set_link_parameters(1, with([](LinkParameters& p, double v) { p.max_linear_velocity = v; }, -1)); },
               "link 'slider': max_linear_velocity = -1 must be >= 0");
  expect_error([&] { sim.set_link_parameters(1, with([](LinkParameters& p, double v) { p.max_angular_velocity = v; }, std::nan(""))); },
               "link 'slider': max_angular_velocity = nan must be >= 0");
  expect_error([&] { sim.set_link_parameters(7, LinkParameters{}); }, "link index 7 is out of range [0, 2)");
  expect_error([&] { sim.set_link_parameters("nope", LinkParameters{}); }, "nope");
  expect_error([&] { sim.set_friction_coefficient("slide", -0.5); },
               "joint 'slide': friction_coefficient = -0.5 must be finite and >= 0");
  expect_error([&] { sim.set_friction_coefficient(0, kInf); },
               "joint 'slide': friction_coefficient = inf must be finite and >= 0");
  EXPECT_EQ(sim.link_parameters(1).cfm_scale, 0.0);  // nothing changed
}

}  // namespace
}  // namespace featherdrive
