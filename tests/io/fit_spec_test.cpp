// A scene's fit: section: the unknowns, their bounds and starting values (the scene's own
// values where none is given), and one-line errors naming the key path and the value.
#include "featherdrive/io/fit_spec.hpp"

#include <gtest/gtest.h>

#include "featherdrive/io/scene.hpp"
#include "support/source_tree.hpp"

namespace featherdrive {
namespace {

using test::kExamples;

// The arm with drives on every joint and armature on joint2; `fit` is the fit: section.
Scene arm_fitting(const std::string& fit) {
  return parse_scene(
      "model: arm7.urdf\nsteps: 10\n"
      "drive_defaults: {type: force, stiffness: 400, damping: 10}\n"
      "drives: {joint4: {stiffness: 250}, joint7: {type: none}}\n"
      "joints: {joint2: {armature: 0.1}, joint3: {friction: {static: 0.3}}}\n"
      "fit:\n" +
          fit,
      kExamples + "inline_fit.yaml");
}

std::string fit_error_of(const std::string& fit) {
  try {
    arm_fitting(fit);
  } catch (const InputError& e) {
    const std::string what = e.what();  // the file's folder left out
    return what.rfind(kExamples, 0) == 0 ? what.substr(kExamples.size()) : what;
  }
  return "(no error)";
}

// A fit: section of one parameter.
std::string one_parameter(const std::string& entry) {
  return "  parameters:\n    - " + entry + "\n";
}

TEST(FitSpec, SceneWithoutFitHasNone) {
  EXPECT_FALSE(load_scene(kExamples + "arm7_pgs.yaml").fit.has_value());
}

TEST(FitSpec, StartingValuesAreTheScenesUnlessGiven) {
  const Scene s = arm_fitting(
      "  parameters:\n"
      "    - {quantity: stiffness, joints: [joint2, joint4], bounds: [10, 1000]}\n"
      "    - {quantity: damping, joints: all, bounds: [1, 100], shared: true, initial: 20}\n"
      "    - {quantity: armature, joints: [joint2], bounds: [0, 1]}\n"
      "    - {quantity: friction.static, joints: [joint3], bounds: [0, 1]}\n"
      "    - {quantity: mass_scale, links: [link3], bounds: [0.5, 2]}\n"
      "    - {quantity: delay, joints: all, bounds: [0, 3]}\n"
      "  data: {resample: linear, segment_steps: 40, qd_weight: 0.1}\n");
  ASSERT_TRUE(s.fit.has_value());
  const FitSpec& f = *s.fit;
  ASSERT_EQ(f.parameters.size(), 6u);
  const FitParameter& k = f.parameters[0];
  EXPECT_EQ(k.quantity, FitQuantity::stiffness);
  EXPECT_EQ(k.names, (std::vector<std::string>{"joint2", "joint4"}));
  EXPECT_EQ(k.indices, (std::vector<int>{1, 3}));
  EXPECT_EQ(k.initial, (std::vector<double>{400.0, 250.0}));  // drive_defaults, drives.joint4
  EXPECT_FALSE(k.shared);
  EXPECT_EQ(k.lower, 10.0);
  EXPECT_EQ(k.upper, 1000.0);
  // all: the six joints with a drive (joint7's is type none); shared: one unknown.
  EXPECT_EQ(f.parameters[1].names.size(), 6u);
  EXPECT_EQ(f.parameters[1].initial, (std::vector<double>{20.0}));
  EXPECT_EQ(f.parameters[2].initial, (std::vector<double>{0.1}));  // joints.joint2.armature
  EXPECT_EQ(f.parameters[3].initial, (std::vector<double>{0.3}));
  EXPECT_EQ(f.parameters[4].initial, (std::vector<double>{1.0}));
  EXPECT_EQ(f.parameters[5].quantity, FitQuantity::delay);
  EXPECT_TRUE(f.parameters[5].shared);
  EXPECT_EQ(f.num_unknowns(), 2 + 1 + 1 + 1 + 1);
  EXPECT_EQ(f.data.resample, FitData::Resample::linear);
  EXPECT_EQ(f.data.segment_steps, 40);
  EXPECT_EQ(f.data.qd_weight, 0.1);
  EXPECT_STREQ(to_string(FitQuantity::friction_static), "friction.static");
}

TEST(FitSpec, BadEntriesNameTheKeyAndValue) {
  const auto bad = [](const std::string& entry) { return fit_error_of(one_parameter(entry)); };
  const std::string f = "inline_fit.yaml: fit.parameters[0]";
  EXPECT_EQ(bad("{quantity: stiffness, joints: [elbow], bounds: [1, 2]}"),
            f + ".joints[0]: no joint named 'elbow' in arm7.urdf (moving joints: joint1, joint2, "
                "joint3, joint4, joint5, joint6, joint7)");
  EXPECT_EQ(bad("{quantity: damping, joints: [joint2], bounds: [50, 5]}"),
            f + ".bounds = [50, 5]: lower must be below upper");
  EXPECT_EQ(bad("{quantity: stiffness, joints: [joint2], bounds: [1, 100]}"),
            f + ": the starting value (the scene's stiffness of joint2; give initial:) = 400 is "
                "outside bounds [1, 100]");
  EXPECT_EQ(bad("{quantity: damping, joints: [joint2], bounds: [1, 5], initial: 7}"),
            f + ": the starting value initial = 7 is outside bounds [1, 5]");
  EXPECT_EQ(bad("{quantity: stifness, joints: [joint2], bounds: [1, 5]}"),
            f + ".quantity = stifness: unknown (expected one of: stiffness, damping, max_force, "
                "armature, friction.static, friction.dynamic, friction.viscous, "
                "friction_coefficient, delay, mass_scale, joint_spring.stiffness, "
                "joint_spring.damping, joint_spring.reference)");
  EXPECT_EQ(bad("{quantity: stiffness, joints: [joint7], bounds: [1, 5]}"),
            f + ".joints[0] = joint7: the joint has no drive (drives: type none) to fit stiffness");
  EXPECT_EQ(bad("{quantity: delay, joints: all, bounds: [0, 2.5]}"),
            f + ".bounds[1] = 2.5: must be an integer");
  EXPECT_EQ(bad("{quantity: max_force, joints: [joint1], bounds: [1, 50]}"),
            f + ": the starting value (the scene's max_force of joint1; give initial:) = inf is "
                "outside bounds [1, 50]");
  EXPECT_EQ(fit_error_of("  parameters:\n"
                         "    - {quantity: armature, joints: [joint1], bounds: [0, 1]}\n"
                         "    - {quantity: armature, joints: [joint1], bounds: [0, 1]}\n"),
            "inline_fit.yaml: fit.parameters[1]: armature of joint1 is fitted twice");
  EXPECT_EQ(fit_error_of("  parameters: []\n"),
            "inline_fit.yaml: fit.parameters = []: must be a non-empty list of "
            "{quantity, joints, bounds}");
  EXPECT_EQ(fit_error_of(one_parameter("{quantity: armature, joints: [joint1], bounds: [0, 1]}") +
                         "  data: {resample: cubic}\n"),
            "inline_fit.yaml: fit.data.resample = cubic: must be exact or linear");
}

}  // namespace
}  // namespace featherdrive
