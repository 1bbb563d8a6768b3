// Settings as the importers return them (robot_settings for URDF and MJCF, scene_settings), and
// simulations and batches built from a Settings value. The expectations are the files' own values.
#include <gtest/gtest.h>

#include <limits>
#include <string>

#include "featherdrive/io/mjcf.hpp"
#include "featherdrive/io/scene.hpp"
#include "featherdrive/io/urdf.hpp"
#include "featherdrive/sim/batch.hpp"
#include "featherdrive/sim/simulation.hpp"
#include "support/source_tree.hpp"

namespace featherdrive {
namespace {

using test::kExamples;
using test::kSourceDir;
constexpr double kInf = std::numeric_limits<double>::infinity();

// tests/data/branches.urdf: "left" (prismatic, limits [0, 0.1], velocity 0.5) mimics "right1"
// with multiplier -0.5 and offset 0.01, which is the row left + 0.5 right1 - 0.01 = 0.
TEST(RobotSettings, UrdfGivesTheModelsLimitsAndItsMimicRows) {
  const UrdfRobot robot = load_urdf(kSourceDir + "/tests/data/branches.urdf");
  const Model& model = *robot.model;
  SimulationOptions options;
  options.dt = 0.002;
  const Settings s = robot_settings(robot, options);
  EXPECT_EQ(s.options.dt, 0.002);
  const int left = model.links[model.joint_link_index("left")].v_index;
  const int right1 = model.links[model.joint_link_index("right1")].v_index;
  EXPECT_EQ(s.lower_limit[left], 0.0);
  EXPECT_EQ(s.upper_limit[left], 0.1);
  EXPECT_EQ(s.max_joint_velocity[left], 0.5);
  EXPECT_EQ(s.lower_limit[right1], -1.0);
  ASSERT_EQ(s.mimic_joints.size(), 1u);
  EXPECT_EQ(s.mimic_joints[0].dof_a, left);
  EXPECT_EQ(s.mimic_joints[0].dof_b, right1);
  EXPECT_EQ(s.mimic_joints[0].gear_ratio, 0.5);
  EXPECT_EQ(s.mimic_joints[0].offset, -0.01);
  // A simulation and a batch built from the value hold it.
  const Simulation sim(robot.model, s);
  EXPECT_EQ(sim.mimic_joints().size(), 1u);
  EXPECT_EQ(sim.options().dt, 0.002);
  Batch batch(robot.model, 3, s);
  EXPECT_EQ(batch.sim(2).mimic_joints().size(), 1u);
  EXPECT_EQ(batch.sim(2).max_joint_velocity(left), 0.5);
}

// Two position and velocity actuators on one hinge (gear 2) are one ideal_pd actuator of
// stiffness kp gear^2 and damping kv gear^2; a forcerange of +-3 on the actuator bounds the
// joint's effort at gear * 3.
TEST(RobotSettings, MjcfGivesItsActuators) {
  const char* const xml = R"(<mujoco>
  <worldbody>
    <body name="a"><joint name="hinge" axis="0 1 0"/><geom size=".1"/></body>
  </worldbody>
  <actuator>
    <position name="p" joint="hinge" kp="50" gear="2"/>
    <velocity name="v" joint="hinge" kv="4" gear="2"/>
  </actuator>
</mujoco>)";
  const MjcfRobot robot = parse_mjcf(xml, "pd.xml");
  const Settings s = robot_settings(robot);
  EXPECT_EQ(s.actuators[0].kind, ActuatorKind::ideal_pd);
  EXPECT_EQ(s.actuators[0].stiffness, 200.0);
  EXPECT_EQ(s.actuators[0].damping, 16.0);
  EXPECT_EQ(s.actuators[0].effort_limit, kInf);
  const Simulation sim(robot.model, s);
  EXPECT_TRUE(sim.has_actuator(0));
  EXPECT_EQ(sim.actuator(0).stiffness, 200.0);

  const char* const limited = R"(<mujoco>
  <worldbody>
    <body name="a"><joint name="hinge" axis="0 1 0"/><geom size=".1"/></body>
  </worldbody>
  <actuator>
    <position name="p" joint="hinge" kp="50" gear="2" forcelimited="true" forcerange="-3 3"/>
  </actuator>
</mujoco>)";
  // The forcerange is the actuator's own clip (docs/mujoco_bridge.md), with or without
  // UrdfEffort::effort_limit.
  for (UrdfEffort effort : {UrdfEffort::none, UrdfEffort::effort_limit}) {
    UrdfOptions options;
    options.effort = effort;
    EXPECT_EQ(robot_settings(parse_mjcf(limited, "limited.xml", options)).actuators[0].effort_limit,
              6.0);
  }
}

