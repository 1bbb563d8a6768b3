// URDF import against the numbers written in the shipped files, a hand-built twin, and fixed-joint
// merging worked out by hand.
#include "featherdrive/io/urdf.hpp"

#include <gtest/gtest.h>

#include <numbers>
#include <random>

#include "featherdrive/sim/simulation.hpp"

namespace featherdrive {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
const std::string kSource = FEATHERDRIVE_SOURCE_DIR;

std::string example(const std::string& name) {
  return kSource + "/examples/" + name;
}
std::string data(const std::string& name) {
  return kSource + "/tests/data/" + name;
}

const Link& link_named(const Model& m, const std::string& name) {
  return m.links[m.link_index(name)];
}

void expect_mat_near(const Mat3& a, const Mat3& b, double tol) {
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(a(r, c), b(r, c), tol) << "(" << r << "," << c << ")";
}

Mat3 diag(double x, double y, double z) {
  return Vec3(x, y, z).asDiagonal();
}

// The <inertial> and <joint> values as written in examples/arm7.urdf.
struct ArmLink {
  const char* link;
  const char* joint;
  double mass, com_z, ixx, izz;
  Vec3 axis;
  double joint_z, lower, upper, effort, velocity, damping, friction;
};
const ArmLink kArm[] = {
    {"link1", "joint1", 3.5, 0.1, 0.0148167, 0.0063, Vec3(0, 0, 1), 0.1, -2.8, 2.8, 150, 2.2, 0.5,
     0.2},
    {"link2", "joint2", 3.5, 0.175, 0.038376, 0.00529375, Vec3(0, 1, 0), 0.2, -1.8, 1.8, 150, 2.2,
     0.5, 0.2},
    {"link3", "joint3", 2.5, 0.075, 0.00625, 0.003125, Vec3(0, 0, 1), 0.35, -2.8, 2.8, 80, 2.6, 0.3,
     0.1},
    {"link4", "joint4", 2.0, 0.15, 0.0160125, 0.002025, Vec3(0, 1, 0), 0.15, -2.6, 2.6, 80, 2.6,
     0.3, 0.1},
    {"link5", "joint5", 1.5, 0.06, 0.0024, 0.0012, Vec3(0, 0, 1), 0.3, -2.8, 2.8, 30, 3.1, 0.1,
     0.05},
    {"link6", "joint6", 1.2, 0.05, 0.00148, 0.00096, Vec3(0, 1, 0), 0.12, -2.2, 2.2, 30, 3.1, 0.1,
     0.05},
};

TEST(Urdf, Arm7MassesInertiasAxesAndLimitsAreTheFilesValues) {
  const UrdfRobot robot = load_urdf(example("arm7.urdf"));
  const Model& m = *robot.model;
  EXPECT_EQ(robot.name, "arm7");
  EXPECT_EQ(m.nv, 7);
  EXPECT_EQ(m.num_links(), 8);  // world (with base_link), link1..link7 (with hand, tcp)
  EXPECT_FALSE(m.floating_base());
  for (const ArmLink& e : kArm) {
    SCOPED_TRACE(e.link);
    const Link& l = link_named(m, e.link);
    EXPECT_EQ(l.joint_name, e.joint);
    EXPECT_EQ(l.joint_type, JointType::revolute);
    EXPECT_EQ(l.mass, e.mass);
    EXPECT_EQ(l.com, Vec3(0, 0, e.com_z));
    EXPECT_EQ(l.inertia_com, diag(e.ixx, e.ixx, e.izz));
    EXPECT_EQ(l.axis, e.axis);
    EXPECT_EQ(l.tree_transform.r, Vec3(0, 0, e.joint_z));
    EXPECT_EQ(l.tree_transform.E, Mat3::Identity());
    const int d = l.v_index;
    EXPECT_EQ(m.lower_limit[d], e.lower);
    EXPECT_EQ(m.upper_limit[d], e.upper);
    EXPECT_EQ(m.effort_limit[d], e.effort);
    EXPECT_EQ(m.velocity_limit[d], e.velocity);
    EXPECT_EQ(m.damping[d], e.damping);
    EXPECT_EQ(m.friction[d], e.friction);
    EXPECT_EQ(robot.effort_limits.at(e.joint), e.effort);
  }
  // The root: "world" has no inertial; base_link (4 kg, com 0.05 up) is merged into it.
  const Link& root = m.links[0];
  EXPECT_EQ(root.name, "world");
  EXPECT_EQ(root.mass, 4.0);
  EXPECT_EQ(root.com, Vec3(0, 0, 0.05));
  EXPECT_EQ(root.inertia_com, diag(0.00973333, 0.00973333, 0.0128));
  EXPECT_EQ(robot.joint_order,
            (std::vector<std::string>{"world_to_base", "joint1", "joint2", "joint3", "joint4",
                                      "joint5", "joint6", "joint7", "hand_joint", "tcp_joint"}));
  EXPECT_EQ(robot.dof_order, (std::vector<int>{0, 1, 2, 3, 4, 5, 6}));
  EXPECT_TRUE(robot.mimics.empty());
}

TEST(Urdf, Arm7HandIsMergedIntoLink7ByTheParallelAxisTheorem) {
  const UrdfRobot robot = load_urdf(example("arm7.urdf"));
  const Link& l7 = link_named(*robot.model, "link7");
  // link7: 0.6 kg at z 0.03, diag(0.00042, 0.00042, 0.00048). hand: 0.8 kg, frame 0.06 up and
  // turned 45 degrees about z, centre 0.03 above its frame, so at z 0.09; box inertia
  // diag(a, b, c) = (0.00194667, 0.000666667, 0.00213333) turned by 45 degrees about z:
  // xx = yy = (a + b) / 2, xy = (a - b) / 2.
  const double a = 0.00194667, b = 0.000666667, c = 0.00213333;
  const double m = 1.4, z = (0.6 * 0.03 + 0.8 * 0.09) / 1.4;
  const double d7 = 0.03 - z, dh = 0.09 - z;  // offsets along z from the common centre
  Mat3 expected;
  expected << 0.00042 + (a + b) / 2 + 0.6 * d7 * d7 + 0.8 * dh * dh, (a - b) / 2, 0,  //
      (a - b) / 2, 0.00042 + (a + b) / 2 + 0.6 * d7 * d7 + 0.8 * dh * dh, 0,          //
      0, 0, 0.00048 + c;
  EXPECT_DOUBLE_EQ(l7.mass, m);
  EXPECT_NEAR(l7.com.z(), z, 1e-15);
  EXPECT_NEAR(l7.com.head<2>().norm(), 0.0, 1e-15);
  expect_mat_near(l7.inertia_com, expected, 1e-15);
  ASSERT_EQ(robot.merged.count("hand"), 1u);
  ASSERT_EQ(robot.merged.count("tcp"), 1u);
  EXPECT_EQ(robot.merged.at("hand").into, "link7");
  EXPECT_EQ(robot.merged.at("tcp").into, "link7");
  // tcp: 0.1 along the hand's z, which is link7's z.
  EXPECT_NEAR((robot.merged.at("tcp").xyz - Vec3(0, 0, 0.16)).norm(), 0.0, 1e-15);
  expect_mat_near(robot.merged.at("hand").rotation,
                  Eigen::AngleAxisd(std::numbers::pi / 4, Vec3::UnitZ()).toRotationMatrix(), 1e-15);
}

TEST(Urdf, SliderAndPendulumAreTheFilesValues) {
  const UrdfRobot slider = load_urdf(example("slider.urdf"));
  const Link& carriage = link_named(*slider.model, "carriage");
  EXPECT_EQ(carriage.joint_type, JointType::prismatic);
  EXPECT_EQ(carriage.axis, Vec3(0, 0, 1));
  EXPECT_EQ(carriage.mass, 2.5);
  const double i = 0.004166666666666667;
  EXPECT_EQ(carriage.inertia_com, diag(i, i, i));
  EXPECT_EQ(slider.model->lower_limit[0], -1.0);
  EXPECT_EQ(slider.model->upper_limit[0], 1.0);
  EXPECT_EQ(slider.model->effort_limit[0], 200.0);
  EXPECT_EQ(slider.model->velocity_limit[0], 10.0);
  EXPECT_EQ(slider.model->links[0].mass, 0.0);  // "base" has no inertial and is welded

  // A continuous joint is a revolute joint without limits.
  const UrdfRobot pendulum = load_urdf(example("pendulum.urdf"));
  const Link& bob = link_named(*pendulum.model, "bob");
  EXPECT_EQ(bob.joint_type, JointType::revolute);
  EXPECT_EQ(bob.axis, Vec3(0, 1, 0));
  EXPECT_EQ(bob.com, Vec3(0, 0, -0.5));
  EXPECT_EQ(bob.tree_transform.r, Vec3(0, 0, 1));
  EXPECT_EQ(bob.mass, 1.0);
  EXPECT_EQ(bob.inertia_com, diag(0.001, 0.001, 0.001));
  EXPECT_EQ(pendulum.model->lower_limit[0], -kInf);
  EXPECT_EQ(pendulum.model->upper_limit[0], kInf);
  EXPECT_EQ(pendulum.model->velocity_limit[0], kInf);
}

// examples/chain3.urdf written with ModelBuilder.
std::shared_ptr<const Model> chain3_by_hand() {
  ModelBuilder b;
  b.add_link(
      make_link("world", "", 2, Vec3::Zero(), diag(0.01, 0.01, 0.01), fixed_joint("root_joint")));
  const double mass[] = {1, 0.8, 0.6}, ixx[] = {0.0076, 0.00608, 0.00456},
               izz[] = {0.0002, 0.00016, 0.00012};
  const double effort[] = {50, 30, 20};
  for (int i = 0; i < 3; ++i) {
    const std::string n = std::to_string(i + 1);
    JointSpec j =
        revolute_joint("joint" + n, Vec3(0, 1, 0), i == 0 ? Vec3::Zero() : Vec3(0, 0, -0.3));
    j.lower_limit = -3;
    j.upper_limit = 3;
    j.effort_limit = effort[i];
    j.velocity_limit = 5;
    b.add_link(make_link("link" + n, i == 0 ? "world" : "link" + std::to_string(i), mass[i],
                         Vec3(0, 0, -0.15), diag(ixx[i], ixx[i], izz[i]), j));
  }
  return std::make_shared<const Model>(b.build());
}

class UrdfTwin : public ::testing::TestWithParam<SolverType> {};

TEST_P(UrdfTwin, Chain3FromUrdfAndByHandGiveBitwiseEqualTrajectories) {
  const UrdfRobot robot = load_urdf(example("chain3.urdf"));
  SimulationOptions o;
  o.solver = GetParam();
  Simulation from_file(robot.model, o), by_hand(chain3_by_hand(), o);
  VecX q0(3);
  q0 << 0.4, -0.3, 0.2;
  for (Simulation* s : {&from_file, &by_hand}) {
    s->set_q(q0);
    s->set_drive("joint1", Drive{DriveType::force, 200, 5, 40, 0.5, 0.0});
    s->set_drive("joint2", Drive{DriveType::acceleration, 300, 30, kInf, -0.2, 0.1});
    s->set_drive("joint3", Drive{DriveType::force, 50, 1, kInf, 0.0, 0.0});
  }
  for (int k = 0; k < 100; ++k) {
    from_file.step();
    by_hand.step();
  }
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(from_file.q()[i], by_hand.q()[i]) << "q[" << i << "]";
    EXPECT_EQ(from_file.qd()[i], by_hand.qd()[i]) << "qd[" << i << "]";
  }
  EXPECT_GT(std::abs(from_file.q()[0] - q0[0]), 1e-3);  // it moved
}

