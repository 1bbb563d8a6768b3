// MJCF import (io/mjcf.hpp) against MuJoCo 2.2.2 itself: the same file compiled by MuJoCo gives
// the reference mass matrix (mj_fullM), bias forces (qfrc_bias) and passive accelerations (qacc
// from mj_forward), with MuJoCo's constraints, passive forces (springs, damping) and actuation
// switched off, so both sides compute M(q) a + b(q, v) = 0 for the rigid bodies alone.
//
// q is MuJoCo's qpos for every joint. Velocities differ only at a free root: MuJoCo's qvel is
// [world velocity of the body origin; body-frame angular velocity], ours the body-frame [w; v], so
// qvel = T v with T = [0 R; 1 0], and qacc = T a + c with c = [R (w x v); 0] (R turns with w).
// Then our M = T^T M_mj T, our bias = T^T (b_mj + M_mj c) and our a = T^-1 (qacc - c).
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
#include "featherdrive/sim/simulation.hpp"

namespace featherdrive {
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

// Ball joints: one at the body origin, one at an offset below a hinge.
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

}  // namespace
}  // namespace featherdrive
