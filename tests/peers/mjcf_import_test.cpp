// MJCF import (io/mjcf.hpp) against MuJoCo 2.2.2 itself: the same file compiled by MuJoCo gives
// the reference mass matrix (mj_fullM), bias forces (qfrc_bias) and passive accelerations (qacc
// from mj_forward), with MuJoCo's constraints, passive forces (springs, damping) and actuation
// switched off, so both sides compute M(q) a + b(q, v) = 0 for the rigid bodies alone.
//
// q is MuJoCo's qpos for every joint. Velocities differ only at a free root: MuJoCo's qvel is
// [world velocity of the body origin; body-frame angular velocity], ours the body-frame [w; v], so
// qvel = T v with T = [0 R; 1 0], and qacc = T a + c with c = [R (w x v); 0] (R turns with w).
// Then our M = T^T M_mj T, our bias = T^T (b_mj + M_mj c) and our a = T^-1 (qacc - c).
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <random>
#include <string>

#include <unistd.h>

#include "featherdrive/algorithm/aba.hpp"
#include "featherdrive/algorithm/crba.hpp"
#include "featherdrive/algorithm/rnea.hpp"
#include "featherdrive/io/mjcf.hpp"
#include "featherdrive/sim/explicit_actuator.hpp"
#include "featherdrive/sim/simulation.hpp"

