#include "support/contact_models.hpp"

#include <cmath>

#include "featherdrive/algorithm/floating_base.hpp"
#include "support/compare.hpp"
#include "support/models.hpp"

namespace featherdrive::test {
namespace {

constexpr double kLegRadius = 0.025, kSegment = 0.2;
const char* const kLegs[4] = {"fl", "fr", "hl", "hr"};
const Vec3 kHips[4] = {{0.15, 0.12, -0.05}, {0.15, -0.12, -0.05}, {-0.15, 0.12, -0.05},
                       {-0.15, -0.12, -0.05}};

// A solid cylinder along z about its centre.
Mat3 cylinder_inertia(double m) {
  const double across = m * (3 * kLegRadius * kLegRadius + kSegment * kSegment) / 12;
  return Vec3(across, across, m * kLegRadius * kLegRadius / 2).asDiagonal();
}

CollisionShape shape(ShapeType type, const Vec3& size, const Vec3& position, double mu,
                     std::string name) {
  CollisionShape s;
  s.name = std::move(name);
  s.type = type;
  s.size = size;
  s.position = position;
  s.material = Material{mu, mu, 0.0};
  return s;
}

}  // namespace

std::shared_ptr<const Model> make_ground_box(double mu) {
  ModelBuilder b;
  b.set_gravity(Vec3(0, 0, -kContactGravity));
  const double inertia = 1.0 * (2 * 0.2 * 0.2) / 12;  // the bench's expression, bit for bit
  b.add_link(make_link("box", "", 1.0, Vec3::Zero(), Mat3::Identity() * inertia,
                       floating_joint("box_root")));
  b.add_shape("box", shape(ShapeType::box, Vec3(0.1, 0.1, 0.1), Vec3::Zero(), mu, "box"));
  return std::make_shared<const Model>(b.build());
}

ModelBuilder quadruped_builder() {
  ModelBuilder b;
  b.set_gravity(Vec3(0, 0, -kContactGravity));
  const Vec3 half(0.2, 0.1, 0.05);
  const double m = 4.0;
  b.add_link(make_link("base", "", m, Vec3::Zero(),
                       Vec3(m / 3 * (half.y() * half.y() + half.z() * half.z()),
                            m / 3 * (half.x() * half.x() + half.z() * half.z()),
                            m / 3 * (half.x() * half.x() + half.y() * half.y()))
                           .asDiagonal(),
                       floating_joint("base_root")));
  for (int i = 0; i < 4; ++i) {
    const std::string leg = kLegs[i];
    b.add_link(make_link(leg + "_thigh", "base", 0.5, Vec3(0, 0, -kSegment / 2),
                         cylinder_inertia(0.5), revolute_joint(leg + "_hip", Vec3::UnitY(), kHips[i])));
    b.add_link(make_link(leg + "_shin", leg + "_thigh", 0.3, Vec3(0, 0, -kSegment / 2),
                         cylinder_inertia(0.3),
                         revolute_joint(leg + "_knee", Vec3::UnitY(), Vec3(0, 0, -kSegment))));
  }
  return b;
}

std::vector<std::pair<std::string, CollisionShape>> quadruped_shapes(double mu) {
  std::vector<std::pair<std::string, CollisionShape>> shapes;
  shapes.emplace_back("base", shape(ShapeType::box, Vec3(0.2, 0.1, 0.05), Vec3::Zero(), mu, "base"));
  for (const char* leg : kLegs)
    for (const char* part : {"_thigh", "_shin"}) {
      const std::string link = std::string(leg) + part;
      shapes.emplace_back(link, shape(ShapeType::capsule, Vec3(kLegRadius, kSegment / 2, 0),
                                      Vec3(0, 0, -kSegment / 2), mu, link));
    }
  return shapes;
}

std::shared_ptr<const Model> make_quadruped(double mu) {
  ModelBuilder b = quadruped_builder();
  for (auto& [link, s] : quadruped_shapes(mu)) b.add_shape(link, s);
  return std::make_shared<const Model>(b.build());
}

double quadruped_standing_height() {
  // The bench's expression: the hip's depth, the two segments and the foot's radius.
  return 0.05 + kSegment * std::cos(kQuadrupedHip) + kSegment * std::cos(kQuadrupedHip + kQuadrupedKnee) +
         kLegRadius;
}

Simulation contact_reference_simulation(std::shared_ptr<const Model> model, SolverType solver,
                                        double mu) {
  SimulationOptions o;
  o.dt = kContactDt;
  o.solver = solver;
  o.position_iterations = 4;
  o.velocity_iterations = 1;
  o.compat = Compat::physx;
  Simulation sim(std::move(model), o);
  for (int i = 0; i < sim.model().num_links(); ++i) {
    LinkParameters p = sim.link_parameters(i);
    p.linear_damping = p.angular_damping = 0.0;  // the bench zeroes them
    sim.set_link_parameters(i, p);
  }
  Ground ground;
  ground.enabled = true;
  ground.material = Material{mu, mu, 0.0};
  sim.set_ground(ground);
  return sim;
}

Simulation ground_box_simulation(SolverType solver, double v0) {
  Simulation sim = contact_reference_simulation(make_ground_box(0.5), solver, 0.5);
  VecX q = sim.q(), qd = sim.qd();
  BaseState base;
  base.position = Vec3(0, 0, 0.1);
  base.linear_velocity = Vec3(v0, 0, 0);
  set_base_state(sim.model(), base, q, qd);
  sim.set_q(q);
  sim.set_qd(qd);
  return sim;
}

Simulation quadruped_simulation(SolverType solver, double lift) {
  Simulation sim = contact_reference_simulation(make_quadruped(1.0), solver, 1.0);
  const Model& model = sim.model();
  VecX q = sim.q(), qd = sim.qd();
  BaseState base;
  base.position = Vec3(0, 0, quadruped_standing_height() + lift);
  set_base_state(model, base, q, qd);
  for (const char* leg : kLegs)
    for (const auto& [joint, target] :
         {std::pair{"_hip", kQuadrupedHip}, std::pair{"_knee", kQuadrupedKnee}}) {
      const std::string name = std::string(leg) + joint;
      q[model.links[model.joint_link_index(name)].q_index] = target;
      sim.set_drive(name, Drive{DriveType::force, 300.0, 10.0,
                                kInf, target, 0.0});
    }
  sim.set_q(q);
  sim.set_qd(qd);
  return sim;
}

}  // namespace featherdrive::test
