// URDF import against the numbers written in the shipped files, a hand-built twin, and fixed-joint
// merging worked out by hand.
#include "featherdrive/io/urdf.hpp"

#include <gtest/gtest.h>

#include <pthread.h>

#include <functional>
#include <numbers>
#include <random>

#include "featherdrive/io/describe.hpp"
#include "featherdrive/io/trajectory.hpp"
#include "featherdrive/sim/simulation.hpp"
#include "support/compare.hpp"

namespace featherdrive {
namespace {

using test::kInf;
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

TEST(Urdf, DofOrderFollowsTheDocumentAndMimicTagsBecomeMimicJoints) {
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
  // left = -0.5 right1 + 0.01 is the row left + 0.5 right1 - 0.01 = 0.
  ASSERT_EQ(robot.mimic_joints.size(), 1u);
  EXPECT_EQ(robot.mimic_joints[0].dof_a, m.dof_index("left"));
  EXPECT_EQ(robot.mimic_joints[0].dof_b, m.dof_index("right1"));
  EXPECT_EQ(robot.mimic_joints[0].gear_ratio, 0.5);
  EXPECT_EQ(robot.mimic_joints[0].offset, -0.01);
  EXPECT_TRUE(robot.warnings.empty());
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

// The file lists l_knee, neck (fixed), l_hip, waist, head_tilt; the model orders links depth
// first, children in the file's link order: body, torso (+ head merged), camera, l_thigh, l_shin,
// so the dofs are waist, head_tilt, l_hip, l_knee (worked out by hand from the file).
TEST(Urdf, FileJointOrderAndDofOrderMapBothWays) {
  for (const bool floating : {false, true}) {
    UrdfOptions options;
    options.fixed_base = !floating;
    const UrdfRobot robot = load_urdf(data("leaf_joint_first.urdf"), options);
    const Model& m = *robot.model;
    const int o = floating ? 6 : 0;  // a floating root's dofs come first
    EXPECT_EQ(robot.joint_order,
              (std::vector<std::string>{"l_knee", "neck", "l_hip", "waist", "head_tilt"}));
    std::vector<std::string> names(m.dof_names.begin() + o, m.dof_names.end());
    EXPECT_EQ(names, (std::vector<std::string>{"waist", "head_tilt", "l_hip", "l_knee"}));
    EXPECT_EQ(robot.dof_of_urdf_joint, (std::vector<int>{o + 3, -1, o + 2, o + 0, o + 1}));
    EXPECT_EQ(robot.link_of_urdf_joint, (std::vector<int>{4, 1, 3, 1, 2}));
    EXPECT_EQ(m.links[robot.link_of_urdf_joint[1]].name, "torso");  // head merged into torso
    std::vector<int> joint_of_dof(static_cast<size_t>(o), -1);
    for (const int j : {3, 4, 2, 0}) joint_of_dof.push_back(j);
    EXPECT_EQ(robot.urdf_joint_of_dof, joint_of_dof);
    std::vector<int> dof_order;
    for (int d = 0; d < o; ++d) dof_order.push_back(d);
    for (const int d : {3, 2, 0, 1}) dof_order.push_back(o + d);
    EXPECT_EQ(robot.dof_order, dof_order);
    // Every table follows the file's order: the CSV header and describe's dof line.
    std::vector<std::string> columns = trajectory_columns(robot);
    columns.erase(columns.begin(), columns.begin() + (floating ? 7 : 0));
    EXPECT_EQ(columns[0], "q:l_knee");
    EXPECT_EQ(columns[3], "q:head_tilt");
    EXPECT_EQ(columns[4 + o], "qd:l_knee");
    EXPECT_EQ(columns.back(), "f:head_tilt");
    EXPECT_NE(describe(robot).find("dofs in the file's order:" +
                                   std::string(floating ? " " + robot.root_joint + ":wx" : "")),
              std::string::npos);
    EXPECT_NE(describe(robot).find("l_knee l_hip waist head_tilt\n"), std::string::npos);
  }
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

// Runs f on a thread with a 256 KiB stack: recursion per link or per element would overflow it
// long before 10 000 levels. Returns f's exception message, or "" when it returned.
std::string on_small_stack(const std::function<void()>& f) {
  struct Job {
    const std::function<void()>* f;
    std::string error;
  } job{&f, ""};
  pthread_attr_t attr;
  pthread_attr_init(&attr);
  pthread_attr_setstacksize(&attr, 256 * 1024);
  pthread_t thread;
  const auto run = [](void* p) -> void* {
    auto* j = static_cast<Job*>(p);
    try {
      (*j->f)();
    } catch (const std::exception& e) {
      j->error = e.what();
    }
    return nullptr;
  };
  EXPECT_EQ(pthread_create(&thread, &attr, run, &job), 0);
  pthread_join(thread, nullptr);
  pthread_attr_destroy(&attr);
  return job.error;
}

std::string urdf_error(const std::string& xml) {
  std::string e;
  try {
    parse_urdf(xml, "inline.urdf");
  } catch (const InputError& error) {
    e = error.what();
  }
  return e;
}

const std::string kInertial =
    "<inertial><mass value='1'/><inertia ixx='0.01' ixy='0' ixz='0' iyy='0.01' iyz='0' "
    "izz='0.01'/></inertial>";

// A robot whose root link holds `inside` (unknown elements urdfdom skips) after its inertial.
std::string robot_with(const std::string& inside) {
  return "<robot name='r'><link name='base'>" + kInertial + inside + "</link></robot>";
}

// n links on `type` joints, each hanging 0.1 m below the last; link names count down when
// `reversed` (so the map order of urdfdom's links is the opposite of the tree's).
std::string chain_urdf(int n, const std::string& type, bool reversed = false) {
  const auto link = [&](int i) { return "l" + std::to_string(reversed ? n - i : i); };
  std::string xml = "<robot name='chain'>\n<link name='" + link(0) + "'>" + kInertial + "</link>\n";
  for (int i = 1; i <= n; ++i)
    xml += "<joint name='j" + std::to_string(i) + "' type='" + type + "'><parent link='" +
           link(i - 1) + "'/><child link='" + link(i) +
           "'/><origin xyz='0 0 -0.1'/><axis xyz='0 1 0'/>"
           "<limit lower='-1' upper='1' effort='1' velocity='1'/></joint>\n<link name='" +
           link(i) + "'>" + kInertial + "</link>\n";
  return xml + "</robot>\n";
}

TEST(Urdf, DocumentsNestedDeeperThanTheBoundAreRefusedBeforeAnyReaderRecurses) {
  ASSERT_EQ(kMaxUrdfDepth, 100);
  const auto nested = [](int depth, const std::string& open) {
    std::string s;
    for (int i = 0; i < depth; ++i) s += open;
    return s;
  };
  // <robot> and <link> are 2 levels: 98 more reach the bound, 99 pass it (line 1, no newline).
  const std::string deeper = "inline.urdf: line 1: elements nested deeper than 100 (the bound)";
  EXPECT_EQ(urdf_error(robot_with(nested(99, "<a>"))), deeper);
  EXPECT_EQ(on_small_stack([&] { parse_urdf(robot_with(nested(100000, "<a>")), "inline.urdf"); }),
            deeper);
  // Unclosed, attributes with '>' and '/', whitespace and newlines inside tags.
  EXPECT_EQ(on_small_stack([&] {
              parse_urdf("<robot name='r'>\n" + nested(100000, "<a b=\"x>/y\" c='/>'\n>"),
                         "x.urdf");
            }),
            "x.urdf: line 101: elements nested deeper than 100 (the bound)");
  // Closing tags in comments, CDATA or processing instructions close nothing.
  EXPECT_EQ(urdf_error(robot_with(nested(50, "<a>") + "<!-- " + nested(60, "</a>") + " -->" +
                                  "<![CDATA[" + nested(60, "</a>") + "]]>" + nested(60, "<b>"))),
            deeper);
  // Exactly at the bound, with the same constructs around: loads.
  std::string at_bound = nested(98, "<a>") + nested(98, "</a>");
  at_bound += "<!-- <a><a><a> --><![CDATA[<a><a>]]><?pi data?><c x='>'/><c/><c />";
  const std::string xml = "<?xml version='1.0'?>\n<!DOCTYPE robot>\n" + robot_with(at_bound);
  EXPECT_EQ(on_small_stack([&] { EXPECT_EQ(parse_urdf(xml, "ok.urdf").model->nv, 0); }), "");
  // Many siblings are not depth: 100 000 self-closing and empty elements load.
  EXPECT_EQ(on_small_stack([&] {
              parse_urdf(robot_with(nested(50000, "<c/>") + nested(50000, "<d></d>")), "w.urdf");
            }),
            "");
}

TEST(Urdf, ALinkThatIsTheChildOfTwoJointsIsRefusedNamingBoth) {
  const auto joint = [](const std::string& name, const std::string& parent,
                        const std::string& child) {
    return "<joint name='" + name + "' type='revolute'><parent link='" + parent +
           "'/><child link='" + child +
           "'/><axis xyz='0 0 1'/><limit lower='-1' upper='1' effort='1' velocity='1'/></joint>";
  };
  const auto link = [](const std::string& name) {
    return "<link name='" + name + "'>" + kInertial + "</link>";
  };
  const std::string abc = link("a") + link("b") + link("c");
  // Two parents, no cycle.
  EXPECT_EQ(urdf_error("<robot name='r'>" + abc + joint("j1", "a", "b") + joint("j2", "c", "b") +
                       "</robot>"),
            "inline.urdf: link 'b' is the child of two joints, 'j1' and 'j2'");
  // A cycle reached through b's second parent (the importer used to loop forever).
  EXPECT_EQ(urdf_error("<robot name='r'>" + abc + joint("j1", "a", "b") + joint("j2", "b", "c") +
                       joint("j3", "c", "b") + "</robot>"),
            "inline.urdf: link 'b' is the child of two joints, 'j1' and 'j3'");
  // The root itself reached again from below, the second joint first in the document.
  EXPECT_EQ(urdf_error("<robot name='r'>" + abc + joint("up", "c", "b") + joint("j1", "a", "b") +
                       joint("j2", "b", "c") + "</robot>"),
            "inline.urdf: link 'b' is the child of two joints, 'up' and 'j1'");
  // A cycle with one parent each has no root: still the cycle message, found in O(n).
  std::string ring = "<robot name='r'>";
  for (int i = 0; i < 20000; ++i)
    ring += link("r" + std::to_string(i)) + joint("k" + std::to_string(i), "r" + std::to_string(i),
                                                  "r" + std::to_string((i + 1) % 20000));
  EXPECT_NE(
      urdf_error(ring + "</robot>").find("inline.urdf: the joints form a cycle through link 'r"),
      std::string::npos);
}

TEST(Urdf, LongChainsImportAndDescribeWithoutRecursion) {
  // Names counting down: urdfdom's map frees the leaf first and the root last, which freed the
  // whole chain recursively from the root.
  const std::string xml = chain_urdf(10000, "revolute", /*reversed=*/true);
  std::string text;
  EXPECT_EQ(on_small_stack([&] {
              const UrdfRobot robot = parse_urdf(xml, "chain.urdf");
              EXPECT_EQ(robot.model->nv, 10000);
              EXPECT_EQ(robot.model->links.back().parent, 9999);
              text = describe(robot);
            }),
            "");
  // Indentation stops at depth 32; deeper links say their depth: the output grows linearly.
  EXPECT_NE(text.find("\n" + std::string(64, ' ') + "- (depth 10000) l0  <- j10000: revolute"),
            std::string::npos);
  EXPECT_NE(text.find(std::string(64, ' ') + "- l"), std::string::npos);
  EXPECT_EQ(text.find(std::string(64 + 2, ' ') + "- "), std::string::npos);
  EXPECT_LT(text.size(), 10001u * 500u);
  EXPECT_NE(text.find("total mass 10001 kg"), std::string::npos);
}

// Fixed joints merge the whole chain into the root, walked without recursion too.
TEST(Urdf, LongChainsOfFixedJointsMergeWithoutRecursion) {
  EXPECT_EQ(on_small_stack([] {
              const UrdfRobot robot = parse_urdf(chain_urdf(10000, "fixed"), "fixed.urdf");
              EXPECT_EQ(robot.model->num_links(), 1);
              EXPECT_EQ(robot.merged.size(), 10000u);
              EXPECT_NEAR(robot.model->links[0].mass, 10001.0, 1e-9);
              // The centre of mass of 10 001 equal masses at 0, -0.1, ..., -1000 m: -500 m.
              EXPECT_NEAR(robot.model->links[0].com.z(), -500.0, 1e-7);
            }),
            "");
}

TEST(Urdf, NamesWithControlCharactersAreRefused) {
  const auto named = [](const std::string& link_name, const std::string& joint_name) {
    return "<robot name='r'><link name='base'/><link name='" + link_name + "'>" + kInertial +
           "</link><joint name='" + joint_name +
           "' type='continuous'><parent link='base'/>"
           "<child link='" +
           link_name + "'/></joint></robot>";
  };
  EXPECT_EQ(urdf_error(named("a&#10;b", "j")),
            "inline.urdf: link name 'a\\x0ab' contains a control character (0x0a)");
  EXPECT_EQ(urdf_error(named("a", "j&#9;1")),
            "inline.urdf: joint name 'j\\x091' contains a control character (0x09)");
  EXPECT_EQ(urdf_error(named("a", "j&#13;")),
            "inline.urdf: joint name 'j\\x0d' contains a control character (0x0d)");
  EXPECT_EQ(urdf_error(named("a\x1f", "j")),
            "inline.urdf: link name 'a\\x1f' contains a control character (0x1f)");
  EXPECT_EQ(urdf_error(named("\x7f", "j")),
            "inline.urdf: link name '\\x7f' contains a control character (0x7f)");
  // Commas, quotes and non-ASCII letters are names like any other.
  EXPECT_EQ(parse_urdf(named("a,b \"c\" \xc3\xa9", "j,1"), "ok.urdf").model->nv, 1);
}

// urdfdom refuses non-finite <limit> values itself ("is not a valid float"); the importer's own
// check holds for readers that accept them. A joint without limits is written as continuous.
TEST(Urdf, LimitsOfInfAreRefused) {
  const auto limited = [](const std::string& lower, const std::string& upper) {
    return "<robot name='r'><link name='base'/><link name='a'>" + kInertial +
           "</link><joint name='j' type='revolute'><parent link='base'/><child link='a'/>"
           "<limit lower='" +
           lower + "' upper='" + upper +
           "' effort='1' velocity='1'/>"
           "</joint></robot>";
  };
  for (const auto& [lower, upper] : {std::pair{"inf", "inf"}, std::pair{"-1", "-inf"},
                                     std::pair{"1e999", "2e999"}, std::pair{"-inf", "-inf"}}) {
    SCOPED_TRACE(std::string(lower) + " " + upper);
    const std::string e = urdf_error(limited(lower, upper));
    EXPECT_EQ(e.rfind("inline.urdf: invalid URDF: ", 0), 0u) << e;
    EXPECT_NE(e.find("joint [j]"), std::string::npos) << e;
  }
}

TEST(Urdf, InertialsThatOverflowAreRefusedNamingTheLinkAndTheValue) {
  const auto robot = [](const std::string& mass, const std::string& origin,
                        const std::string& joint_type) {
    return "<robot name='r'><link name='base'>" + kInertial +
           "</link><link name='hand'><inertial><origin xyz='" + origin + "'/><mass value='" + mass +
           "'/><inertia ixx='1' ixy='0' ixz='0' iyy='1' iyz='0' izz='1'/></inertial>"
           "</link><joint name='j' type='" +
           joint_type +
           "'><parent link='base'/>"
           "<child link='hand'/><axis xyz='0 0 1'/></joint></robot>";
  };
  // Merged: the parallel axis shift m d^2 overflows (it used to say "inertia(0,0) = -nan").
  EXPECT_EQ(urdf_error(robot("1e10", "1e200 0 0", "fixed")),
            "inline.urdf: link 'hand' <inertial><origin xyz> = [1e+200, 0, 0], mass 1e+10: merged "
            "into link 'base' (fixed joints), the combined inertia overflows");
  // Merged into a finite body, then too heavy for the model's sums (3 m in the spatial inertia).
  EXPECT_EQ(urdf_error(robot("1.7e308", "0 0 0", "fixed")),
            "inline.urdf: link 'base': mass = 1.7e+308, inertia [1.01, 1.01, 1.01]: the model's "
            "total mass or inertia overflows");
  // Moving: the spatial inertia m c c^T, or the model's total mass.
  EXPECT_EQ(urdf_error(robot("1e10", "0 1e150 0", "continuous")),
            "inline.urdf: link 'hand': mass = 1e+10 at com = [0, 1e+150, 0]: the spatial inertia "
            "(m c, m c c^T) overflows");
  const std::string two_heavy =
      "<robot name='r'><link name='base'><inertial><mass value='5e307'/><inertia ixx='1' "
      "ixy='0' ixz='0' iyy='1' iyz='0' izz='1'/></inertial></link><link name='hand'><inertial>"
      "<mass value='5e307'/><inertia ixx='1' ixy='0' ixz='0' iyy='1' iyz='0' izz='1'/>"
      "</inertial></link><joint name='j' type='continuous'><parent link='base'/>"
      "<child link='hand'/></joint></robot>";
  EXPECT_NE(urdf_error(two_heavy).find(
                "inline.urdf: link 'hand': mass = 5e+307, inertia [1, 1, 1]: the model's total"),
            std::string::npos);
  // Heavy but summable: describe prints the finite total.
  const UrdfRobot ok = parse_urdf(robot("1e300", "0 0 0", "continuous"), "ok.urdf");
  EXPECT_NE(describe(ok).find("total mass 1e+300 kg"), std::string::npos) << describe(ok);
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

// UrdfOptions::effort: the slider's <limit effort="200"> as every drive's max_force or every
// explicit actuator's effort_limit, only where they have none of their own.
TEST(Urdf, EffortLimitBecomesMaxForceOrTheActuatorsClipByOption) {
  for (UrdfEffort mode : {UrdfEffort::none, UrdfEffort::max_force, UrdfEffort::effort_limit}) {
    UrdfOptions options;
    options.effort = mode;
    const UrdfRobot robot = load_urdf(kSource + "/examples/slider.urdf", options);
    Simulation driven(robot.model), limited(robot.model), actuated(robot.model);
    driven.set_drive(0, Drive{DriveType::force, 10.0, 1.0});
    limited.set_drive(0, Drive{DriveType::force, 10.0, 1.0, 50.0});
    ExplicitActuator a;
    a.kind = ActuatorKind::ideal_pd;
    actuated.set_actuator(0, a);
    for (Simulation* s : {&driven, &limited, &actuated}) apply_urdf_effort_limits(robot, *s);
    EXPECT_EQ(driven.drive(0).max_force, mode == UrdfEffort::max_force ? 200.0 : kInf)
        << to_string(mode);
    EXPECT_EQ(limited.drive(0).max_force, 50.0);
    EXPECT_EQ(actuated.actuator(0).effort_limit, mode == UrdfEffort::effort_limit ? 200.0 : kInf)
        << to_string(mode);
    EXPECT_EQ(actuated.drive(0).max_force, kInf);
  }
}

}  // namespace
}  // namespace featherdrive