// Names live in a namespace of their own: test files may be compiled several to a translation
// unit (featherdrive_test_batches).
namespace featherdrive::mjcf_import {
namespace {

const char* const kHumanoid = "/usr/share/mujoco/model/humanoid/humanoid.xml";
// Relative to the largest entry of the compared quantity (at least 1).
constexpr double kTolerance = 1e-9;

struct MjDeleter {
  void operator()(mjModel* m) const { mj_deleteModel(m); }
  void operator()(mjData* d) const { mj_deleteData(d); }
};
using MjModelPtr = std::unique_ptr<mjModel, MjDeleter>;
using MjDataPtr = std::unique_ptr<mjData, MjDeleter>;

// MuJoCo's own compile of the text, through a temporary file.
MjModelPtr mujoco_model(const std::string& xml) {
  const std::filesystem::path file =
      std::filesystem::temp_directory_path() /
      ("featherdrive_mjcf_import_" + std::to_string(::getpid()) + ".xml");
  std::ofstream(file) << xml;
  char error[1000] = "";
  MjModelPtr m(mj_loadXML(file.c_str(), nullptr, error, sizeof error));
  std::filesystem::remove(file);
  EXPECT_NE(m, nullptr) << error;
  return m;
}

std::string read(const char* path) {
  std::ifstream in(path);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

struct Worst {
  double mass = 0.0, bias = 0.0, qacc = 0.0;
};

double relative(const VecX& ours, const VecX& theirs) {
  return (ours - theirs).cwiseAbs().maxCoeff() / std::max(1.0, theirs.cwiseAbs().maxCoeff());
}

// Compares our CRBA, RNEA and ABA with MuJoCo at `trials` random states; returns the worst
// relative differences.
Worst compare_dynamics(const std::string& xml, int trials, unsigned seed) {
  UrdfOptions floating;
  floating.fixed_base = false;
  const MjcfRobot robot = parse_mjcf(xml, "test.xml", floating);
  MjModelPtr m = mujoco_model(xml);
  Worst worst;
  if (!m) return worst;
  const Model& model = *robot.model;
  EXPECT_EQ(model.nq, m->nq);
  EXPECT_EQ(model.nv, m->nv);
  m->opt.disableflags |= mjDSBL_CONSTRAINT | mjDSBL_PASSIVE | mjDSBL_ACTUATION;
  MjDataPtr d(mj_makeData(m.get()));
  Data data(model);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const int nv = model.nv;
  for (int trial = 0; trial < trials; ++trial) {
    VecX q = VecX::Zero(model.nq), v = VecX::Zero(nv);
    for (const Link& link : model.links) {
      for (int k = 0; k < link.nq; ++k) q[link.q_index + k] = 1.5 * u(rng);
      const int quat = link.joint_type == JointType::floating    ? link.q_index + 3
                       : link.joint_type == JointType::spherical ? link.q_index
                                                                 : -1;
      if (quat >= 0) q.segment<4>(quat).normalize();
    }
    for (int k = 0; k < nv; ++k) v[k] = 2.0 * u(rng);
    MatX T = MatX::Identity(nv, nv);
    VecX c = VecX::Zero(nv);
    if (model.floating_base()) {
      const Mat3 R = Quat(q[3], q[4], q[5], q[6]).toRotationMatrix();
      T.topLeftCorner(6, 6).setZero();
      T.block<3, 3>(0, 3) = R;
      T.block<3, 3>(3, 0).setIdentity();
      c.head<3>() = R * v.head<3>().cross(v.segment<3>(3));
    }
    const VecX qvel = T * v;
    std::memcpy(d->qpos, q.data(), sizeof(double) * static_cast<size_t>(model.nq));
    std::memcpy(d->qvel, qvel.data(), sizeof(double) * static_cast<size_t>(nv));
    mj_forward(m.get(), d.get());
    MatX M_mj(nv, nv);
    mj_fullM(m.get(), M_mj.data(), d->qM);  // symmetric: row or column major alike
    const VecX bias_mj = Eigen::Map<const VecX>(d->qfrc_bias, nv);
    const VecX qacc_mj = Eigen::Map<const VecX>(d->qacc, nv);

    const MatX M = crba(model, data, q);
    const MatX M_expected = T.transpose() * M_mj * T;
    worst.mass = std::max(worst.mass, (M - M_expected).cwiseAbs().maxCoeff() /
                                          std::max(1.0, M_expected.cwiseAbs().maxCoeff()));
    const VecX bias = rnea(model, data, q, v, VecX::Zero(nv));
    worst.bias = std::max(worst.bias, relative(bias, T.transpose() * (bias_mj + M_mj * c)));
    const VecX a = aba(model, data, q, v, VecX::Zero(nv));
    worst.qacc = std::max(worst.qacc, relative(a, T.inverse() * (qacc_mj - c)));
  }
  return worst;
}

void expect_matches(const std::string& xml, const char* what) {
  const Worst w = compare_dynamics(xml, 50, 7);
  EXPECT_LT(w.mass, kTolerance) << what;
  EXPECT_LT(w.bias, kTolerance) << what;
  EXPECT_LT(w.qacc, kTolerance) << what;
  std::printf("%s: worst relative difference M %.2e, bias %.2e, qacc %.2e\n", what, w.mass,
              w.bias, w.qacc);
}

// Hinges at offsets from their bodies (jnt_pos), rotated body frames (quat, euler, axisangle),
// non-unit axes, a ref (qpos0), armature, a body without a joint and an inertia whose principal
// axes are turned (fullinertia); the base body has a hinge, so the world becomes our root link.
const char* const kArm = R"(<mujoco model="arm">
  <compiler angle="radian"/>
  <worldbody>
    <body name="base" pos="0.1 -0.2 0.3" euler="0.3 -0.2 0.5">
      <joint name="j1" type="hinge" axis="0 0 2" pos="0.05 0 0" armature="0.02"/>
      <inertial pos="0.01 0.02 0.1" mass="2" diaginertia="0.02 0.03 0.04"/>
      <body name="upper" pos="0 0.1 0.4" quat="0.9 0.1 -0.3 0.2">
        <joint name="j2" type="hinge" axis="1 1 0" pos="0 0.03 -0.05" ref="0.4"/>
        <inertial pos="0 0 0.2" mass="1.5" fullinertia="0.05 0.04 0.03 0.002 -0.003 0.004"/>
        <body name="bracket" pos="0.02 0 0.45" axisangle="0 1 0 0.7">
          <inertial pos="0.03 0 0" mass="0.3" diaginertia="0.001 0.002 0.002"/>
          <body name="fore" pos="0.1 0 0.05">
            <joint name="j3" type="hinge" axis="0 1 0" pos="-0.02 0 0.01" armature="0.005"/>
            <inertial pos="0 0 0.15" quat="0.8 0.2 0.1 0.3" mass="0.8"
                      diaginertia="0.01 0.012 0.003"/>
          </body>
        </body>
      </body>
    </body>
  </worldbody>
</mujoco>)";

// Two hinges in one body (a chain whose first link is massless), then a slide with a ref and a
// hinge in one body.
const char* const kMultiJoint = R"(<mujoco model="multi">
  <compiler angle="radian"/>
  <worldbody>
    <body name="hip" pos="0 0 1" quat="0.7 0.7 0 0">
      <joint name="hx" type="hinge" axis="1 0 0" pos="0 0 0.1"/>
      <joint name="hy" type="hinge" axis="0 1 0.3" pos="0.02 0.01 0.05" armature="0.01"/>
      <inertial pos="0.05 0 -0.2" mass="3" fullinertia="0.1 0.08 0.03 0.01 0 -0.005"/>
      <body name="slider" pos="0 0.1 -0.4">
        <joint name="s" type="slide" axis="0.2 0 1" pos="0.3 0.3 0.3" ref="0.05"/>
        <joint name="h" type="hinge" axis="0 0 1" pos="0 0.02 0"/>
        <inertial pos="0 0.05 -0.1" mass="1" diaginertia="0.01 0.02 0.015"/>
      </body>
    </body>
  </worldbody>
</mujoco>)";

// Ball joints: one at the body origin, one at an offset below a hinge, one after a hinge in the
// same body (MuJoCo refuses a ball followed by a rotation).
const char* const kBall = R"(<mujoco model="ball">
  <compiler angle="radian"/>
  <worldbody>
    <body name="top" pos="0 0 2" euler="0.1 0.2 0.3">
      <joint name="b1" type="ball" armature="0.01"/>
      <inertial pos="0 0.05 -0.3" mass="2" fullinertia="0.05 0.06 0.04 0.005 0.002 0"/>
      <body name="mid" pos="0 0 -0.6" quat="0.9 0 0.3 0.1">
        <joint name="h" type="hinge" axis="1 0 0" pos="0 0 0.05"/>
        <inertial pos="0 0 -0.2" mass="1" diaginertia="0.02 0.02 0.005"/>
        <body name="low" pos="0.1 0 -0.4">
          <joint name="b2" type="ball" pos="0.02 -0.03 0.04"/>
          <inertial pos="0 0.1 -0.1" quat="0.6 0.8 0 0" mass="0.5" diaginertia="0.004 0.003 0.002"/>
        </body>
        <body name="wrist" pos="0 0.2 -0.3" euler="0.4 0 0.2">
          <joint name="twist" type="hinge" axis="0 0 1" pos="0 0.03 0"/>
          <joint name="b3" type="ball" pos="0.01 0 0.02"/>
          <inertial pos="0.02 0 -0.1" mass="0.3" diaginertia="0.002 0.003 0.001"/>
        </body>
      </body>
    </body>
  </worldbody>
</mujoco>)";