// An unnamed <freejoint/> (the usual MJCF idiom) is the floating root: q0 is where the file puts
// the body (pos 0 0 1, no rotation), and the settings step from it with its ball joint.
TEST(RobotSettings, UnnamedFreeJointStartsWhereTheFilePutsItsBody) {
  const char* const xml = R"(<mujoco><worldbody>
  <body name="torso" pos="0 0 1"><freejoint/><geom size=".1"/>
    <body name="arm"><joint name="ball" type="ball"/><geom size=".05"/></body>
  </body></worldbody></mujoco>)";
  UrdfOptions floating;
  floating.fixed_base = false;
  const MjcfRobot robot = parse_mjcf(xml, "free.xml", floating);
  ASSERT_TRUE(robot.model->floating_base());
  EXPECT_EQ(robot.q0.head<7>(), (VecX(7) << 0, 0, 1, 1, 0, 0, 0).finished());
  Simulation sim(robot.model, robot_settings(robot));
  sim.set_q(robot.q0);
  sim.step(10);
  EXPECT_LT(sim.q()[2], 1.0);  // it falls
}

// A scene's values, as written in its text, are the settings; make_simulation holds them.
TEST(SceneSettings, AreTheScenesValues) {
  const Scene scene = parse_scene(R"(model: slider.urdf
dt: 0.01
steps: 10
solver: {type: tgs, position_iterations: 8, velocity_iterations: 2}
drives:
  slide: {type: acceleration, stiffness: 40, damping: 3, max_force: 7, delay: 2,
          target_position: 0.2}
joints:
  slide: {lower: -0.5, upper: 0.25, max_velocity: 1.5, friction: {static: 0.3, dynamic: 0.2}}
)",
                                  kExamples + "inline.yaml");
  const Settings s = scene_settings(scene);
  EXPECT_EQ(s.options.dt, 0.01);
  EXPECT_EQ(s.options.solver, SolverType::tgs);
  EXPECT_EQ(s.options.position_iterations, 8);
  EXPECT_EQ(s.options.velocity_iterations, 2);
  EXPECT_EQ(s.drives[0].type, DriveType::acceleration);
  EXPECT_EQ(s.drives[0].stiffness, 40.0);
  EXPECT_EQ(s.drives[0].damping, 3.0);
  EXPECT_EQ(s.drives[0].max_force, 7.0);
  EXPECT_EQ(s.drives[0].target_position, 0.2);
  EXPECT_EQ(s.drive_delay[0], 2);
  EXPECT_EQ(s.lower_limit[0], -0.5);
  EXPECT_EQ(s.upper_limit[0], 0.25);
  EXPECT_EQ(s.max_joint_velocity[0], 1.5);
  EXPECT_EQ(s.friction[0].static_effort, 0.3);
  EXPECT_EQ(s.friction[0].dynamic_effort, 0.2);
  const Simulation sim = make_simulation(scene);
  EXPECT_EQ(sim.drive_delay(0), 2);
  EXPECT_EQ(sim.upper_limit(0), 0.25);
  EXPECT_EQ(sim.joint_friction(0).static_effort, 0.3);
}

// A value of another model is refused naming the field, and nothing is built.
TEST(RobotSettings, SettingsOfAnotherModelAreRefused) {
  const UrdfRobot slider = load_urdf(kExamples + "slider.urdf");
  const UrdfRobot arm = load_urdf(kExamples + "arm7.urdf");
  const Settings s = robot_settings(arm);
  try {
    Simulation sim(slider.model, s);
    FAIL() << "accepted settings of nv = " << arm.model->nv;
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("drives"), std::string::npos) << e.what();
  }
  EXPECT_THROW(Batch(slider.model, 2, s), std::invalid_argument);
  SimulationOptions bad;
  bad.dt = -1.0;
  EXPECT_THROW(robot_settings(slider, bad), std::invalid_argument);
}

}  // namespace
}  // namespace featherdrive