INSTANTIATE_TEST_SUITE_P(Solvers, UrdfTwin, ::testing::Values(SolverType::pgs, SolverType::tgs),
                         [](const auto& p) { return std::string(to_string(p.param)); });

TEST(Urdf, FixedJointMergesTwoBoxesAsWorkedOutByHand) {
  const UrdfRobot robot = load_urdf(data("two_boxes.urdf"));
  const Model& m = *robot.model;
  ASSERT_EQ(m.num_links(), 3);  // base, a (with b), c
  const Link& a = link_named(m, "a");
  // b's centre in a: (0.3, 0, 0) + Rz(90)(0.1, 0, 0) = (0.3, 0.1, 0); with a's (0, 0, 0), weights
  // 1 and 2: com = (0.2, 1/15, 0). Offsets from it: a (-0.2, -1/15, 0), b (0.1, 1/30, 0).
  // Ia = diag(1/600, 1/240, 1/240); Ib turned 90 degrees about z swaps xx and yy:
  // diag(1/30, 1/120, 17/600). Parallel axis m (|d|^2 1 - d d^T):
  //   xx: 1/600 + 1/30 + 1 (1/225) + 2 (1/900)       = 75/1800  = 1/24
  //   yy: 1/240 + 1/120 + 1 (0.04) + 2 (0.01)         = 0.0725
  //   zz: 1/240 + 17/600 + (0.04 + 1/225) + 2 (0.01 + 1/900) = 357/3600
  //   xy: -1 (-0.2)(-1/15) - 2 (0.1)(1/30)            = -1/75 - 1/150 = -0.02
  EXPECT_DOUBLE_EQ(a.mass, 3.0);
  EXPECT_NEAR((a.com - Vec3(0.2, 1.0 / 15, 0)).norm(), 0.0, 1e-15);
  Mat3 expected;
  expected << 1.0 / 24, -0.02, 0, -0.02, 0.0725, 0, 0, 0, 357.0 / 3600;
  expect_mat_near(a.inertia_com, expected, 1e-15);

  // c hangs off b: re-attached to a at (0.3, 0, 0) + Rz(90)(0.1, 0, 0.05), turned 90 degrees.
  const Link& c = link_named(m, "c");
  EXPECT_EQ(m.links[c.parent].name, "a");
  EXPECT_NEAR((c.tree_transform.r - Vec3(0.3, 0.1, 0.05)).norm(), 0.0, 1e-15);
  expect_mat_near(c.tree_transform.E.transpose(),
                  Eigen::AngleAxisd(std::numbers::pi / 2, Vec3::UnitZ()).toRotationMatrix(), 1e-15);
  EXPECT_EQ(c.axis, Vec3(1, 0, 0));
  ASSERT_EQ(robot.merged.count("b"), 1u);
  EXPECT_EQ(robot.merged.at("b").into, "a");
  EXPECT_EQ(robot.merged.at("b").xyz, Vec3(0.3, 0, 0));
}