// A free root with a hinge child, a slide grandchild and a welded body.
const char* const kFree = R"(<mujoco model="free">
  <compiler angle="radian"/>
  <worldbody>
    <body name="trunk" pos="0.3 0.2 1.1" quat="0.9 0.1 0.2 0.3">
      <freejoint name="root"/>
      <inertial pos="0.02 -0.01 0.03" quat="0.7 0 0.7 0" mass="5" diaginertia="0.2 0.15 0.1"/>
      <body name="leg" pos="0 0.1 -0.2" euler="0.2 0 0">
        <joint name="knee" type="hinge" axis="0 1 0" pos="0 0 0.05" armature="0.02"/>
        <inertial pos="0 0 -0.2" mass="1" diaginertia="0.02 0.02 0.004"/>
        <body name="foot" pos="0 0 -0.4">
          <joint name="ankle" type="slide" axis="0 0 1"/>
          <inertial pos="0.05 0 0" mass="0.4" diaginertia="0.001 0.002 0.002"/>
        </body>
      </body>
      <body name="head" pos="0 0 0.3">
        <inertial pos="0 0 0.05" mass="0.8" diaginertia="0.003 0.003 0.003"/>
      </body>
    </body>
  </worldbody>
</mujoco>)";

TEST(MjcfImport, ArmWithOffsetsAndRotatedFramesMatchesMuJoCo) {
  expect_matches(kArm, "arm");
}
TEST(MjcfImport, SeveralJointsInOneBodyMatchMuJoCo) { expect_matches(kMultiJoint, "multi"); }
TEST(MjcfImport, BallJointsMatchMuJoCo) { expect_matches(kBall, "ball"); }
TEST(MjcfImport, FreeRootMatchesMuJoCo) { expect_matches(kFree, "free"); }
TEST(MjcfImport, HumanoidMatchesMuJoCo) { expect_matches(read(kHumanoid), "humanoid"); }

