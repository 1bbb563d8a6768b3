// Scene files: every key reaches the simulation, sine targets are those of each step's end, and
// bad values name the key path.
#include "featherdrive/io/scene.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <numbers>
#include <sstream>

#include "featherdrive/algorithm/frame_kinematics.hpp"
#include "featherdrive/algorithm/kinematics.hpp"
#include "featherdrive/io/trajectory.hpp"
#include "support/compare.hpp"
#include "support/source_tree.hpp"

namespace featherdrive {
namespace {

using test::kInf;
using test::kExamples;

// A scene given as text, placed in examples/ so that model paths resolve there.
Scene scene_from(const std::string& text) {
  return parse_scene(text, kExamples + "inline.yaml");
}

std::string error_of(const std::string& text) {
  try {
    scene_from(text);
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(Scene, SliderSceneHasTheFilesValues) {
  const Scene s = load_scene(kExamples + "slider.yaml");
  EXPECT_EQ(s.options.dt, 0.016666666666666666);
  EXPECT_EQ(s.options.solver, SolverType::pgs);
  EXPECT_EQ(s.options.position_iterations, 4);
  EXPECT_EQ(s.options.velocity_iterations, 1);
  EXPECT_EQ(s.steps, 240);
  EXPECT_EQ(s.model()->gravity, Vec3(0, 0, -9.81));
  EXPECT_EQ(s.model_path.filename(), "slider.urdf");
  ASSERT_EQ(s.q0.size(), 1);
  EXPECT_EQ(s.q0[0], 0.05);
  EXPECT_EQ(s.qd0[0], 0.0);
  ASSERT_EQ(s.drives.size(), 1u);
  const DriveSpec& d = s.drives[0];
  EXPECT_EQ(d.joint, "slide");
  EXPECT_EQ(d.drive.type, DriveType::force);
  EXPECT_EQ(d.drive.stiffness, 400.0);
  EXPECT_EQ(d.drive.damping, 40.0);
  EXPECT_EQ(d.drive.max_force, kInf);
  ASSERT_TRUE(d.sine.has_value());
  EXPECT_EQ(d.sine->amplitude, 0.2);
  EXPECT_EQ(d.sine->frequency, 0.5);
  EXPECT_EQ(d.sine->phase, 0.3);
  EXPECT_EQ(d.sine->offset, 0.1);
}

TEST(Scene, SineTargetsAreThoseOfEachStepsEndTime) {
  const Scene s = load_scene(kExamples + "slider.yaml");
  const double dt = s.options.dt, w = 2 * std::numbers::pi * 0.5;
  auto position = [&](double t) { return 0.1 + 0.2 * std::sin(w * t + 0.3); };
  auto velocity = [&](double t) { return 0.2 * w * std::cos(w * t + 0.3); };
  Simulation sim = make_simulation(s);
  EXPECT_EQ(sim.q()[0], 0.05);
  EXPECT_NEAR(sim.drive(0).target_position, position(dt), 1e-15);  // ready for step 0
  EXPECT_NEAR(sim.drive(0).target_velocity, velocity(dt), 1e-15);
  for (int k : {1, 5, 239}) {
    apply_targets(s, sim, k);
    EXPECT_NEAR(sim.drive(0).target_position, position((k + 1) * dt), 1e-15) << k;
    EXPECT_NEAR(sim.drive(0).target_velocity, velocity((k + 1) * dt), 1e-14) << k;
  }
}

TEST(Scene, DriveDefaultsApplyToEveryJointAndEntriesOverrideThem) {
  const Scene s = load_scene(kExamples + "chain3.yaml");
  ASSERT_EQ(s.drives.size(), 3u);
  for (const DriveSpec& d : s.drives) {
    SCOPED_TRACE(d.joint);
    EXPECT_EQ(d.drive.type, DriveType::acceleration);
    EXPECT_EQ(d.drive.stiffness, 400.0);
    EXPECT_EQ(d.drive.damping, 40.0);
    EXPECT_EQ(d.drive.max_force, 50.0);
  }
  EXPECT_EQ(s.drives[0].joint, "joint1");
  EXPECT_EQ(s.drives[0].sine->amplitude, 0.6);
  EXPECT_EQ(s.drives[1].sine->phase, 1.0);
  EXPECT_FALSE(s.drives[2].sine.has_value());
  EXPECT_EQ(s.drives[2].drive.target_position, 0.5);

  // type: none removes a default drive; a joint not named keeps the default.
  const Scene t = scene_from(
      "model: chain3.urdf\nsteps: 1\ndrive_defaults: {type: force, stiffness: 10}\n"
      "drives: {joint2: {type: none}, joint3: {stiffness: 20, target_position: 0.1}}\n");
  ASSERT_EQ(t.drives.size(), 2u);
  EXPECT_EQ(t.drives[0].joint, "joint1");
  EXPECT_EQ(t.drives[0].drive.stiffness, 10.0);
  EXPECT_EQ(t.drives[1].joint, "joint3");
  EXPECT_EQ(t.drives[1].drive.type, DriveType::force);
  EXPECT_EQ(t.drives[1].drive.stiffness, 20.0);
}

TEST(Scene, JointSettingsEnvelopesAndArmatureReachTheSimulation) {
  const Scene s = scene_from(R"(
model: chain3.urdf
fixed_base: true
gravity: [0.5, 0, -9.8]
dt: 0.005
steps: 3
solver: {type: tgs, position_iterations: 8, velocity_iterations: 2}
initial: {q: {joint2: 0.25}, qd: {joint3: -1.5}}
joints:
  joint1: {lower: -0.5, upper: 0.75, max_velocity: 4, armature: 0.02,
           friction: {static: 0.3, dynamic: 0.2, viscous: 0.1}}
  joint3: {upper: 2}
drives:
  joint1: {type: force, stiffness: 100, damping: 2, max_force: 7,
           envelope: {max_effort: 6, max_actuator_velocity: 3, speed_effort_gradient: 0.5,
                      velocity_dependent_resistance: 0.25}}
)");
  const Model& m = *s.model();
  EXPECT_EQ(m.gravity, Vec3(0.5, 0, -9.8));
  EXPECT_EQ(s.options.solver, SolverType::tgs);
  EXPECT_EQ(s.options.position_iterations, 8);
  EXPECT_EQ(s.options.velocity_iterations, 2);
  EXPECT_EQ(s.options.dt, 0.005);
  const int j1 = m.dof_index("joint1"), j2 = m.dof_index("joint2"), j3 = m.dof_index("joint3");
  EXPECT_EQ(m.armature[j1], 0.02);
  EXPECT_EQ(m.armature[j2], 0.0);
  const Simulation sim = make_simulation(s);
  EXPECT_EQ(sim.q()[j2], 0.25);
  EXPECT_EQ(sim.qd()[j3], -1.5);
  EXPECT_EQ(sim.lower_limit(j1), -0.5);
  EXPECT_EQ(sim.upper_limit(j1), 0.75);
  EXPECT_EQ(sim.lower_limit(j3), -3.0);  // from the URDF
  EXPECT_EQ(sim.upper_limit(j3), 2.0);
  EXPECT_EQ(sim.max_joint_velocity(j1), 4.0);
  EXPECT_EQ(sim.max_joint_velocity(j2), 5.0);  // from the URDF
  EXPECT_EQ(sim.joint_friction(j1).static_effort, 0.3);
  EXPECT_EQ(sim.joint_friction(j1).dynamic_effort, 0.2);
  EXPECT_EQ(sim.joint_friction(j1).viscous, 0.1);
  EXPECT_EQ(sim.drive(j1).max_force, 7.0);
  EXPECT_EQ(sim.actuator_envelope(j1).max_effort, 6.0);
  EXPECT_EQ(sim.actuator_envelope(j1).max_actuator_velocity, 3.0);
  EXPECT_EQ(sim.actuator_envelope(j1).speed_effort_gradient, 0.5);
  EXPECT_EQ(sim.actuator_envelope(j1).velocity_dependent_resistance, 0.25);
  EXPECT_EQ(sim.drive(j2).type, DriveType::none);
}

// A row kind's fields by its name under joints.J and joint_defaults (the defaults first, a joint's
// fields over them, the others kept); a bad value names the joint, the field and the value.
TEST(Scene, RowKindsByNameReachTheSimulation) {
  const Scene s = scene_from(R"(
model: chain3.urdf
steps: 1
joint_defaults: {joint_spring: {stiffness: 8, reference: 0.1}}
joints:
  joint2: {joint_spring: {damping: 0.5}}
  joint3: {joint_spring: {stiffness: 0}}
)");
  const Model& m = *s.model();
  const Simulation sim = make_simulation(s);
  EXPECT_EQ(sim.row_parameters("joint_spring", m.dof_index("joint1")),
            (std::vector<double>{8.0, 0.0, 0.1}));
  EXPECT_EQ(sim.row_parameters("joint_spring", m.dof_index("joint2")),
            (std::vector<double>{8.0, 0.5, 0.1}));
  EXPECT_EQ(sim.row_parameters("joint_spring", m.dof_index("joint3")),
            (std::vector<double>{0.0, 0.0, 0.1}));
  const std::string head = "model: chain3.urdf\nsteps: 1\n";
  EXPECT_EQ(error_of(head + "joints: {joint1: {joint_spring: {stiffness: -1}}}"),
            kExamples + "inline.yaml: joint spring of joint 'joint1': stiffness = -1 must be "
                        "finite and >= 0");
  EXPECT_NE(error_of(head + "joints: {joint1: {joint_spring: {k: 1}}}")
                .find("joints.joint1.joint_spring.k: unknown key (expected one of: stiffness, "
                      "damping, reference)"),
            std::string::npos);
  EXPECT_NE(error_of(head + "joints: {joint1: {joint_sprung: {}}}")
                .find("joints.joint1.joint_sprung: unknown key"),
            std::string::npos);
}

TEST(Scene, JsonAndYamlGiveTheSameScene) {
  const Scene yaml = scene_from(
      "model: slider.urdf\ndt: 0.01\nsteps: 5\ndrives: {slide: {type: acceleration, stiffness: 9, "
      "target: {sine: {amplitude: 0.1, frequency: 2}}}}\n");
  const Scene json = scene_from(
      R"({"model": "slider.urdf", "dt": 0.01, "steps": 5, "drives": {"slide": {"type": "acceleration",
          "stiffness": 9, "target": {"sine": {"amplitude": 0.1, "frequency": 2}}}}})");
  EXPECT_EQ(yaml.options.dt, json.options.dt);
  EXPECT_EQ(yaml.steps, json.steps);
  ASSERT_EQ(json.drives.size(), 1u);
  EXPECT_EQ(json.drives[0].drive.type, DriveType::acceleration);
  EXPECT_EQ(json.drives[0].drive.stiffness, 9.0);
  EXPECT_EQ(json.drives[0].sine->frequency, 2.0);
  EXPECT_EQ(yaml.drives[0].sine->frequency, 2.0);
}

TEST(Scene, RunSceneReportsEveryStateAndMatchesAManualLoop) {
  const Scene s = load_scene(kExamples + "chain3.yaml");
  int calls = 0;
  const Simulation end = run_scene(s, [&](const Simulation& sim, int k) {
    EXPECT_EQ(sim.step_count(), k);
    ++calls;
  });
  EXPECT_EQ(calls, s.steps + 1);
  Simulation manual = make_simulation(s);
  for (int k = 0; k < s.steps; ++k) {
    apply_targets(s, manual, k);
    manual.step();
  }
  for (int i = 0; i < 3; ++i) EXPECT_EQ(end.q()[i], manual.q()[i]);
}

TEST(Scene, BadValuesNameTheFileTheKeyPathAndTheValue) {
  const std::string head = "model: chain3.urdf\nsteps: 1\n";
  EXPECT_EQ(error_of(head + "drives: {joint1: {type: force, stiffness: -5}}"),
            kExamples + "inline.yaml: drives.joint1.stiffness = -5: must be finite and >= 0");
  EXPECT_EQ(error_of(head + "drives: {joint1: {type: force, damping: .nan}}"),
            kExamples + "inline.yaml: drives.joint1.damping = .nan: must be finite and >= 0");
  EXPECT_EQ(error_of(head + "solver: {type: tgs, position_iterations: 0}"),
            kExamples + "inline.yaml: solver.position_iterations = 0: must be >= 1");
  EXPECT_NE(error_of(head + "drives: {joint9: {type: force}}")
                .find("drives.joint9: no joint named 'joint9'"),
            std::string::npos);
  EXPECT_NE(error_of(head + "drive_defaults: {stiffness: 3}").find("drive_defaults.type: missing"),
            std::string::npos);
  EXPECT_NE(error_of(head + "initial: {q: {joint1: [1]}}")
                .find("initial.q.joint1 = [1]: must be a number"),
            std::string::npos);
  EXPECT_NE(error_of(head + "joints: {joint1: {friction: {kinetic: 1}}}")
                .find("joints.joint1.friction.kinetic: unknown key"),
            std::string::npos);
  EXPECT_NE(error_of("model: slider.urdf\nsteps: 1\nfixed_base: false\n")
                .find("slider.urdf: link 'base' has no <inertial>"),
            std::string::npos);
  EXPECT_THROW(load_scene(kExamples + "no_such_scene.yaml"), InputError);
}

// initial.base places a floating root in world axes: forward kinematics of the simulation the
// scene makes finds the root link there, moving as the scene says; given to a fixed robot, or
// malformed, it is refused naming the key.
TEST(Scene, InitialBasePlacesAFloatingRootInWorldAxes) {
  const std::string head =
      "model: /usr/share/mujoco/model/humanoid/humanoid.xml\nfixed_base: false\nsteps: 1\n";
  const Scene scene = scene_from(
      head + "initial: {base: {position: [0.1, -0.2, 1.5], orientation: [0, 0, 0, 2], "
             "linear_velocity: [1, 0, -0.5], angular_velocity: [0, 0.3, 0]}}\n");
  const Simulation sim = make_simulation(scene);
  const Model& model = sim.model();
  ASSERT_TRUE(model.floating_base());
  Data data(model);
  forward_kinematics(model, data, sim.q(), sim.qd());
  // (0, 0, 0, 2) normalised: half a turn about z.
  EXPECT_LT((data.world_rotation[0] - Vec3(-1, -1, 1).asDiagonal().toDenseMatrix()).norm(), 1e-15);
  EXPECT_LT((data.world_position[0] - Vec3(0.1, -0.2, 1.5)).norm(), 1e-15);
  const Vec6 v = link_velocity(model, data, 0, ReferenceFrame::world_aligned);
  EXPECT_LT((v.head<3>() - Vec3(0, 0.3, 0)).norm(), 1e-15);
  EXPECT_LT((v.tail<3>() - Vec3(1, 0, -0.5)).norm(), 1e-15);
  // Keys left out keep the model's pose: its position with only the velocity given.
  const Scene moving = scene_from(head + "initial: {base: {linear_velocity: [0, 0, 2]}}\n");
  const Scene still = scene_from(head);
  EXPECT_EQ(moving.q0, still.q0);
  EXPECT_EQ(error_of("model: slider.urdf\nsteps: 1\ninitial: {base: {position: [0, 0, 1]}}\n"),
            kExamples + "inline.yaml: initial.base = {position: [0, 0, 1]}: the robot has no "
                        "floating root (fixed_base: false gives one)");
  EXPECT_EQ(error_of(head + "initial: {base: {orientation: [0, 0, 0, 0]}}\n"),
            kExamples + "inline.yaml: initial.base.orientation = [0, 0, 0, 0]: must not be zero");
  EXPECT_EQ(error_of(head + "initial: {base: {orientation: [1, 0, 0]}}\n"),
            kExamples + "inline.yaml: initial.base.orientation = [1, 0, 0]: must be a list of 4 "
                        "numbers (w, x, y, z)");
  EXPECT_EQ(error_of(head + "initial: {base: {position: [0, .nan, 0]}}\n"),
            kExamples + "inline.yaml: initial.base.position[1] = .nan: must be finite");
  EXPECT_NE(error_of(head + "initial: {base: {pos: [0, 0, 0]}}\n")
                .find("initial.base.pos: unknown key"),
            std::string::npos);
}

std::string repeat(const std::string& s, int n) {
  std::string out;
  for (int i = 0; i < n; ++i) out += s;
  return out;
}

TEST(Scene, ScenesNestedDeeperThanTheBoundAreRefusedBeforeYamlCppParses) {
  ASSERT_EQ(kMaxSceneDepth, 64);
  const std::string head = "model: chain3.urdf\nsteps: 1\n";
  const std::string at = kExamples + "inline.yaml: line ";
  const std::string deeper = ": nested deeper than 64 levels (the bound)";
  // Flow sequences and maps, 100 000 deep, closed or not; the top-level map is one level.
  EXPECT_EQ(error_of(head + "description: " + repeat("[", 100000)), at + "3" + deeper);
  EXPECT_EQ(error_of(head + "description: " + repeat("{a: ", 100000) + repeat("}", 100000)),
            at + "3" + deeper);
  EXPECT_EQ(error_of(head + "description:\n  " + repeat("[\n", 100000)), at + "66" + deeper);
  // Block sequences on one line, and block maps one space deeper per line.
  EXPECT_EQ(error_of(head + "description:\n" + repeat("- ", 100000) + "x"), at + "4" + deeper);
  std::string block = head + "description:\n";
  for (int i = 1; i <= 1000; ++i) block += std::string(i, ' ') + "a:\n";
  EXPECT_EQ(error_of(block), at + "67" + deeper);
  // Mixed: flow inside block.
  EXPECT_EQ(error_of(head + "description:\n - - - " + repeat("{a: [", 40)), at + "4" + deeper);

  // Shallow scenes with brackets in quotes, comments, plain and block scalars load.
  const std::string many = repeat("[{", 500);
  for (const std::string& text :
       {"description: \"" + many + "\\\" '" + many + "\"\n", "description: '" + many + "'' \"'\n",
        "# " + many + "\ndescription: x # " + many + "\n", "description: it's " + many + "\n",
        "description: |\n  " + many + "\n   \"\n    '\n" + repeat(" ", 200) + "x\n",
        "description: >-\n  a\n" + repeat(" ", 300) + many + "\n"}) {
    SCOPED_TRACE(text.substr(0, 80));
    EXPECT_EQ(error_of(head + text + "drives: {joint1: {type: force, stiffness: 1}}"),
              "(no error)");
  }
}

TEST(Scene, IntegersAreCheckedInSixtyFourBitsBeforeTheyAreNarrowed) {
  const std::string head = "model: chain3.urdf\n";
  const std::string file = kExamples + "inline.yaml: ";
  struct Case {
    std::string text, error;
  };
  const Case cases[] = {
      {"steps: 1\nsolver: {position_iterations: 4294967297}",
       "solver.position_iterations = 4294967297: must be <= 1000000"},
      {"steps: 1\nsolver: {velocity_iterations: 4294967296}",
       "solver.velocity_iterations = 4294967296: must be <= 1000000"},
      {"steps: 1\nsolver: {velocity_iterations: 1000001}",
       "solver.velocity_iterations = 1000001: must be <= 1000000"},
      {"steps: 1\nsolver: {position_iterations: -4294967295}",
       "solver.position_iterations = -4294967295: must be >= 1"},
      {"steps: 2147483648", "steps = 2147483648: must be <= 1000000000"},
      {"steps: 1000000001", "steps = 1000000001: must be <= 1000000000"},
      {"steps: 99999999999999999999999", "steps = 99999999999999999999999: must be <= 1000000000"},
      {"steps: -99999999999999999999999", "steps = -99999999999999999999999: must be >= 0"},
      {"steps: -9223372036854775808", "steps = -9223372036854775808: must be >= 0"},
      {"steps: 4.5", "steps = 4.5: must be an integer"},
      {"steps: 1e3", "steps = 1e3: must be an integer"},
      {"steps: 0x10", "steps = 0x10: must be an integer"},
      {"steps: 12abc", "steps = 12abc: must be an integer"},
      {"steps: +-3", "steps = +-3: must be an integer"},
      {"steps: ''", "steps = : must be an integer"},
      {"steps: [1]", "steps = [1]: must be an integer"},
  };
  for (const Case& c : cases) EXPECT_EQ(error_of(head + c.text), file + c.error) << c.text;
  // The largest values load as themselves.
  const Scene s = scene_from(head +
                             "steps: +1000000000\n"
                             "solver: {position_iterations: 1000000, velocity_iterations: 0}");
  EXPECT_EQ(s.steps, 1000000000);
  EXPECT_EQ(s.options.position_iterations, 1000000);
  EXPECT_EQ(s.options.velocity_iterations, 0);
}

TEST(Scene, ApplyTargetsIsExactForEveryStepIndex) {
  const Scene scene = load_scene(kExamples + "slider.yaml");
  Simulation sim = make_simulation(scene);
  const SineTarget& sine = *scene.drives[0].sine;
  const double dt = scene.options.dt, w = 2.0 * std::numbers::pi * sine.frequency;
  for (int k : {0, 1, 1000, std::numeric_limits<int>::max() - 1, std::numeric_limits<int>::max(),
                -1, std::numeric_limits<int>::min()}) {
    SCOPED_TRACE(k);
    apply_targets(scene, sim, k);
    const double t = (static_cast<double>(k) + 1.0) * dt;
    EXPECT_EQ(sim.drive(0).target_position,
              sine.offset + sine.amplitude * std::sin(w * t + sine.phase));
    EXPECT_EQ(sim.drive(0).target_velocity, sine.amplitude * w * std::cos(w * t + sine.phase));
  }
  EXPECT_GT(sim.drive(0).target_position, -1.0);  // INT_MIN: t < 0 is just another time
}

std::string slider_with(const std::string& control) {
  std::ifstream in(kExamples + "slider.yaml");
  std::stringstream text;
  text << in.rdbuf() << control;
  return text.str();
}

TEST(Scene, ControlDefaultsToOneHeldStepAndBadValuesNameTheKey) {
  const Scene plain = scene_from(slider_with(""));
  EXPECT_EQ(plain.control.substeps, 1);
  EXPECT_EQ(plain.control.targets, TargetInterpolation::hold);
  const Scene four = scene_from(slider_with("control: {substeps: 4, targets: linear}\n"));
  EXPECT_EQ(four.control.substeps, 4);
  EXPECT_EQ(four.control.targets, TargetInterpolation::linear);
  EXPECT_EQ(error_of(slider_with("control: {substeps: 0}\n")),
            kExamples + "inline.yaml: control.substeps = 0: must be >= 1");
  EXPECT_EQ(error_of(slider_with("control: {substeps: 1000001}\n")),
            kExamples + "inline.yaml: control.substeps = 1000001: must be <= 1000000");
  EXPECT_EQ(error_of(slider_with("control: {targets: cubic}\n")),
            kExamples + "inline.yaml: control.targets = cubic: must be hold or linear");
  EXPECT_NE(error_of(slider_with("control: {decimation: 2}\n"))
                .find("control.decimation: unknown key (expected one of: substeps, targets)"),
            std::string::npos);
}

// guard: present = on, its bounds defaulted; bad bounds name the key and the value
// (docs/math/step_guard.md).
TEST(Scene, GuardIsOnWhenPresentAndBadValuesNameTheKey) {
  EXPECT_FALSE(scene_from(slider_with("")).options.guard.enabled);
  const Scene plain = scene_from(slider_with("guard: {}\n"));
  EXPECT_TRUE(plain.options.guard.enabled);
  EXPECT_EQ(plain.options.guard.max_joint_step, 0.25);
  EXPECT_EQ(plain.options.guard.max_substeps, 64);
  EXPECT_EQ(plain.options.guard.energy_tolerance, 0.02);
  EXPECT_EQ(plain.options.guard.dissipation_share, 0.15);
  const Scene set = scene_from(
      slider_with("guard: {max_joint_step: 0.1, max_substeps: 16, energy_tolerance: 0.005, "
                  "dissipation_share: 2.5}\n"));
  EXPECT_EQ(set.options.guard.max_joint_step, 0.1);
  EXPECT_EQ(set.options.guard.max_substeps, 16);
  EXPECT_EQ(set.options.guard.energy_tolerance, 0.005);
  EXPECT_EQ(set.options.guard.dissipation_share, 2.5);
  EXPECT_TRUE(make_simulation(set).options().guard.enabled);
  EXPECT_EQ(error_of(slider_with("guard: {max_joint_step: -0.5}\n")),
            kExamples + "inline.yaml: guard.max_joint_step = -0.5: must be finite and > 0");
  EXPECT_EQ(error_of(slider_with("guard: {max_joint_step: .nan}\n")),
            kExamples + "inline.yaml: guard.max_joint_step = .nan: must be finite and > 0");
  EXPECT_EQ(error_of(slider_with("guard: {max_substeps: 0}\n")),
            kExamples + "inline.yaml: guard.max_substeps = 0: must be >= 2");
  EXPECT_EQ(error_of(slider_with("guard: {max_substeps: 100000}\n")),
            kExamples + "inline.yaml: guard.max_substeps = 100000: must be <= 4096");
  EXPECT_EQ(error_of(slider_with("guard: {energy_tolerance: 0}\n")),
            kExamples + "inline.yaml: guard.energy_tolerance = 0: must be in (0, 1]");
  EXPECT_EQ(error_of(slider_with("guard: {dissipation_share: 150}\n")),
            kExamples + "inline.yaml: guard.dissipation_share = 150: must be in (0, 100]");
  EXPECT_NE(error_of(slider_with("guard: {max_step: 2}\n"))
                .find("guard.max_step: unknown key (expected one of: max_joint_step, "
                      "max_substeps, energy_tolerance, dissipation_share)"),
            std::string::npos);
}

// The scene's per-step rule (what the CLI and compare-physx run) against the core's control step
// fed the sine at the control times t = (m + 1) k dt, from the sine at t = 0 for linear.
TEST(Scene, ControlStepsMatchTheCoreControlStepBitForBit) {
  for (const std::string mode : {"hold", "linear"}) {
    const int k = 4;
    const Scene s =
        scene_from(slider_with("control: {substeps: 4, targets: " + mode + "}\n"));
    const SineTarget& sine = *s.drives[0].sine;
    const double dt = s.options.dt;
    Simulation scene_run = make_simulation(s), core_run = make_simulation(s);
    core_run.set_drive_target(0, sine.position(0.0), sine.velocity(0.0));
    for (int m = 0; m < 10; ++m) {
      for (int j = 0; j < k; ++j) {
        apply_targets(s, scene_run, m * k + j);
        scene_run.step();
      }
      const double t = static_cast<double>((m + 1) * k) * dt;
      step_control(core_run, VecX::Constant(1, sine.position(t)),
                   VecX::Constant(1, sine.velocity(t)), s.control);
      ASSERT_EQ(scene_run.q()[0], core_run.q()[0]) << mode << " control step " << m;
      ASSERT_EQ(scene_run.qd()[0], core_run.qd()[0]) << mode << " control step " << m;
    }
    // Held targets stay put for k steps; linear ones move every step.
    apply_targets(s, scene_run, 41);
    const double at41 = scene_run.drive(0).target_position;
    apply_targets(s, scene_run, 42);
    EXPECT_EQ(at41 == scene_run.drive(0).target_position, mode == "hold");
  }
}

TEST(Scene, SineTargetsThatOverflowAreRefusedWithTheKey) {
  const std::string head =
      "model: slider.urdf\nsteps: 1\ndrives: {slide: {type: force, stiffness: 1, ";
  const std::string file = kExamples + "inline.yaml: drives.slide.target.sine = ";
  EXPECT_EQ(error_of(head + "target: {sine: {amplitude: 1e308, offset: 1e308}}}}"),
            file + "{amplitude: 1e308, offset: 1e308}: offset + amplitude overflows");
  EXPECT_EQ(error_of(head + "target: {sine: {amplitude: -1.5e308, offset: -1e308}}}}"),
            file + "{amplitude: -1.5e308, offset: -1e308}: offset + amplitude overflows");
  EXPECT_EQ(error_of(head + "target: {sine: {amplitude: 1e300, frequency: 1e10}}}}"),
            file +
                "{amplitude: 1e300, frequency: 1e10}: the velocity amplitude 2 pi frequency "
                "amplitude overflows");
  EXPECT_EQ(error_of(head + "target: {sine: {amplitude: 0, frequency: 1e308}}}}"),
            file +
                "{amplitude: 0, frequency: 1e308}: the velocity amplitude 2 pi frequency "
                "amplitude overflows");
  // Finite everywhere but at a huge time: 2 pi f t overflows at step 999 (t = 1000 s).
  const Scene s = scene_from(
      "model: slider.urdf\nsteps: 1\ndt: 1\ndrives: {slide: {type: force, "
      "target: {sine: {amplitude: 1, frequency: 1e305}}}}");
  Simulation sim = make_simulation(s);
  apply_targets(s, sim, 0);
  try {
    apply_targets(s, sim, 999);
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()),
              kExamples +
                  "inline.yaml: drives.slide.target.sine: the target at t = 1000 s is not "
                  "finite (2 pi frequency t overflows)");
  }
}