TEST(Urdf, DofOrderFollowsTheDocumentAndMimicTagsAreReportedNotSimulated) {
  const UrdfRobot robot = load_urdf(data("branches.urdf"));
  const Model& m = *robot.model;
  // Depth-first: right1, right2, left.
  EXPECT_EQ(m.dof_names, (std::vector<std::string>{"right1", "right2", "left"}));
  // Document: right1, left, right2.
  ASSERT_EQ(robot.dof_order.size(), 3u);
  EXPECT_EQ(m.dof_names[robot.dof_order[0]], "right1");
  EXPECT_EQ(m.dof_names[robot.dof_order[1]], "left");
  EXPECT_EQ(m.dof_names[robot.dof_order[2]], "right2");
  ASSERT_EQ(robot.mimics.size(), 1u);
  EXPECT_EQ(robot.mimics[0].joint, "left");
  EXPECT_EQ(robot.mimics[0].leader, "right1");
  EXPECT_EQ(robot.mimics[0].multiplier, -0.5);
  EXPECT_EQ(robot.mimics[0].offset, 0.01);
  bool warned = false;
  for (const std::string& w : robot.warnings)
    warned = warned || (w.find("'left'") != std::string::npos &&
                        w.find("not simulated") != std::string::npos);
  EXPECT_TRUE(warned);
  const int r2 = m.dof_index("right2");
  EXPECT_EQ(m.damping[r2], 0.3);
  EXPECT_EQ(m.friction[r2], 0.1);
  EXPECT_EQ(m.lower_limit[r2], -kInf);
  // The simulation starts its joint friction from <dynamics>.
  const Simulation sim(robot.model);
  EXPECT_EQ(sim.joint_friction(r2).static_effort, 0.1);
  EXPECT_EQ(sim.joint_friction(r2).viscous, 0.3);
}