// What load_mjcf says about the humanoid, against the file and MuJoCo's compile of it.
TEST(MjcfImport, HumanoidLoadsWithItsWarnings) {
  UrdfOptions floating;
  floating.fixed_base = false;
  const MjcfRobot robot = load_mjcf(kHumanoid, floating);
  MjModelPtr m = mujoco_model(read(kHumanoid));
  ASSERT_NE(m, nullptr);
  const Model& model = *robot.model;
  EXPECT_EQ(model.nv, 27);
  EXPECT_TRUE(model.floating_base());
  EXPECT_EQ(robot.root_link, "torso");
  EXPECT_EQ(robot.root_joint, "root");
  double mass = 0.0;
  for (const Link& link : model.links) mass += link.mass;
  EXPECT_NEAR(mass, mj_getTotalmass(m.get()), 1e-12);
  // The free root starts where the file puts the torso: pos="0 0 1.5", identity orientation.
  EXPECT_EQ(robot.q0.head<7>(), (VecX(7) << 0, 0, 1.5, 1, 0, 0, 0).finished());
  EXPECT_EQ(robot.joint_order.size(), 21u);
  EXPECT_EQ(robot.joint_order.front(), "abdomen_z");
  ASSERT_EQ(robot.actuators.size(), 21u);
  // <motor name="right_hip_y" gear="120" joint="right_hip_y"/> with ctrlrange -1 1 (defaults).
  const MjcfActuator& hip = robot.actuators[5];
  EXPECT_EQ(hip.name, "right_hip_y");
  EXPECT_EQ(hip.kind, MjcfActuatorKind::motor);
  EXPECT_EQ(hip.gear, 120.0);
  EXPECT_EQ(hip.ctrl_upper, 1.0);
  EXPECT_EQ(hip.actuator.kind, ActuatorKind::none);
  EXPECT_EQ(robot.effort_limits.at("right_hip_y"), 120.0);
  EXPECT_EQ(model.dof_names[static_cast<size_t>(hip.dof)], "right_hip_y");
  // armature=".01" for every joint (class "body").
  EXPECT_EQ(model.armature[hip.dof], 0.01);
  // One line each: self-collision (MuJoCo's pairs of the robot's geoms, all contype and
  // conaffinity 1, by MuJoCo's filter: not on one welded body, nor on a welded body and its
  // parent's: the hands have no joint and move with the lower arms), the springs (every joint
  // but the elbows, stiffness="0"), damping.
  ASSERT_EQ(robot.warnings.size(), 3u);
  int pairs = 0;
  {
    std::vector<int> welds;  // the welded body of each robot geom
    for (int g = 0; g < m->ngeom; ++g)
      if (m->geom_bodyid[g] != 0) welds.push_back(m->body_weldid[m->geom_bodyid[g]]);
    auto parent = [&](int w) { return m->body_weldid[m->body_parentid[w]]; };
    for (size_t i = 0; i < welds.size(); ++i)
      for (size_t j = i + 1; j < welds.size(); ++j)
        pairs += welds[i] != welds[j] && parent(welds[i]) != welds[j] &&
                 parent(welds[j]) != welds[i];
  }
  EXPECT_EQ(pairs, 142);
  EXPECT_EQ(robot.warnings[0], std::to_string(pairs) + " pairs of the robot's own geoms collide in "
            "MuJoCo; featherdrive's shapes collide with each other only with contact: "
            "{self_collision: true} (off by default; parent and child links never)");
  EXPECT_NE(robot.warnings[1].find("stiffness"), std::string::npos);
  EXPECT_NE(robot.warnings[1].find("'left_ankle_x'"), std::string::npos);
  EXPECT_EQ(robot.warnings[1].find("elbow"), std::string::npos);
  EXPECT_NE(robot.warnings[2].find("damping"), std::string::npos);
  for (const std::string& w : robot.warnings) EXPECT_EQ(w.find('\n'), std::string::npos) << w;
}

