// Spherical joints from files: URDF type="spherical" and "ball" (an extension read before
// urdfdom), the scene's per-axis keys (`<joint>:twist`, `:swing1`, `:swing2`), the trajectory's
// columns, and the one-line errors for bad axis names and limits outside [-pi, pi].
#include <gtest/gtest.h>

#include <sstream>

#include "featherdrive/constraint/spherical_axes.hpp"
#include "featherdrive/io/checkpoint.hpp"
#include "featherdrive/io/scene.hpp"
#include "featherdrive/io/trajectory.hpp"
#include "featherdrive/io/urdf.hpp"
#include "support/compare.hpp"
#include "support/source_tree.hpp"

namespace featherdrive {
namespace {

using test::kExamples;

std::string scene_error(const std::string& text) {
  try {
    parse_scene(text, kExamples + "inline.yaml");
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(SphericalImport, UrdfSphericalJointHasThreeNamedAxesInItsRotatedFrame) {
  const UrdfRobot robot = load_urdf(kExamples + "spherical_wrist.urdf");
  const Model& m = *robot.model;
  ASSERT_EQ(m.nv, 4);
  ASSERT_EQ(m.nq, 5);
  const Link& hand = m.links[m.joint_link_index("wrist")];
  EXPECT_EQ(hand.joint_type, JointType::spherical);
  EXPECT_EQ(std::vector<std::string>(m.dof_names.begin() + 1, m.dof_names.end()),
            (std::vector<std::string>{"wrist:twist", "wrist:swing1", "wrist:swing2"}));
  // The joint frame is the origin's rpy (fixed-axis roll, pitch, yaw) in the arm's frame.
  const Mat3 R = (Eigen::AngleAxisd(-0.3, Vec3::UnitZ()) * Eigen::AngleAxisd(0.1, Vec3::UnitY()) *
                  Eigen::AngleAxisd(0.2, Vec3::UnitX()))
                     .toRotationMatrix();
  EXPECT_LT((hand.tree_transform.E.transpose() - R).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_LT((hand.tree_transform.r - Vec3(0, 0, -0.4)).norm(), 1e-15);
  for (int d = 1; d < 4; ++d) {
    EXPECT_EQ(m.velocity_limit[d], 8.0);
    EXPECT_EQ(m.effort_limit[d], 20.0);
    EXPECT_EQ(robot.urdf_joint_of_dof[static_cast<size_t>(d)], 1);  // the file's second joint
  }
  EXPECT_EQ(robot.dof_order, (std::vector<int>{0, 1, 2, 3}));
  EXPECT_EQ(trajectory_columns(robot),
            (std::vector<std::string>{"q:shoulder", "q:wrist:twist", "q:wrist:swing1",
                                      "q:wrist:swing2", "qd:shoulder", "qd:wrist:twist",
                                      "qd:wrist:swing1", "qd:wrist:swing2", "f:shoulder",
                                      "f:wrist:twist", "f:wrist:swing1", "f:wrist:swing2"}));
}

TEST(SphericalImport, BallIsASynonymAndPositionLimitsAreLeftToTheScene) {
  const std::string xml =
      "<robot name='r'><link name='a'/><link name='b'><inertial><mass value='1'/>"
      "<inertia ixx='1' ixy='0' ixz='0' iyy='1' iyz='0' izz='1'/></inertial></link>"
      "<joint name='j' type='ball'><parent link='a'/><child link='b'/>"
      "<limit lower='-1' upper='1' effort='0' velocity='0'/></joint></robot>";
  const UrdfRobot robot = parse_urdf(xml, "ball.urdf");
  EXPECT_EQ(robot.model->links[1].joint_type, JointType::spherical);
  EXPECT_EQ(robot.model->dof_names[0], "j:twist");
  bool warned = false;
  for (const std::string& w : robot.warnings)
    warned = warned || w.find("joint 'j' is spherical: <limit lower upper> is not read") !=
                           std::string::npos;
  EXPECT_TRUE(warned);
}

TEST(SphericalImport, SceneSetsEachAxisAndStartsAtPhysxsPositions) {
  const Scene scene = load_scene(kExamples + "spherical_wrist.yaml");
  Simulation sim = make_simulation(scene);
  const Model& m = sim.model();
  const int twist = m.dof_index("wrist:twist");
  EXPECT_EQ(twist, 1);
  EXPECT_EQ(m.dof_index("wrist:swing2"), 3);
  EXPECT_EQ(sim.drive(twist).stiffness, 20.0);
  EXPECT_EQ(sim.drive(3).type, DriveType::acceleration);
  EXPECT_EQ(sim.lower_limit(2), -0.25);
  EXPECT_EQ(sim.upper_limit(2), 0.375);
  EXPECT_EQ(sim.qd()[3], 1.0);
  // The initial rotation is exp(0.2 e_x - 0.1 e_y): its PhysX positions are those numbers.
  const double* x = sim.q().data() + m.links[m.dof_link[twist]].q_index;
  const Vec3 theta = spherical_joint_positions(Quat(x[0], x[1], x[2], x[3]));
  EXPECT_LT((theta - Vec3(0.2, -0.1, 0.0)).norm(), 1e-15);
}

TEST(SphericalImport, ArmatureIsPerAxis) {
  const Scene scene = parse_scene(
      "model: spherical_wrist.urdf\nsteps: 1\njoints: {wrist:swing1: {armature: 0.05}}\n",
      kExamples + "inline.yaml");
  const Model& m = *scene.model();
  EXPECT_EQ(m.armature[1], 0.0);
  EXPECT_EQ(m.armature[2], 0.05);
  EXPECT_EQ(m.armature[3], 0.0);
}

TEST(SphericalImport, CsvRowsGivePhysxPositionsAndCheckpointsKeepTheAxes) {
  const Scene scene = load_scene(kExamples + "spherical_wrist.yaml");
  Simulation sim = make_simulation(scene);
  std::ostringstream csv;
  TrajectoryWriter writer(csv, scene.robot);
  writer.write(0, sim, true);
  // step, t, q:shoulder, then the wrist's positions: the scene's initial 0.2, -0.1, 0.
  const std::string row = csv.str().substr(csv.str().find('\n') + 1);
  EXPECT_EQ(row.substr(0, row.find(",0,0,0,1,")), "0,0,0,0.2,-0.1,0");
  // Per-axis settings survive a checkpoint bit for bit, and a step after it matches.
  sim.set_max_joint_velocity("wrist:swing2", 3.0);
  sim.step();
  const std::string bytes = checkpoint_bytes(sim);
  Simulation other = make_simulation(scene);
  restore_checkpoint(bytes, other, "wrist.ckpt");
  EXPECT_EQ(checkpoint_bytes(other), bytes);
  EXPECT_EQ(other.max_joint_velocity(3), 3.0);
  EXPECT_EQ(other.upper_limit(2), 0.375);
  sim.step();
  other.step();
  EXPECT_EQ(checkpoint_bytes(other), checkpoint_bytes(sim));
}

TEST(SphericalImport, BadAxisNamesAndLimitsAreOneLineErrors) {
  const std::string head = "model: spherical_wrist.urdf\nsteps: 1\n";
  EXPECT_EQ(scene_error(head + "joints: {wrist:twist: {lower: -4, upper: 1}}"),
            kExamples + "inline.yaml: limits on joint 'wrist:twist': lower = -4 is outside "
                        "[-pi, pi], where a spherical axis's position lies");
  EXPECT_EQ(scene_error(head + "drives: {wrist: {type: force, stiffness: 1}}"),
            kExamples + "inline.yaml: drives.wrist: joint 'wrist' is spherical: name one of its "
                        "axes, 'wrist:twist', 'wrist:swing1' or 'wrist:swing2'");
  EXPECT_EQ(scene_error(head + "drives: {wrist:tilt: {type: force, stiffness: 1}}"),
            kExamples + "inline.yaml: drives.wrist:tilt: no joint named 'wrist:tilt' in "
                        "spherical_wrist.urdf (moving joints: shoulder, wrist:twist, "
                        "wrist:swing1, wrist:swing2)");
  for (const std::string& error :
       {scene_error(head + "joints: {wrist:twist: {lower: -4, upper: 1}}"),
        scene_error(head + "drives: {wrist:tilt: {type: force, stiffness: 1}}")})
    EXPECT_EQ(error.find('\n'), std::string::npos);
}

}  // namespace
}  // namespace featherdrive
