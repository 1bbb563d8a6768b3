#include "bench_models.hpp"

#include <random>

#include "featherdrive/io/urdf.hpp"
#include "featherdrive/model/model_builder.hpp"

namespace featherdrive::bench {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

Mat3 box_inertia(double m, double x, double y, double z) {
  return Vec3(m * (y * y + z * z) / 12.0, m * (x * x + z * z) / 12.0, m * (x * x + y * y) / 12.0)
      .asDiagonal();
}

// A solid cylinder of radius r and length h along z.
Mat3 cylinder_inertia(double m, double r, double h) {
  const double across = m * (3.0 * r * r + h * h) / 12.0;
  return Vec3(across, across, 0.5 * m * r * r).asDiagonal();
}

VecX random_targets(const Model& model, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-0.5, 0.5);
  VecX target = VecX::Zero(model.nv);
  for (int d = 0; d < model.nv; ++d)
    if (is_driven(model, d)) target[d] = u(rng);
  return target;
}

BenchRobot finish(std::string name, ModelBuilder& builder, unsigned seed) {
  BenchRobot robot;
  robot.name = std::move(name);
  robot.model = std::make_shared<const Model>(builder.build());
  robot.q0 = robot.model->neutral_configuration();
  robot.target = random_targets(*robot.model, seed);
  return robot;
}

}  // namespace

bool is_driven(const Model& model, int dof) {
  return model.links[model.dof_link[dof]].joint_type == JointType::revolute;
}

BenchRobot make_chain(int n) {
  const double mass = 1.0, length = 0.5, radius = 0.05;
  const Vec3 axes[3] = {Vec3::UnitY(), Vec3::UnitZ(), Vec3::UnitX()};
  ModelBuilder b;
  b.add_link(make_link("base", "", 1.0, Vec3::Zero(), box_inertia(1.0, 0.1, 0.1, 0.1),
                       fixed_joint("world_joint")));
  std::string parent = "base";
  for (int i = 0; i < n; ++i) {
    const std::string name = "link" + std::to_string(i + 1);
    b.add_link(make_link(name, parent, mass, Vec3(0, 0, -length / 2),
                         cylinder_inertia(mass, radius, length),
                         revolute_joint("joint" + std::to_string(i + 1), axes[i % 3],
                                        i == 0 ? Vec3::Zero() : Vec3(0, 0, -length))));
    parent = name;
  }
  return finish("chain" + std::to_string(n), b, 42u + static_cast<unsigned>(n));
}

BenchRobot make_arm7() {
  UrdfRobot urdf = load_urdf(FEATHERDRIVE_SOURCE_DIR "/examples/arm7.urdf");
  for (LinkSpec& link : urdf.links) {
    link.joint.lower_limit = -kInf;
    link.joint.upper_limit = kInf;
    link.joint.velocity_limit = kInf;
    link.joint.damping = 0.0;
    link.joint.friction = 0.0;
  }
  urdf.rebuild();
  BenchRobot robot;
  robot.name = "arm7";
  robot.model = urdf.model;
  robot.q0 = robot.model->neutral_configuration();
  robot.target = random_targets(*robot.model, 7u);
  return robot;
}