// fixed_base welds the free root where the file puts it: our fixed-base mass matrix and gravity
// torques are the hinge block of MuJoCo's floating ones with the root at that pose.
TEST(MjcfImport, FixedBaseWeldsTheFreeRootWhereItStands) {
  const char* const tilted = R"(<mujoco>
  <worldbody>
    <body name="trunk" pos="0.3 -0.2 1" euler="20 -30 45">
      <freejoint/>
      <inertial pos="0 0 0" mass="4" diaginertia="0.1 0.1 0.1"/>
      <body name="arm" pos="0.2 0 0">
        <joint name="shoulder" axis="0 1 0" pos="0 0 0.05"/>
        <inertial pos="0.2 0 0.1" mass="1" diaginertia="0.01 0.02 0.02"/>
      </body>
    </body>
  </worldbody>
</mujoco>)";
  const MjcfRobot robot = parse_mjcf(tilted, "tilted.xml");
  MjModelPtr m = mujoco_model(tilted);
  ASSERT_NE(m, nullptr);
  ASSERT_EQ(robot.model->nv, 1);
  EXPECT_EQ(robot.root_joint, "root_joint");  // the free joint has no name
  MjDataPtr d(mj_makeData(m.get()));
  m->opt.disableflags |= mjDSBL_CONSTRAINT | mjDSBL_PASSIVE | mjDSBL_ACTUATION;
  Data data(*robot.model);
  for (double angle : {-1.0, 0.3, 2.0}) {
    std::copy(m->qpos0, m->qpos0 + m->nq, d->qpos);
    d->qpos[7] = angle;
    mj_forward(m.get(), d.get());
    MatX M(m->nv, m->nv);
    mj_fullM(m.get(), M.data(), d->qM);
    const VecX q = VecX::Constant(1, angle);
    EXPECT_NEAR(crba(*robot.model, data, q)(0, 0), M(6, 6), 1e-12);
    EXPECT_NEAR(generalized_gravity(*robot.model, data, q)[0], d->qfrc_bias[6], 1e-12);
  }
}