TEST(Urdf, FloatingRootComesFirstInTheDofOrder) {
  UrdfOptions options;
  options.fixed_base = false;
  options.gravity = Vec3(0, 0, -1.62);
  const UrdfRobot robot = load_urdf(example("chain3.urdf"), options);
  const Model& m = *robot.model;
  EXPECT_TRUE(m.floating_base());
  EXPECT_EQ(m.nv, 9);
  EXPECT_EQ(m.gravity, Vec3(0, 0, -1.62));
  EXPECT_EQ(robot.dof_order, (std::vector<int>{0, 1, 2, 3, 4, 5, 6, 7, 8}));
  // A floating root needs an inertial of its own (after merging).
  EXPECT_THROW(load_urdf(example("slider.urdf"), options), InputError);
}

TEST(Urdf, ErrorsNameTheFileAndAreInvalidArgument) {
  try {
    load_urdf(data("malformed/planar_joint.urdf"));
    FAIL() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("planar_joint.urdf"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("'plane'"), std::string::npos) << e.what();
  }
  EXPECT_THROW(load_urdf(data("does_not_exist.urdf")), InputError);
  EXPECT_THROW(parse_urdf("<robot name='x'><link name='a'/>", "inline.urdf"), InputError);
}

TEST(Urdf, RpyFromRotationInvertsRotationFromRpy) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> angle(-3.1, 3.1), pitch(-1.55, 1.55);
  for (int k = 0; k < 200; ++k) {
    const Vec3 rpy(angle(rng), pitch(rng), angle(rng));
    const Mat3 R = rotation_from_rpy(rpy);
    expect_mat_near(rotation_from_rpy(rpy_from_rotation(R)), R, 1e-14);
  }
  // Gimbal lock: only the rotation is defined, not the angles.
  for (double p : {std::numbers::pi / 2, -std::numbers::pi / 2}) {
    const Mat3 R = rotation_from_rpy(Vec3(0.3, p, -0.5));
    expect_mat_near(rotation_from_rpy(rpy_from_rotation(R)), R, 1e-14);
  }
}

}  // namespace
}  // namespace featherdrive