TEST(Scene, LimitsOfInfOnTheWrongSideAndSubnormalStepsAreRefused) {
  const std::string head = "model: chain3.urdf\nsteps: 1\n";
  const std::string file = kExamples + "inline.yaml: ";
  EXPECT_EQ(error_of(head + "joints: {joint1: {lower: .inf, upper: .inf}}"),
            file + "joints.joint1.lower = .inf: must be a number below .inf");
  EXPECT_EQ(error_of(head + "joints: {joint1: {lower: -.inf, upper: -.inf}}"),
            file + "joints.joint1.upper = -.inf: must be a number above -.inf");
  EXPECT_EQ(error_of(head + "joints: {joint2: {lower: .Inf}}"),
            file + "joints.joint2.lower = .Inf: must be a number below .inf");
  EXPECT_EQ(error_of(head + "joints: {joint3: {upper: -.INF}}"),
            file + "joints.joint3.upper = -.INF: must be a number above -.inf");
  const Scene open = scene_from(head + "joints: {joint1: {lower: -.inf, upper: .inf}}");
  const Simulation sim = make_simulation(open);
  EXPECT_EQ(sim.lower_limit(0), -kInf);
  EXPECT_EQ(sim.upper_limit(0), kInf);

  const std::string range = ": must be in [2.2250738585072014e-308, 1000] s (a normal number)";
  for (const char* dt : {"1e-310", "4.9e-324", "2.2e-308", "1000.5", "1e308"})
    EXPECT_EQ(error_of(head + "dt: " + dt), file + "dt = " + dt + range) << dt;
  EXPECT_EQ(scene_from(head + "dt: 2.2250738585072014e-308").options.dt,
            std::numeric_limits<double>::min());
  EXPECT_EQ(scene_from(head + "dt: 1000").options.dt, 1000.0);
}