// With a force drive of stiffness k on every hinge and the torso welded, the humanoid comes to a
// standstill where the drives hold it against gravity: each drive's force equals MuJoCo's
// gravity torque at the final q (its bias forces at rest, hinge rows), and no joint deflects
// further than the largest gravity torque over k. (The solver's stored qd is not zero at that
// standstill: PhysX's velocity iteration leaves the drive's bias out of it, so q is what stays.)
TEST(MjcfImport, HumanoidHoldsItsPoseWithDrivesOnAWeldedTorso) {
  const MjcfRobot robot = load_mjcf(kHumanoid);
  const double k = 2000.0;
  SimulationOptions options;
  options.dt = 0.005;
  options.solver = SolverType::tgs;
  Simulation sim(robot.model, options);
  for (int dof = 0; dof < robot.model->nv; ++dof)
    sim.set_drive(dof, Drive{DriveType::force, k, 100.0});
  sim.step(500);
  const VecX q_before = sim.q();
  sim.step(100);
  MjModelPtr m = mujoco_model(read(kHumanoid));
  ASSERT_NE(m, nullptr);
  MjDataPtr d(mj_makeData(m.get()));
  std::copy(m->qpos0, m->qpos0 + 7, d->qpos);  // the torso where the file puts it
  for (int i = 0; i < robot.model->nv; ++i) d->qpos[7 + i] = sim.q()[i];
  mj_forward(m.get(), d.get());
  const VecX g = Eigen::Map<const VecX>(d->qfrc_bias + 6, robot.model->nv);
  const double g_max = g.cwiseAbs().maxCoeff();
  const VecX q = sim.q();
  EXPECT_LT((q - q_before).cwiseAbs().maxCoeff(), 1e-8);  // settled: 1e-9 in the last 100 steps
  EXPECT_LT((VecX(sim.drive_force()) - g).cwiseAbs().maxCoeff(), 0.01 * g_max)
      << "drive " << VecX(sim.drive_force()).transpose() << "\ngravity " << g.transpose();
  EXPECT_LT(q.cwiseAbs().maxCoeff(), g_max / k);
  std::printf("humanoid hold: largest deflection %.4e rad (|g| / k = %.4e), |f - g| %.2e Nm of "
              "|g| %.3f Nm\n", q.cwiseAbs().maxCoeff(), g_max / k,
              (VecX(sim.drive_force()) - g).cwiseAbs().maxCoeff(), g_max);
}

// Position and velocity actuators with gears and force ranges: the featherdrive form of each
// (ideal_pd, target ctrl / gear) gives the joint effort MuJoCo's actuator gives (qfrc_actuator)
// at random states and controls, saturated ones included.
TEST(MjcfImport, PositionAndVelocityActuatorsGiveMuJoCosEfforts) {
  const char* const xml = R"(<mujoco>
  <worldbody>
    <body name="a">
      <joint name="hinge" axis="0 1 0"/>
      <geom size=".1"/>
      <body name="b" pos="0 0 -0.5">
        <joint name="slide" type="slide" axis="1 0 0"/>
        <geom size=".1"/>
      </body>
    </body>
  </worldbody>
  <actuator>
    <position name="p" joint="hinge" kp="300" gear="2.5" forcelimited="true" forcerange="-40 40"/>
    <velocity name="v" joint="slide" kv="20" gear="-3"/>
    <motor name="m" joint="slide" gear="7" ctrllimited="true" ctrlrange="-2 2"/>
  </actuator>
</mujoco>)";
  const MjcfRobot robot = parse_mjcf(xml, "actuators.xml");
  MjModelPtr m = mujoco_model(xml);
  ASSERT_NE(m, nullptr);
  ASSERT_EQ(robot.actuators.size(), 3u);
  const MjcfActuator& p = robot.actuators[0];
  const MjcfActuator& v = robot.actuators[1];
  EXPECT_EQ(p.kind, MjcfActuatorKind::position);
  EXPECT_EQ(v.kind, MjcfActuatorKind::velocity);
  EXPECT_EQ(robot.actuators[2].kind, MjcfActuatorKind::motor);
  EXPECT_EQ(p.actuator.stiffness, 300.0 * 2.5 * 2.5);
  EXPECT_EQ(p.actuator.effort_limit, 2.5 * 40.0);
  EXPECT_EQ(v.actuator.damping, 20.0 * 9.0);
  // Informative joint limits, summed per joint: 2.5 * 40 on the hinge; the slide's velocity
  // actuator has no force bound, so its 7 * 2 from the motor becomes unbounded.
  EXPECT_EQ(robot.effort_limits.at("hinge"), 100.0);
  EXPECT_EQ(robot.effort_limits.at("slide"), std::numeric_limits<double>::infinity());
  MjDataPtr d(mj_makeData(m.get()));
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int saturated = 0;
  for (int trial = 0; trial < 20; ++trial) {
    for (int i = 0; i < 2; ++i) {
      d->qpos[i] = 0.2 * u(rng);
      d->qvel[i] = u(rng);
    }
    d->ctrl[0] = 0.5 * u(rng);
    d->ctrl[1] = u(rng);
    d->ctrl[2] = 0.0;
    mj_forward(m.get(), d.get());
    const double hinge = actuator_effort(p.actuator, d->qpos[p.dof], d->qvel[p.dof],
                                         {d->ctrl[0] / p.gear, 0.0, 0.0});
    const double slide = actuator_effort(v.actuator, d->qpos[v.dof], d->qvel[v.dof],
                                         {0.0, d->ctrl[1] / v.gear, 0.0});
    EXPECT_NEAR(hinge, d->qfrc_actuator[p.dof], 1e-12);
    EXPECT_NEAR(slide, d->qfrc_actuator[v.dof], 1e-12);
    saturated += std::abs(hinge) == 100.0;
  }
  EXPECT_GT(saturated, 0);  // the forcerange clip was exercised
}

