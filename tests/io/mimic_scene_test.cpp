// Scenes' applied_force, mimic and revolute keys (issue 17), and a URDF gripper whose <mimic> tags
// become mimic joints: closed forms and the constraints held.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "featherdrive/io/checkpoint.hpp"
#include "featherdrive/io/scene.hpp"
#include "support/compare.hpp"
#include "support/models.hpp"
#include "support/source_tree.hpp"

namespace featherdrive::mimic_scene_test {
namespace {

Scene from_text(const std::string& text) {
  return parse_scene(text, test::kExamples + "inline.yaml");
}

std::string load_error(const std::string& text) {
  try {
    from_text(text);
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

double row_error(const Simulation& sim, const MimicJoint& m) {
  const Model& model = sim.model();
  return sim.q()[model.links[model.dof_link[m.dof_a]].q_index] +
         m.gear_ratio * sim.q()[model.links[model.dof_link[m.dof_b]].q_index] + m.offset;
}

// The 2.5 kg slider without gravity under applied_force: semi-implicit Euler of x'' = F(t) / m
// with the force of step k taken at t = k dt, summed here step by step.
TEST(SceneAppliedForce, SliderFollowsTheSumOfItsForces) {
  for (const std::string force : {"2.5", "{sine: {amplitude: 2.5, frequency: 0.5, offset: 0.5}}"}) {
    const Scene s = from_text(
        "model: slider.urdf\ngravity: [0, 0, 0]\ndt: 0.01\nsteps: 80\n"
        "applied_force: {slide: " +
        force + "}\n");
    ASSERT_EQ(s.applied_forces.size(), 1u);
    const bool sine = force[0] == '{';
    double v = 0.0, x = 0.0, worst = 0.0;
    run_scene(s, [&](const Simulation& sim, int k) {
      if (k == 0) return;
      const double t = (k - 1) * 0.01;
      const double f = sine ? 0.5 + 2.5 * std::sin(std::numbers::pi * t) : 2.5;
      v += 0.01 * f / 2.5;
      x += 0.01 * v;
      worst = std::max({worst, std::abs(sim.q()[0] - x), std::abs(sim.qd()[0] - v)});
      EXPECT_EQ(sim.applied_force()[0], f);
    });
    EXPECT_LT(worst, 1e-12) << force;
    EXPECT_GT(x, 0.1);
  }
}

TEST(SceneAppliedForce, BadValuesNameTheKey) {
  const std::string head = "model: slider.urdf\nsteps: 1\n";
  EXPECT_NE(load_error(head + "applied_force: {slide: .nan}\n").find("applied_force.slide"),
            std::string::npos);
  EXPECT_NE(load_error(head + "applied_force: {nope: 1}\n").find("no joint named 'nope'"),
            std::string::npos);
  EXPECT_NE(load_error(head + "applied_force: {slide: {cosine: {}}}\n").find("unknown key"),
            std::string::npos);
}

// The gripper's two <mimic> tags as rigid rows: the fingers open together and the knuckle
// follows, to 1e-9, while the wrist swings under gravity and the left finger is driven.
TEST(SceneMimic, UrdfGripperLoadsAndHolds) {
  const Scene s = from_text(R"(
model: ../tests/data/mimic_gripper.urdf
dt: 0.01
steps: 150
solver: {type: pgs, position_iterations: 48, velocity_iterations: 4}
initial: {q: {knuckle: -0.1}}
drives:
  wrist: {type: force, stiffness: 5, damping: 0.5, target: {sine: {amplitude: 0.8, frequency: 1}}}
  left_finger: {type: force, stiffness: 400, damping: 20, target_position: 0.03}
)");
  ASSERT_EQ(s.mimic.size(), 2u);
  EXPECT_EQ(s.mimic[0].gear_ratio, 1.0);  // right = -left: right + left = 0
  EXPECT_EQ(s.mimic[1].gear_ratio, -12.5);
  EXPECT_EQ(s.mimic[1].offset, 0.1);
  double worst = 0.0;
  const Simulation end = run_scene(s, [&](const Simulation& sim, int) {
    for (const MimicJoint& m : s.mimic) worst = std::max(worst, std::abs(row_error(sim, m)));
  });
  const Model& model = end.model();
  std::printf("gripper: largest |C| %.2e, left finger %.5f\n", worst,
              end.q()[model.dof_index("left_finger")]);
  EXPECT_LT(worst, 1e-9);
  EXPECT_NEAR(end.q()[model.dof_index("left_finger")], 0.03, 2e-3);
}

TEST(SceneMimic, SceneRowsReplaceTheUrdfsAndBadRowsNameTheKey) {
  const std::string head = "model: ../tests/data/mimic_gripper.urdf\nsteps: 1\n";
  const Scene s = from_text(head +
                            "mimic:\n  - {follower: knuckle, leader: left_finger, "
                            "gear_ratio: -10, natural_frequency: 20, damping_ratio: 0.5}\n");
  ASSERT_EQ(s.mimic.size(), 2u);
  EXPECT_EQ(s.mimic[1].gear_ratio, -10.0);
  EXPECT_EQ(s.mimic[1].natural_frequency, 20.0);
  EXPECT_EQ(make_simulation(s).mimic_joints().size(), 2u);
  auto error = [&](const std::string& row) {
    return load_error(head + "mimic:\n  - " + row + "\n");
  };
  EXPECT_NE(error("{follower: nope, leader: wrist, gear_ratio: 1}").find("mimic[0].follower"),
            std::string::npos);
  EXPECT_NE(error("{follower: wrist, leader: wrist, gear_ratio: 1}").find("cannot mimic itself"),
            std::string::npos);
  EXPECT_NE(error("{follower: wrist, leader: knuckle, gear_ratio: 0}").find("must be nonzero"),
            std::string::npos);
  EXPECT_NE(error("{follower: wrist, leader: knuckle, gear_ratio: .nan}").find("gear_ratio"),
            std::string::npos);
  EXPECT_NE(error("{follower: wrist, leader: knuckle}").find("mimic[0].gear_ratio: missing"),
            std::string::npos);
  // wrist -> knuckle joins two groups already coupled through left_finger: a cycle.
  EXPECT_NE(error("{follower: left_finger, leader: wrist, gear_ratio: 1}\n"
                  "  - {follower: wrist, leader: knuckle, gear_ratio: 1}")
                .find("closes a cycle"),
            std::string::npos);
}

TEST(SceneRevolute, JointsAndDefaultsChooseTheWrap) {
  const std::string head = "model: ../tests/data/mimic_gripper.urdf\nsteps: 1\n";
  const Scene s = from_text(head +
                            "joint_defaults: {revolute: wrapped}\n"
                            "joints: {knuckle: {revolute: unwrapped}}\n");
  const Simulation sim = make_simulation(s);
  const Model& m = sim.model();
  EXPECT_EQ(sim.revolute_wrap(m.dof_index("wrist")), RevoluteWrap::wrapped);
  EXPECT_EQ(sim.revolute_wrap(m.dof_index("knuckle")), RevoluteWrap::unwrapped);
  EXPECT_EQ(sim.revolute_wrap(m.dof_index("left_finger")), RevoluteWrap::unwrapped);
  EXPECT_NE(load_error(head + "joints: {wrist: {revolute: wrap}}\n").find("joints.wrist.revolute"),
            std::string::npos);
  EXPECT_NE(load_error(head + "joints: {left_finger: {revolute: wrapped}}\n").find("left_finger"),
            std::string::npos);
}

// A checkpoint (version 5) carries the revolute wrap and the mimic joints: restored into a plain
// simulation of the model, the run resumes bit for bit.
TEST(SceneMimic, CheckpointKeepsWrapAndMimicJoints) {
  const Scene s = from_text("model: ../tests/data/mimic_gripper.urdf\nsteps: 1\n"
                            "joints: {wrist: {revolute: wrapped}}\n"
                            "mimic: [{follower: wrist, leader: knuckle, gear_ratio: 2, "
                            "natural_frequency: 30, damping_ratio: 0.7}]\n");
  Simulation sim = make_simulation(s);
  VecX qd = VecX::Zero(sim.model().nv);
  qd[sim.model().dof_index("left_finger")] = 0.1;
  sim.set_qd(qd);
  sim.step(10);
  const std::string bytes = checkpoint_bytes(sim);
  Simulation resumed(sim.model_ptr());
  restore_checkpoint(bytes, resumed, "gripper.ckpt");
  EXPECT_EQ(resumed.revolute_wrap(sim.model().dof_index("wrist")), RevoluteWrap::wrapped);
  ASSERT_EQ(resumed.mimic_joints().size(), 3u);
  EXPECT_EQ(resumed.mimic_joints()[2].natural_frequency, 30.0);
  EXPECT_EQ(checkpoint_bytes(resumed), bytes);
  sim.step(20);
  resumed.step(20);
  EXPECT_TRUE(test::same_bits(sim.q(), resumed.q()));
  EXPECT_TRUE(test::same_bits(sim.qd(), resumed.qd()));
}

}  // namespace
}  // namespace featherdrive::mimic_scene_test