TEST(Scene, TrajectoryHeaderFollowsTheUrdfJointOrder) {
  const Scene s = scene_from("model: ../tests/data/branches.urdf\nsteps: 1\n");
  std::ostringstream out;
  TrajectoryWriter writer(out, s.robot);
  EXPECT_EQ(
      out.str(),
      "step,t,q:right1,q:left,q:right2,qd:right1,qd:left,qd:right2,f:right1,f:left,f:right2\n");
  Simulation sim = make_simulation(s);
  VecX q(3);
  q << 0.125, -0.5, 0.1;  // model order: right1, right2, left
  sim.set_q(q);
  writer.write(0, sim, true);
  EXPECT_EQ(out.str().substr(out.str().find('\n') + 1), "0,0,0.125,0.1,-0.5,0,0,0,0,0,0\n");
}

// drives.J.actuator: an explicit actuator on a joint whose drive type is none; urdf_effort gives
// the URDF's <limit effort> (200 N on the slider) to the actuators or the drives without a limit.
TEST(Scene, ActuatorsAndUrdfEffortReachTheSimulation) {
  const std::string head = "model: slider.urdf\nsteps: 1\n";
  const std::string motor =
      "drives:\n  slide: {type: none, target_position: 0.3, actuator: {type: dc_motor, "
      "stiffness: 500, damping: 20, saturation_effort: 300, velocity_limit: 4, delay: 2}}\n";
  for (const char* mode : {"none", "effort_limit", "max_force"}) {
    const Scene s = scene_from(head + "urdf_effort: " + mode + "\n" + motor);
    Simulation sim = make_simulation(s);
    const ExplicitActuator& a = sim.actuator(0);
    EXPECT_EQ(a.kind, ActuatorKind::dc_motor);
    EXPECT_EQ(a.stiffness, 500.0);
    EXPECT_EQ(a.damping, 20.0);
    EXPECT_EQ(a.saturation_effort, 300.0);
    EXPECT_EQ(a.velocity_limit, 4.0);
    EXPECT_EQ(a.delay, 2);
    EXPECT_EQ(a.integration, ActuatorIntegration::explicit_law);  // the default
    EXPECT_EQ(a.effort_limit, std::string(mode) == "effort_limit" ? 200.0 : kInf) << mode;
    EXPECT_EQ(sim.drive(0).type, DriveType::none);
    // The first step: x = v = 0, demand 500 * 0.3 = 150 within min(S, E) = 200 (or 300).
    sim.step();
    EXPECT_EQ(sim.actuator_force()[0], 150.0);
    // The CSV's f: column is the dof's driver, here the actuator: 150, as computed above.
    std::ostringstream out;
    TrajectoryWriter(out, s.robot).write(1, sim, false);
    EXPECT_EQ(out.str().substr(out.str().rfind(',') + 1), "150\n") << mode;
  }
  // An actuator's own effort_limit stands; drives get the URDF's as max_force.
  Simulation own = make_simulation(scene_from(
      head + "urdf_effort: effort_limit\ndrives:\n  slide: {type: none, actuator: {type: "
             "ideal_pd, stiffness: 10, effort_limit: 50}}\n"));
  EXPECT_EQ(own.actuator(0).effort_limit, 50.0);
  for (const char* mode : {"none", "max_force"}) {
    Simulation drive = make_simulation(scene_from(
        head + "urdf_effort: " + mode + "\ndrives:\n  slide: {type: force, stiffness: 10}\n"));
    EXPECT_EQ(drive.drive(0).max_force, std::string(mode) == "max_force" ? 200.0 : kInf);
    EXPECT_FALSE(drive.has_actuator(0));
  }
  const Scene table = scene_from(
      head + "drives:\n  slide: {type: none, actuator: {type: remotized_pd, stiffness: 10, "
             "lookup: [[-0.5, 10], [0.5, 40]]}}\n");
  ASSERT_EQ(table.drives.size(), 1u);
  ASSERT_TRUE(table.drives[0].actuator);
  EXPECT_EQ(table.drives[0].actuator->lookup,
            (std::vector<std::pair<double, double>>{{-0.5, 10.0}, {0.5, 40.0}}));
  // integration: implicit solves the law at the step's end (docs/math/implicit_actuators.md, eq.
  // I2): the first step's force is the PD law at the state it ends in.
  Simulation late = make_simulation(scene_from(
      head + "drives:\n  slide: {type: none, target_position: 0.3, actuator: {type: ideal_pd, "
             "stiffness: 500, damping: 20, integration: implicit}}\n"));
  EXPECT_EQ(late.actuator(0).integration, ActuatorIntegration::implicit_law);
  late.step();
  EXPECT_NEAR(late.actuator_force()[0], 500.0 * (0.3 - late.q()[0]) - 20.0 * late.qd()[0], 1e-9);
  EXPECT_EQ(late.drive_force()[0], 0.0);
}