// A position and a velocity actuator on one hinge (MuJoCo 2.2's PD idiom) become one ideal_pd
// actuator in a Simulation, whose effort is the sum of MuJoCo's two while neither saturates.
TEST(MjcfImport, PositionAndVelocityOnOneJointBecomeOnePdActuator) {
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
  MjModelPtr m = mujoco_model(xml);
  ASSERT_NE(m, nullptr);
  Simulation sim(robot.model);
  apply_mjcf_actuators(robot, sim);
  ASSERT_TRUE(sim.has_actuator(0));
  EXPECT_EQ(sim.actuator(0).stiffness, 200.0);
  EXPECT_EQ(sim.actuator(0).damping, 16.0);
  MjDataPtr d(mj_makeData(m.get()));
  d->qpos[0] = 0.3;
  d->qvel[0] = -1.2;
  d->ctrl[0] = 0.4;
  d->ctrl[1] = 0.5;
  mj_forward(m.get(), d.get());
  EXPECT_NEAR(actuator_effort(sim.actuator(0), 0.3, -1.2, {0.4 / 2, 0.5 / 2, 0.0}),
              d->qfrc_actuator[0], 1e-12);
}

// Scenes and `info` pick the loader by the file's first element; .urdf is always URDF.
TEST(MjcfImport, LoadRobotTellsMjcfFromUrdf) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() /
                       ("featherdrive_mjcf_kind_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const std::string mjcf = "<?xml version=\"1.0\"?>\n<!-- <robot> in a comment -->\n"
                           "<mujoco model=\"m\"><worldbody><body name=\"b\"><joint/>"
                           "<geom size=\".1\"/></body></worldbody></mujoco>\n";
  const std::string urdf = "<?xml version=\"1.0\"?>\n<robot name=\"r\"><link name=\"base\"/>"
                           "</robot>\n";
  std::ofstream(dir / "mjcf.xml") << mjcf;
  std::ofstream(dir / "urdf.xml") << urdf;
  std::ofstream(dir / "mjcf.urdf") << mjcf;
  EXPECT_TRUE(is_mjcf_file(dir / "mjcf.xml"));
  EXPECT_FALSE(is_mjcf_file(dir / "urdf.xml"));
  EXPECT_FALSE(is_mjcf_file(dir / "mjcf.urdf"));
  EXPECT_TRUE(is_mjcf_file(dir / "missing.xml"));  // the MJCF loader reports it
  EXPECT_EQ(load_robot(dir / "mjcf.xml").name, "m");
  EXPECT_EQ(load_robot(dir / "urdf.xml").name, "r");
  EXPECT_THROW(load_robot(dir / "mjcf.urdf"), InputError);  // urdfdom refuses <mujoco>
  fs::remove_all(dir);
}