BenchRobot make_humanoid() {
  ModelBuilder b;
  const Vec3 X = Vec3::UnitX(), Y = Vec3::UnitY(), Z = Vec3::UnitZ();
  const Mat3 small = box_inertia(0.5, 0.05, 0.05, 0.05);  // the links between the axes of a joint
  b.add_link(make_link("pelvis", "", 10.0, Vec3::Zero(), box_inertia(10.0, 0.25, 0.3, 0.15),
                       floating_joint("root")));
  // Waist and torso, neck and head.
  b.add_link(make_link("waist", "pelvis", 0.5, Vec3::Zero(), small,
                       revolute_joint("waist_yaw", Z, Vec3(0, 0, 0.1))));
  b.add_link(make_link("torso", "waist", 20.0, Vec3(0, 0, 0.25), box_inertia(20.0, 0.25, 0.35, 0.5),
                       revolute_joint("waist_pitch", Y)));
  b.add_link(make_link("neck", "torso", 0.5, Vec3::Zero(), small,
                       revolute_joint("neck_yaw", Z, Vec3(0, 0, 0.55))));
  b.add_link(make_link("head", "neck", 5.0, Vec3(0, 0, 0.12), box_inertia(5.0, 0.2, 0.2, 0.25),
                       revolute_joint("neck_pitch", Y)));
  for (const char* side : {"left", "right"}) {
    const std::string s = side;
    const double y = s == "left" ? 1.0 : -1.0;
    // Leg: hip yaw, roll, pitch; knee; ankle pitch, roll.
    b.add_link(make_link(s + "_hip_yaw_link", "pelvis", 0.5, Vec3::Zero(), small,
                         revolute_joint(s + "_hip_yaw", Z, Vec3(0, 0.1 * y, -0.1))));
    b.add_link(make_link(s + "_hip_roll_link", s + "_hip_yaw_link", 0.5, Vec3::Zero(), small,
                         revolute_joint(s + "_hip_roll", X)));
    b.add_link(make_link(s + "_thigh", s + "_hip_roll_link", 7.0, Vec3(0, 0, -0.2),
                         cylinder_inertia(7.0, 0.07, 0.4), revolute_joint(s + "_hip_pitch", Y)));
    b.add_link(make_link(s + "_shin", s + "_thigh", 4.0, Vec3(0, 0, -0.2),
                         cylinder_inertia(4.0, 0.05, 0.4),
                         revolute_joint(s + "_knee", Y, Vec3(0, 0, -0.4))));
    b.add_link(make_link(s + "_ankle_link", s + "_shin", 0.5, Vec3::Zero(), small,
                         revolute_joint(s + "_ankle_pitch", Y, Vec3(0, 0, -0.4))));
    b.add_link(make_link(s + "_foot", s + "_ankle_link", 1.5, Vec3(0.05, 0, -0.04),
                         box_inertia(1.5, 0.22, 0.1, 0.06), revolute_joint(s + "_ankle_roll", X)));
    // Arm: shoulder pitch, roll, yaw; elbow.
    b.add_link(make_link(s + "_shoulder_pitch_link", "torso", 0.5, Vec3::Zero(), small,
                         revolute_joint(s + "_shoulder_pitch", Y, Vec3(0, 0.22 * y, 0.45))));
    b.add_link(make_link(s + "_shoulder_roll_link", s + "_shoulder_pitch_link", 0.5, Vec3::Zero(),
                         small, revolute_joint(s + "_shoulder_roll", X)));
    b.add_link(make_link(s + "_upper_arm", s + "_shoulder_roll_link", 2.5, Vec3(0, 0, -0.15),
                         cylinder_inertia(2.5, 0.045, 0.3), revolute_joint(s + "_shoulder_yaw", Z)));
    b.add_link(make_link(s + "_forearm", s + "_upper_arm", 1.5, Vec3(0, 0, -0.13),
                         cylinder_inertia(1.5, 0.04, 0.26),
                         revolute_joint(s + "_elbow", Y, Vec3(0, 0, -0.3))));
  }
  BenchRobot robot = finish("humanoid", b, 30u);
  robot.q0[2] = 1.0;  // the pelvis 1 m above the origin
  return robot;
}

void add_drives(Simulation& sim, const BenchRobot& robot) {
  const Model& model = *robot.model;
  for (int d = 0; d < model.nv; ++d)
    if (is_driven(model, d))
      sim.set_drive(d, Drive{DriveType::force, kStiffness, kDamping, kInf, robot.target[d], 0.0});
}

Simulation bench_simulation(const BenchRobot& robot, SolverType solver) {
  SimulationOptions o;
  o.dt = kDt;
  o.solver = solver;
  o.position_iterations = 4;
  o.velocity_iterations = 1;
  Simulation sim(robot.model, o);
  add_drives(sim, robot);
  sim.set_q(robot.q0);
  return sim;
}

}  // namespace featherdrive::bench
