// Self-collision (docs/math/contact.md, section 14) against closed forms: a sphere on a slider
// comes to rest on a sphere of the robot's own fixed base and carries its weight, a dropped one
// rebounds at e times its impact speed; parent and child never collide, and self-collision is off
// unless asked for.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "featherdrive/algorithm/energy.hpp"
#include "featherdrive/algorithm/kinematics.hpp"
#include "featherdrive/model/model_builder.hpp"
#include "featherdrive/sim/simulation.hpp"
#include "support/drives.hpp"
#include "support/models.hpp"

namespace featherdrive {
namespace {

constexpr double kG = 9.81;
constexpr double kR1 = 0.1, kR2 = 0.05, kM2 = 2.0;

CollisionShape sphere(double radius, const Material& material = {}) {
  CollisionShape s;
  s.type = ShapeType::sphere;
  s.size = Vec3(radius, 0, 0);
  s.material = material;
  return s;
}

// A fixed base with a sphere of radius kR1 at its origin; a carriage on a horizontal slider
// (no shape); on it a vertical slider carrying a sphere of radius kR2 and mass kM2, starting at
// height z above the base's centre. The base and the ball are not parent and child.
Simulation stacked_spheres(double z, SolverType solver, int iterations,
                           const Material& material = {}) {
  ModelBuilder b;
  b.add_link(make_link("base", "", 0.0, Vec3::Zero(), Mat3::Zero(), fixed_joint("weld")));
  b.add_link(make_link("carriage", "base", 0.5, Vec3::Zero(), Mat3::Identity() * 0.01,
                       prismatic_joint("across", Vec3::UnitX())));
  b.add_link(make_link("ball", "carriage", kM2, Vec3::Zero(),
                       Mat3::Identity() * 0.4 * kM2 * kR2 * kR2,
                       prismatic_joint("drop", Vec3::UnitZ())));
  b.add_shape("base", sphere(kR1, material));
  b.add_shape("ball", sphere(kR2, material));
  SimulationOptions o;
  o.dt = 0.01;
  o.solver = solver;
  o.position_iterations = iterations;
  Simulation sim(std::make_shared<const Model>(b.build()), o);
  VecX q = sim.q();
  q[1] = z;
  sim.set_q(q);
  ContactOptions c;
  c.self_collision = true;
  sim.set_contact_options(c);
  return sim;
}

double normal_sum(const Simulation& sim) {
  double s = 0.0;
  for (const ContactReport& c : sim.contacts()) s += c.normal_impulse;
  return s;
}

class SelfContact : public ::testing::TestWithParam<SolverType> {};

int converged(SolverType solver) { return solver == SolverType::pgs ? 50 : 100; }

TEST_P(SelfContact, BallRestsOnTheBasesSphereAndCarriesItsWeight) {
  Simulation sim = stacked_spheres(kR1 + kR2 + 0.01, GetParam(), converged(GetParam()));
  for (int k = 0; k < 300; ++k) sim.step();
  ASSERT_EQ(sim.contacts().size(), 1u);
  const ContactReport& c = sim.contacts()[0];
  EXPECT_EQ(c.link, 0);  // the base's shape comes first in the pair
  EXPECT_EQ(c.other_link, 2);
  EXPECT_NEAR(c.normal.z(), -1.0, 1e-12);  // from the ball into the base
  EXPECT_NEAR(sim.q()[1], kR1 + kR2, 1e-9);
  EXPECT_NEAR(sim.q()[0], 0.0, 1e-12);  // straight above: nothing pushes the carriage
  EXPECT_NEAR(normal_sum(sim) / (sim.options().dt * kM2 * kG), 1.0, 1e-9);
  // The base carries the ball's weight down, the ball is held up.
  EXPECT_NEAR(sim.link_contact_force()[2].z(), kM2 * kG, 1e-7);
  EXPECT_NEAR(sim.link_contact_force()[0].z(), -kM2 * kG, 1e-7);
}

TEST_P(SelfContact, ADroppedBallReboundsAtRestitutionTimesItsImpactSpeed) {
  const double e = 0.5;
  Simulation sim = stacked_spheres(kR1 + kR2 + 0.2, GetParam(), converged(GetParam()),
                                   Material{0.5, 0.5, e});
  ContactOptions c = sim.contact_options();
  c.bounce_threshold = 0.5;
  sim.set_contact_options(c);
  double impact = 0.0, rebound = 0.0;
  for (int k = 0; k < 100 && rebound == 0.0; ++k) {
    const double v0 = sim.qd()[1];
    sim.step();
    if (normal_sum(sim) > 0.0) {
      impact = v0 - kG * sim.options().dt;  // the pre-solve velocity: the step's gravity in it
      rebound = sim.qd()[1];
    }
  }
  ASSERT_LT(impact, -0.5);
  EXPECT_NEAR(-rebound / impact, e, 1e-9);
}

// Off by default: the ball falls through the base's sphere.
TEST_P(SelfContact, IsOffUnlessAskedFor) {
  Simulation sim = stacked_spheres(kR1 + kR2 + 0.01, GetParam(), 4);
  sim.set_contact_options(ContactOptions{});
  for (int k = 0; k < 100; ++k) sim.step();
  EXPECT_TRUE(sim.contacts().empty());
  EXPECT_LT(sim.q()[1], 0.0);
}

// Parent and child never collide, though their spheres overlap: the run is the run without
// self-collision, bit for bit.
TEST_P(SelfContact, ParentAndChildAreFiltered) {
  ModelBuilder b;
  b.add_link(make_link("base", "", 0.0, Vec3::Zero(), Mat3::Zero(), fixed_joint("weld")));
  b.add_link(make_link("arm", "base", 1.0, Vec3(0.1, 0, 0), Mat3::Identity() * 0.01,
                       revolute_joint("hinge", Vec3::UnitY())));
  b.add_shape("base", sphere(0.2));
  b.add_shape("arm", sphere(0.2));
  SimulationOptions o;
  o.solver = GetParam();
  const auto model = std::make_shared<const Model>(b.build());
  Simulation with(model, o), without(model, o);
  ContactOptions c;
  c.self_collision = true;
  with.set_contact_options(c);
  for (int k = 0; k < 50; ++k) {
    with.step();
    without.step();
  }
  EXPECT_TRUE(with.contacts().empty());
  EXPECT_EQ(with.q(), without.q());
  EXPECT_EQ(with.qd(), without.qd());
}

// Two balls, each spinning on a hinge whose axis runs through its centre and centre of mass, touch
// 1 cm deep: neither can move along the normal row, whose response is rounding (u of order eps
// where Lambda is of order 1), nor has a linear response at its centre of mass, so the cfm of C32
// is rounding too. C22a counts such a u as 0: the row applies nothing, and the friction rows
// (which can turn the balls) see a normal impulse of 0. Exact rows would divide by the rounding.
TEST_P(SelfContact, TwoLinksThatCannotMoveAlongTheirRowApplyNothing) {
  ModelBuilder b;
  b.add_link(make_link("base", "", 0.0, Vec3::Zero(), Mat3::Zero(), fixed_joint("weld")));
  // Axes and the line of centres (0.19 m long) off the coordinate axes.
  const Vec3 a = Vec3(0.3, 0.7, -0.2).normalized(), c = Vec3(-0.6, 0.1, 0.5).normalized();
  const Vec3 left(0.1, 0.2, 0.3), right = left + Vec3(0.11, -0.07, 0.13).normalized() * 0.19;
  b.add_link(make_link("left", "base", 1.3, Vec3::Zero(), Mat3::Identity() * 0.013,
                       revolute_joint("spin_left", a, left)));
  b.add_link(make_link("right", "base", 0.7, Vec3::Zero(), Mat3::Identity() * 0.007,
                       revolute_joint("spin_right", c, right)));
  b.add_shape("left", sphere(0.1));
  b.add_shape("right", sphere(0.1));
  SimulationOptions o;
  o.solver = GetParam();
  Simulation sim(std::make_shared<const Model>(b.build()), o);
  ContactOptions options;
  options.self_collision = true;
  sim.set_contact_options(options);
  VecX qd(2);
  qd << 1.0, -2.0;
  sim.set_qd(qd);
  for (int k = 0; k < 10; ++k) {
    sim.step();
    ASSERT_EQ(sim.contacts().size(), 1u);
    EXPECT_NEAR(sim.contacts()[0].separation, -0.01, 1e-12);
    EXPECT_EQ(sim.contacts()[0].normal_impulse, 0.0);
    EXPECT_EQ(sim.contacts()[0].friction_impulse, Vec3::Zero());
  }
  EXPECT_LT((sim.qd() - qd).cwiseAbs().maxCoeff(), 1e-12);  // no moment about either axis
}

// A floating tree in zero gravity (no armature: rotors would carry momentum the links do not)
// whose links 2 and 8 (not parent and child) carry overlapping spheres: the
// contact is internal, so one step keeps the tree's spatial momentum (measured at the step's start
// in its axes), and 200 steps stay bounded.
TEST_P(SelfContact, InternalContactsKeepTheMomentumOfAFloatingTree) {
  Model tree = *test::make_random_tree(11, 12, true, true, 0.0);
  tree.gravity = Vec3::Zero();
  // A sphere at link 2's origin, another on link 8 placed 0.15 m from it: 0.05 m deep.
  Data posed(tree);
  forward_kinematics(tree, posed, tree.neutral_configuration());
  CollisionShape a = sphere(0.1), b = sphere(0.1);
  a.link = 2;
  b.link = 8;
  b.position = posed.world_rotation[8].transpose() *
               (posed.world_position[2] + Vec3(0.1, 0.05, 0.1) - posed.world_position[8]);
  tree.shapes = {a, b};
  const auto model = std::make_shared<const Model>(tree);
  SimulationOptions o;
  o.solver = GetParam();
  Simulation sim(model, o);
  ContactOptions c;
  c.self_collision = true;
  sim.set_contact_options(c);
  const VecX q0 = sim.q(), v0 = sim.qd();
  sim.step();
  ASSERT_EQ(sim.contacts().size(), 1u);
  EXPECT_NEAR(sim.contacts()[0].separation, -0.05, 1e-12);
  const VecX vstar = test::with_classical_root(
      *model, v0, o.dt, test::free_velocity(*model, q0, v0, VecX::Zero(model->nv), o.dt));
  Data data(*model);
  forward_kinematics(*model, data, q0, vstar);
  const Vec6 h_free = momentum(*model, data);
  forward_kinematics(*model, data, q0, test::in_start_axes(*model, q0, sim.q(), sim.qd()));
  EXPECT_LT((momentum(*model, data) - h_free).norm(), 1e-9 * (1.0 + h_free.norm()));
  sim.step();  // pushed apart (TGS within its sub-steps, its velocity iterations then stop it)
  EXPECT_TRUE(sim.contacts().empty() || sim.contacts()[0].separation > -0.045);
  for (int k = 0; k < 200; ++k) sim.step();
  EXPECT_LT(sim.qd().cwiseAbs().maxCoeff(), 100.0);
}

// A box link (half extents kHalf, kBoxMass) on a hinge about x above a lifting slider (kLiftMass)
// of a fixed base that carries a plate (half extents 0.5, 0.5, 0.05, its top at z = 0.05)
// centred at y = plate_y. The box starts with its lower face 1 mm above the plate's top.
constexpr double kBoxMass = 2.0, kLiftMass = 0.5;
const Vec3 kHalf(0.1, 0.1, 0.05);

CollisionShape box(const Vec3& half, const Vec3& position = Vec3::Zero()) {
  CollisionShape s;
  s.type = ShapeType::box;
  s.size = half;
  s.position = position;
  return s;
}

Simulation box_on_plate(double plate_y, SolverType solver, const CollisionShape& shape = box(kHalf),
                        const Vec3& hinge = Vec3::UnitX()) {
  ModelBuilder b;
  b.add_link(make_link("base", "", 0.0, Vec3::Zero(), Mat3::Zero(), fixed_joint("weld")));
  b.add_link(make_link("lift", "base", kLiftMass, Vec3::Zero(), Mat3::Identity() * 0.01,
                       prismatic_joint("up", Vec3::UnitZ())));
  const Vec3 s = kHalf.cwiseProduct(kHalf);
  const Mat3 inertia =
      Mat3(Vec3(s.y() + s.z(), s.x() + s.z(), s.x() + s.y()).asDiagonal()) * kBoxMass / 3;
  b.add_link(make_link("box", "lift", kBoxMass, Vec3::Zero(), inertia,
                       revolute_joint("tilt", hinge)));
  b.add_shape("base", box(Vec3(0.5, 0.5, 0.05), Vec3(0, plate_y, 0)));
  b.add_shape("box", shape);
  SimulationOptions o;
  o.dt = 0.01;
  o.solver = solver;
  o.position_iterations = converged(solver);
  Simulation sim(std::make_shared<const Model>(b.build()), o);
  VecX q = sim.q();
  q[0] = 0.05 + (shape.type == ShapeType::box ? shape.size.z() : shape.size.x()) + 1e-3;
  sim.set_q(q);
  ContactOptions c;
  c.self_collision = true;
  sim.set_contact_options(c);
  return sim;
}

// Runs 2000 steps; returns the largest tilt. The points and impulses are the last step's.
double settle(Simulation& sim) {
  double tilt = 0.0;
  for (int k = 0; k < 2000; ++k) {
    sim.step();
    tilt = std::max(tilt, std::abs(sim.q()[1]));
  }
  return tilt;
}

// C29a: a box lying flat on a larger plate is carried at its lower face's four corners, so it
// stays level (one point at the middle would leave it balancing on a pivot), and the four normal
// impulses carry the weight of the box and the slider.
TEST_P(SelfContact, ABoxLyingOnAPlateRestsOnItsFourCorners) {
  Simulation sim = box_on_plate(0.0, GetParam());
  EXPECT_LT(settle(sim), 1e-9);
  ASSERT_EQ(sim.contacts().size(), 4u);
  EXPECT_NEAR(sim.q()[0], 0.05 + kHalf.z(), 1e-9);
  EXPECT_NEAR(normal_sum(sim) / (sim.options().dt * (kBoxMass + kLiftMass) * kG), 1.0, 1e-9);
  int corners = 0;
  for (const ContactReport& c : sim.contacts()) {
    EXPECT_NEAR(c.normal.z(), -1.0, 1e-12);  // from the box into the plate
    EXPECT_NEAR(std::abs(c.position.x()), kHalf.x(), 1e-9);
    EXPECT_NEAR(std::abs(c.position.y()), kHalf.y(), 1e-9);
    EXPECT_NEAR(c.position.z(), 0.05, 1e-9);
    corners |= 1 << ((c.position.x() > 0) * 2 + (c.position.y() > 0));
  }
  EXPECT_EQ(corners, 15);  // each corner once
}

// The box overhangs the plate's edge at y = 0.05 by half its width less 0.05 m; its centre of mass
// (y = 0) is over the plate. The points are the overlap's corners: the box's two corners at
// y = -0.1 and where its sides cross the plate's edge. It stays level.
TEST_P(SelfContact, ABoxOverhangingThePlatesEdgeRestsOnTheOverlap) {
  Simulation sim = box_on_plate(-0.45, GetParam());
  EXPECT_LT(settle(sim), 1e-9);
  ASSERT_EQ(sim.contacts().size(), 4u);
  EXPECT_NEAR(normal_sum(sim) / (sim.options().dt * (kBoxMass + kLiftMass) * kG), 1.0, 1e-9);
  int corners = 0;
  for (const ContactReport& c : sim.contacts()) {
    EXPECT_NEAR(std::abs(c.position.x()), kHalf.x(), 1e-9);
    const bool edge = c.position.y() > 0;
    EXPECT_NEAR(c.position.y(), edge ? 0.05 : -kHalf.y(), 1e-9);
    EXPECT_NEAR(c.position.z(), 0.05, 1e-9);
    corners |= 1 << ((c.position.x() > 0) * 2 + edge);
  }
  EXPECT_EQ(corners, 15);
}

// A capsule (radius 0.05 m, half length 0.1 m) lying along x on the plate, on a hinge about y:
// carried at its segment's two ends (C29a), it stays level.
TEST_P(SelfContact, ACapsuleLyingOnAPlateRestsOnItsSegmentsEnds) {
  CollisionShape capsule;
  capsule.type = ShapeType::capsule;
  capsule.size = Vec3(0.05, 0.1, 0);
  capsule.rotation = Eigen::AngleAxisd(0.5 * std::numbers::pi, Vec3::UnitY()).toRotationMatrix();
  Simulation sim = box_on_plate(0.0, GetParam(), capsule, Vec3::UnitY());
  EXPECT_LT(settle(sim), 1e-9);
  ASSERT_EQ(sim.contacts().size(), 2u);
  EXPECT_NEAR(sim.q()[0], 0.05 + 0.05, 1e-9);
  EXPECT_NEAR(normal_sum(sim) / (sim.options().dt * (kBoxMass + kLiftMass) * kG), 1.0, 1e-9);
  double x = 0.0;
  for (const ContactReport& c : sim.contacts()) {
    EXPECT_NEAR(std::abs(c.position.x()), 0.1, 1e-9);
    EXPECT_NEAR(c.position.y(), 0.0, 1e-9);
    EXPECT_NEAR(c.position.z(), 0.05, 1e-9);
    x += c.position.x();
  }
  EXPECT_NEAR(x, 0.0, 1e-9);  // one at each end
}

INSTANTIATE_TEST_SUITE_P(Solvers, SelfContact, ::testing::Values(SolverType::pgs, SolverType::tgs),
                         [](const auto& info) { return std::string(to_string(info.param)); });

}  // namespace
}  // namespace featherdrive