std::string load_error(const std::string& xml, const std::string& name) {
  try {
    parse_mjcf(xml, name);
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos) << e.what();
    return e.what();
  }
  return "(no error)";
}

TEST(MjcfImport, BadFilesGiveOneLineNamingTheFile) {
  try {
    load_mjcf("/nonexistent/robot.xml");
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("/nonexistent/robot.xml: cannot open", 0), 0u)
        << e.what();
  }
  EXPECT_THAT(load_error("<mujoco><worldbody><body></worldbody></mujoco>", "bad.xml"),
              testing::StartsWith("bad.xml: MuJoCo cannot load it: XML parse error"));
  EXPECT_EQ(load_error(R"(<mujoco><worldbody><body name="a"><joint name="j"/>
      <geom size=".1"/><site name="s1"/><body name="b"><joint name="k"/><geom size=".1"/>
      <site name="s2"/></body></body></worldbody>
      <tendon><spatial name="cable"><site site="s1"/><site site="s2"/></spatial></tendon>
      </mujoco>)", "tendon.xml"),
            "tendon.xml: <tendon> 'cable' (1 in all): tendons are not supported (featherdrive "
            "has no tendon constraints or tendon actuators)");
  EXPECT_EQ(load_error(R"(<mujoco><worldbody><body name="a"><joint name="j"/><geom size=".1"/>
      <body name="b"><joint name="k"/><geom size=".1"/></body></body></worldbody>
      <equality><weld name="couple" body1="a" body2="b"/></equality></mujoco>)", "eq.xml"),
            "eq.xml: <equality><weld> 'couple' (1 in all): equality constraints are not "
            "supported");
  EXPECT_EQ(load_error(R"(<mujoco><worldbody>
      <body name="a"><freejoint/><geom size=".1"/></body>
      <body name="b"><freejoint/><geom size=".1"/></body></worldbody></mujoco>)", "two.xml"),
            "two.xml: free bodies 'a', 'b': featherdrive simulates one articulation with at "
            "most one free root");
  // Two hinges of one body on one axis: M = [I I; I I] has no inertia along (1, -1); the first
  // joint moves nothing the second does not.
  EXPECT_THAT(load_error(R"(<mujoco><worldbody><body name="a"><joint name="j1" axis="0 0 1"/>
      <joint name="j2" axis="0 0 1"/><geom size=".1"/></body></worldbody></mujoco>)", "axis.xml"),
              testing::MatchesRegex("axis.xml: joint 'j1' \\(link 'a/j1'\\) moves no inertia at "
                                    "qpos0 \\(the mass matrix's pivot .* against .*\\): no mass "
                                    "below it, or another joint of its body moving it the same way; "
                                    "give the body mass or the joint armature"));
}

// MuJoCo's fatal error (default: print, wait for Enter, exit) throws once featherdrive has
// loaded a model, through MuJoCo's C frames too; the process goes on and loads again.
TEST(MjcfImport, MujocoFatalErrorsThrowInsteadOfExiting) {
  EXPECT_THROW(parse_mjcf("", "empty.xml"), InputError);
  (void)parse_mjcf("<mujoco><worldbody><body><joint/><geom size=\".1\"/></body></worldbody>"
                   "</mujoco>", "ok.xml");
  EXPECT_THROW(mju_error("boom"), std::runtime_error);
  try {
    mju_error_i("bad index %d", 7);
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "MuJoCo: bad index 7");
  }
  auto vfs = std::make_unique<mjVFS>();
  mj_defaultVFS(vfs.get());
  EXPECT_THROW(mj_makeEmptyFileVFS(vfs.get(), "x.xml", 0), std::runtime_error);
  mj_deleteVFS(vfs.get());
  EXPECT_EQ(parse_mjcf("<mujoco><worldbody><body><joint/><geom size=\".1\"/></body></worldbody>"
                       "</mujoco>", "again.xml").model->nv, 1);
}

}  // namespace
}  // namespace featherdrive::mjcf_import