TEST(Scene, BadActuatorsNameTheKeyPath) {
  const std::string head = "model: slider.urdf\nsteps: 1\n";
  const std::string file = kExamples + "inline.yaml: ";
  EXPECT_EQ(error_of(head + "drives:\n  slide: {type: force, actuator: {type: ideal_pd}}\n"),
            file + "drives.slide: an explicit actuator and a force drive on one joint: give the "
                   "drive type: none");
  EXPECT_EQ(error_of(head + "drives:\n  slide: {type: none, actuator: {type: servo}}\n"),
            file + "drives.slide.actuator.type = servo: must be ideal_pd, dc_motor or "
                   "remotized_pd");
  EXPECT_EQ(error_of(head + "drives:\n  slide: {type: none, actuator: {stiffness: 1}}\n"),
            file + "drives.slide.actuator.type: missing (ideal_pd, dc_motor or remotized_pd)");
  EXPECT_EQ(error_of(head + "drives:\n  slide: {type: none, actuator: {type: dc_motor}}\n"),
            file + "drives.slide.actuator: actuator on joint 'slide': saturation_effort = 0 must "
                   "be finite and > 0 for a dc_motor");
  EXPECT_EQ(error_of(head + "drives:\n  slide: {type: none, actuator: {type: remotized_pd, "
                            "lookup: [[0, 1, 2]]}}\n"),
            file + "drives.slide.actuator.lookup[0] = [0, 1, 2]: must be a pair [position, max "
                   "effort]");
  EXPECT_EQ(error_of(head + "drives:\n  slide: {type: none, actuator: {type: ideal_pd, "
                            "delay: -1}}\n"),
            file + "drives.slide.actuator.delay = -1: must be >= 0");
  EXPECT_EQ(error_of(head + "drives:\n  slide: {type: none, actuator: {type: ideal_pd, "
                            "integration: semi}}\n"),
            file + "drives.slide.actuator.integration = semi: must be explicit or implicit");
  EXPECT_EQ(error_of(head + "urdf_effort: sim\n"),
            file + "urdf_effort = sim: must be none, max_force or effort_limit");
}

// delay: K in drive_defaults and per drive reaches Simulation::set_drive_delay; a drive of type
// none (an actuator's) keeps no default delay.
TEST(Scene, DriveDelaysReachTheSimulation) {
  const Scene s = scene_from(
      "model: arm7.urdf\nsteps: 1\ndrive_defaults: {type: force, stiffness: 100, delay: 2}\n"
      "drives:\n  joint2: {delay: 0}\n  joint3: {delay: 7}\n"
      "  joint4: {type: none, actuator: {type: ideal_pd, stiffness: 5}}\n");
  const Simulation sim = make_simulation(s);
  const int expected[] = {2, 0, 7, 0, 2, 2, 2};
  for (int d = 0; d < 7; ++d) EXPECT_EQ(sim.drive_delay(d), expected[d]) << d;
  EXPECT_EQ(s.drives[2].delay, 7);
}

TEST(Scene, BadDrivesDelaysNameTheKeyAndValue) {
  const std::string head = "model: slider.urdf\nsteps: 1\n";
  const std::string file = kExamples + "inline.yaml: ";
  EXPECT_EQ(error_of(head + "drives:\n  slide: {type: force, delay: -1}\n"),
            file + "drives.slide.delay = -1: must be >= 0");
  EXPECT_EQ(error_of(head + "drives:\n  slide: {type: force, delay: 2.5}\n"),
            file + "drives.slide.delay = 2.5: must be an integer");
  EXPECT_EQ(error_of(head + "drives:\n  slide: {type: force, delay: 100001}\n"),
            file + "drives.slide.delay = 100001: must be <= 100000");
  EXPECT_EQ(error_of(head + "drive_defaults: {type: force, delay: [1]}\n"),
            file + "drive_defaults.delay = [1]: must be an integer");
  EXPECT_EQ(error_of(head + "drives:\n  slide: {type: none, delay: 3, actuator: {type: "
                            "ideal_pd}}\n"),
            file + "drives.slide.delay = 3: delays a drive of type force or acceleration; this "
                   "one has type none (an explicit actuator takes actuator.delay)");
}

}  // namespace
}  // namespace featherdrive
