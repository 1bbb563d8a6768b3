// Settings and State as values (issue 32): the defaults are the model's values (and PhysX's where
// compat physx says so), Settings::validate throws the very message the setter of the same field
// throws, a simulation given another's settings and state steps as that one, bit for bit, and so
// does a copy of one, whose workspace is its own.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <random>
#include <string>

#include "featherdrive/sim/simulation.hpp"
#include "support/compare.hpp"
#include "support/models.hpp"

namespace featherdrive::settings_test {
namespace {

using test::same_bits;

// The first dof of a joint of this type (-1 for none).
int first_dof(const Model& model, JointType type) {
  for (int d = 0; d < model.nv; ++d)
    if (model.links[model.dof_link[d]].joint_type == type) return d;
  return -1;
}

// A floating random tree with revolute, prismatic and spherical joints.
std::shared_ptr<const Model> tree() {
  for (unsigned seed = 1;; ++seed) {
    auto model = test::make_random_tree(seed, 9, /*floating=*/true);
    int revolute = 0;
    for (int d = 0; d < model->nv; ++d)
      revolute += model->links[model->dof_link[d]].joint_type == JointType::revolute;
    if (revolute >= 2 && first_dof(*model, JointType::prismatic) >= 0 &&
        first_dof(*model, JointType::spherical) >= 0)
      return model;
  }
}

int second_revolute(const Model& model) {
  const int first = first_dof(model, JointType::revolute);
  for (int d = first + 1; d < model.nv; ++d)
    if (model.links[model.dof_link[d]].joint_type == JointType::revolute) return d;
  return -1;
}

constexpr auto message_of = test::invalid_argument_message;

TEST(Settings, DefaultsAreTheModelsValuesAndPhysxsWithCompatPhysx) {
  const auto model = tree();
  const int r = first_dof(*model, JointType::revolute);
  const int p = first_dof(*model, JointType::prismatic);
  const int f = first_dof(*model, JointType::floating);
  for (const Compat compat : {Compat::none, Compat::physx}) {
    SimulationOptions options;
    options.compat = compat;
    const Settings s = Settings::defaults(*model, options);
    EXPECT_NO_THROW(s.validate(*model));
    const bool physx = compat == Compat::physx;
    EXPECT_TRUE(same_bits(s.lower_limit, model->lower_limit));
    EXPECT_TRUE(same_bits(s.upper_limit, model->upper_limit));
    EXPECT_EQ(s.friction[static_cast<size_t>(r)].dynamic_effort, model->friction[r]);
    EXPECT_EQ(s.friction[static_cast<size_t>(r)].viscous, model->damping[r]);
    EXPECT_EQ(s.friction_coefficient[r], physx ? 0.05 : 0.0);
    EXPECT_EQ(s.friction_coefficient[f], 0.0);  // no rows on a floating base
    EXPECT_EQ(s.revolute_wrap[static_cast<size_t>(r)],
              physx ? RevoluteWrap::wrapped : RevoluteWrap::unwrapped);
    EXPECT_EQ(s.revolute_wrap[static_cast<size_t>(p)], RevoluteWrap::unwrapped);
    EXPECT_EQ(s.link_parameters[0].cfm_scale, physx ? 0.025 : 0.0);
    EXPECT_TRUE(s.mimic_joints.empty());
    // A new simulation starts from them.
    const Simulation sim(model, options);
    EXPECT_TRUE(same_bits(sim.settings().max_joint_velocity, s.max_joint_velocity));
    EXPECT_TRUE(same_bits(sim.settings().friction_coefficient, s.friction_coefficient));
    EXPECT_EQ(sim.revolute_wrap(r), s.revolute_wrap[static_cast<size_t>(r)]);
  }
}

// Each case changes one field of the settings and calls the setter of that field with the same
// value: validate must refuse with the setter's message, word for word.
TEST(Settings, ValidateThrowsTheSettersMessageWordForWord) {
  const auto model = tree();
  const int r = first_dof(*model, JointType::revolute);
  const int r2 = second_revolute(*model);
  const int p = first_dof(*model, JointType::prismatic);
  const int b = first_dof(*model, JointType::spherical);
  const int f = first_dof(*model, JointType::floating);
  const auto k = [](int d) { return static_cast<size_t>(d); };
  const Drive drive{.type = DriveType::force, .stiffness = 100.0, .damping = 10.0};
  const ExplicitActuator pd{.kind = ActuatorKind::ideal_pd, .stiffness = 50.0};
  struct Case {
    const char* name;
    std::function<void(Settings&)> change;
    std::function<void(Simulation&)> setter;
  };
  const std::vector<Case> cases = {
      {"limits reversed", [&](Settings& s) { s.lower_limit[r] = 1.0, s.upper_limit[r] = -1.0; },
       [&](Simulation& s) { s.set_joint_limits(r, 1.0, -1.0); }},
      {"spherical limit beyond pi", [&](Settings& s) { s.lower_limit[b] = -4.0; },
       [&](Simulation& s) { s.set_joint_limits(b, -4.0, s.upper_limit(b)); }},
      {"limits on a floating base", [&](Settings& s) { s.lower_limit[f] = -1.0; },
       [&](Simulation& s) { s.set_joint_limits(f, -1.0, s.upper_limit(f)); }},
      {"negative friction", [&](Settings& s) { s.friction[k(p)] = {-1.0, 0.0, 0.0}; },
       [&](Simulation& s) { s.set_joint_friction(p, {-1.0, 0.0, 0.0}); }},
      {"negative max velocity", [&](Settings& s) { s.max_joint_velocity[r] = -1.0; },
       [&](Simulation& s) { s.set_max_joint_velocity(r, -1.0); }},
      {"negative friction coefficient", [&](Settings& s) { s.friction_coefficient[r] = -1.0; },
       [&](Simulation& s) { s.set_friction_coefficient(r, -1.0); }},
      {"bad envelope", [&](Settings& s) { s.envelopes[k(r)].max_effort = -1.0; },
       [&](Simulation& s) {
         ActuatorEnvelope e;
         e.max_effort = -1.0;
         s.set_actuator_envelope(r, e);
       }},
      {"wrap on a prismatic joint",
       [&](Settings& s) { s.revolute_wrap[k(p)] = RevoluteWrap::wrapped; },
       [&](Simulation& s) { s.set_revolute_wrap(p, RevoluteWrap::wrapped); }},
      {"drive on a floating base", [&](Settings& s) { s.drives[k(f)] = drive; },
       [&](Simulation& s) { s.set_drive(f, drive); }},
      {"drive with a NaN gain",
       [&](Settings& s) { s.drives[k(r)] = drive, s.drives[k(r)].stiffness = std::nan(""); },
       [&](Simulation& s) {
         Drive d = drive;
         d.stiffness = std::nan("");
         s.set_drive(r, d);
       }},
      {"actuator on a spherical axis", [&](Settings& s) { s.actuators[k(b)] = pd; },
       [&](Simulation& s) { s.set_actuator(b, pd); }},
      {"drive beside an actuator",
       [&](Settings& s) { s.actuators[k(r2)] = pd, s.drives[k(r2)] = drive; },
       [&](Simulation& s) {
         s.set_actuator(r2, pd);
         s.set_drive(r2, drive);
       }},
      {"delay without a drive", [&](Settings& s) { s.drive_delay[k(r)] = 3; },
       [&](Simulation& s) { s.set_drive_delay(r, 3); }},
      {"delay out of range",
       [&](Settings& s) { s.drives[k(r)] = drive, s.drive_delay[k(r)] = kMaxDelay + 1; },
       [&](Simulation& s) {
         s.set_drive(r, drive);
         s.set_drive_delay(r, kMaxDelay + 1);
       }},
      {"feed-forward without an actuator", [&](Settings& s) { s.actuator_feedforward[r] = 1.0; },
       [&](Simulation& s) { s.set_actuator_feedforward(r, 1.0); }},
      {"infinite feed-forward",
       [&](Settings& s) { s.actuators[k(r)] = pd, s.actuator_feedforward[r] = test::kInf; },
       [&](Simulation& s) {
         s.set_actuator(r, pd);
         s.set_actuator_feedforward(r, test::kInf);
       }},
      {"link cfm_scale 2", [&](Settings& s) { s.link_parameters[1].cfm_scale = 2.0; },
       [&](Simulation& s) {
         LinkParameters l;
         l.cfm_scale = 2.0;
         s.set_link_parameters(1, l);
       }},
      {"a joint mimicking itself", [&](Settings& s) { s.mimic_joints = {{r, r, 2.0, 0.0}}; },
       [&](Simulation& s) { s.set_mimic_joints({{r, r, 2.0, 0.0}}); }},
      {"dt 0", [&](Settings& s) { s.options.dt = 0.0; },
       [&](Simulation& s) {
         SimulationOptions o;
         o.dt = 0.0;
         s.set_options(o);
       }},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    Simulation sim(model);
    Settings settings = sim.settings();
    c.change(settings);
    const std::string expected = message_of([&] { c.setter(sim); });
    EXPECT_NE(expected, "(no error)");
    EXPECT_EQ(message_of([&] { settings.validate(*model); }), expected);
    // set_settings refuses the same way and changes nothing.
    Simulation fresh(model);
    EXPECT_EQ(message_of([&] { fresh.set_settings(settings); }), expected);
    EXPECT_TRUE(same_bits(fresh.settings().lower_limit, model->lower_limit));
    EXPECT_EQ(fresh.drive(r).type, DriveType::none);
  }
}

TEST(Settings, WrongSizesAndAnotherCompatAreRefused) {
  const auto model = tree();
  Simulation sim(model);
  Settings s = sim.settings();
  s.drives.pop_back();
  EXPECT_EQ(message_of([&] { s.validate(*model); }),
            "settings: drives has " + std::to_string(model->nv - 1) +
                " entries, the model has nv = " + std::to_string(model->nv));
  Settings physx = sim.settings();
  physx.options.compat = Compat::physx;
  EXPECT_EQ(message_of([&] { sim.set_settings(physx); }),
            "simulation options: compat = physx differs from the simulation's none: compat is "
            "chosen at construction");
}

// Settings made by the setters, given whole to a fresh simulation: both step the same bits.
TEST(Settings, ASimulationGivenAnothersSettingsStepsTheSameBits) {
  const auto model = tree();
  const int r = first_dof(*model, JointType::revolute);
  const int r2 = second_revolute(*model);
  const int p = first_dof(*model, JointType::prismatic);
  const int b = first_dof(*model, JointType::spherical);
  for (const SolverType solver : {SolverType::pgs, SolverType::tgs}) {
    SCOPED_TRACE(to_string(solver));
    SimulationOptions options;
    options.solver = solver;
    options.dt = 1.0 / 240.0;
    Simulation a(model, options);
    const Drive drive{
        .type = DriveType::force, .stiffness = 200.0, .damping = 5.0, .target_position = 0.3};
    a.set_drive(r, drive);
    a.set_drive_delay(r, 2);
    a.set_drive(b + 1, drive);
    a.set_joint_limits(p, -0.05, 0.05);
    a.set_joint_friction(p, {0.5, 0.4, 0.1});
    a.set_max_joint_velocity(b, 3.0);
    const ExplicitActuator pd{.kind = ActuatorKind::dc_motor,
                              .stiffness = 80.0,
                              .damping = 2.0,
                              .saturation_effort = 30.0,
                              .velocity_limit = 10.0,
                              .delay = 1};
    a.set_actuator(r2, pd);
    a.set_actuator_feedforward(r2, 0.5);
    a.set_drive_target(r2, -0.2, 0.0);
    a.set_revolute_wrap(r, RevoluteWrap::wrapped);
    a.set_mimic_joints({{p, r2, 0.1, 0.0}});
    LinkParameters l;
    l.linear_damping = 0.1;
    a.set_link_parameters(2, l);
    Simulation c(model, options);
    c.set_settings(a.settings());
    std::mt19937 rng(7);
    const VecX q = test::random_configuration(*model, rng);
    const VecX qd = test::random_vector(model->nv, rng, 0.5);
    for (Simulation* s : {&a, &c}) {
      s->set_q(q);
      s->set_qd(qd);
      s->step(200);
    }
    EXPECT_TRUE(same_bits(a.q(), c.q()));
    EXPECT_TRUE(same_bits(a.qd(), c.qd()));
    EXPECT_TRUE(same_bits(a.actuator_force(), c.actuator_force()));
    EXPECT_EQ(c.drive_delay(r), 2);
    EXPECT_EQ(c.actuator(r2).kind, ActuatorKind::dc_motor);
    EXPECT_EQ(c.actuators().feedforward(r2), 0.5);
    EXPECT_EQ(c.mimic_joints().size(), 1u);
    EXPECT_EQ(c.link_parameters(2).linear_damping, 0.1);
    // And back: clearing through set_settings equals the default simulation.
    c.set_settings(Settings::defaults(*model, options));
    EXPECT_FALSE(c.has_actuator(r2));
    EXPECT_EQ(c.drive_delay(r), 0);
    EXPECT_TRUE(c.mimic_joints().empty());
  }
}

// A run with every kind of history, its state taken mid-run and given to a fresh simulation with
// the same settings: the two continue with the same bits. Bad states change nothing.
TEST(State, AStateGivenToAnotherSimulationContinuesTheSameBits) {
  const auto model = tree();
  const int r = first_dof(*model, JointType::revolute);
  const int r2 = second_revolute(*model);
  SimulationOptions options;
  options.dt = 1.0 / 240.0;
  Simulation a(model, options);
  a.set_drive(r, Drive{.type = DriveType::force, .stiffness = 300.0, .damping = 3.0});
  a.set_drive_delay(r, 3);
  a.set_actuator(
      r2, ExplicitActuator{
              .kind = ActuatorKind::ideal_pd, .stiffness = 60.0, .damping = 1.0, .delay = 2});
  std::mt19937 rng(11);
  a.set_q(test::random_configuration(*model, rng));
  for (int k = 0; k < 37; ++k) {
    a.set_drive_target(r, 0.01 * k, 0.0);
    a.set_drive_target(r2, -0.01 * k, 0.0);
    a.step();
  }
  const State mid = a.state();
  EXPECT_EQ(mid.step_count, 37);
  EXPECT_EQ(mid.drive_delay_history[static_cast<size_t>(r)].ring.size(), 4u);
  EXPECT_EQ(mid.actuator_history[static_cast<size_t>(r2)].ring.size(), 3u);
  Simulation b(model, options);
  b.set_settings(a.settings());
  b.set_state(mid);
  for (Simulation* s : {&a, &b}) {
    s->set_drive_target(r, -0.3, 0.0);
    s->set_drive_target(r2, 0.4, 0.0);
    s->step(40);
  }
  EXPECT_TRUE(same_bits(a.q(), b.q()));
  EXPECT_TRUE(same_bits(a.qd(), b.qd()));
  EXPECT_TRUE(same_bits(a.drive_force(), b.drive_force()));
  EXPECT_TRUE(same_bits(a.actuator_force(), b.actuator_force()));
  EXPECT_EQ(a.time(), b.time());

  const State before = b.state();
  const auto refused = [&](const std::function<void(State&)>& change) {
    State s = mid;
    change(s);
    const std::string e = message_of([&] { b.set_state(s); });
    EXPECT_TRUE(same_bits(b.q(), before.q));
    EXPECT_EQ(b.step_count(), before.step_count);
    EXPECT_EQ(b.drive_delays().pushes(r),
              before.drive_delay_history[static_cast<size_t>(r)].pushes);
    return e;
  };
  EXPECT_EQ(refused([](State& s) { s.time = 1.0, s.step_count = 0; }),
            "clock: time = 1 s after 0 steps: no run reaches it (at most 0 s, 2 * steps * 1000 s)");
  EXPECT_EQ(refused([](State& s) { s.qd[0] = test::kInf; }), "qd[0] = inf is not finite");
  EXPECT_NE(refused([](State& s) { s.q.segment<4>(3) *= 2.0; }).find(", expected 1"),
            std::string::npos);  // the floating base's quaternion
  EXPECT_EQ(refused([&](State& s) { s.actuator_history[static_cast<size_t>(r)].pushes = 1; }),
            "actuator history of dof " + std::to_string(r) + ": the dof has no actuator");
  EXPECT_NE(
      refused([&](State& s) { s.drive_delay_history[static_cast<size_t>(r)].ring.pop_back(); }),
      "(no error)");
  EXPECT_EQ(refused([](State& s) { s.drive_delay_history.pop_back(); }),
            "state: " + std::to_string(model->nv - 1) +
                " delay histories, expected one per dof (nv = " + std::to_string(model->nv) + ")");
}

// The workspace (src/sim/workspace.hpp) goes with its simulation: a copy made mid-run, delay
// histories in flight, steps the original's bits and leaves the original alone; so do a move and
// an assignment over a simulation of another model.
TEST(Workspace, ACopyMidRunStepsTheOriginalsBitsOnItsOwn) {
  const auto model = tree();
  const int r = first_dof(*model, JointType::revolute);
  const int r2 = second_revolute(*model);
  Simulation a(model);
  a.set_drive(r, {.type = DriveType::force, .stiffness = 200.0, .damping = 5.0,
                  .target_position = 0.3});
  a.set_drive_delay(r, 2);
  a.set_actuator(r2, {.kind = ActuatorKind::dc_motor, .stiffness = 80.0, .damping = 2.0,
                      .saturation_effort = 30.0, .velocity_limit = 10.0, .delay = 1});
  a.set_drive_target(r2, -0.2, 0.0);
  a.step(10);
  Simulation copy = a;
  const VecX q_before = a.q();
  copy.step(50);
  EXPECT_TRUE(same_bits(a.q(), q_before));
  const Simulation moved = std::move(copy);
  Simulation assigned(test::make_pendulum(1.0, 0.5));
  assigned = a;
  a.step(50);
  assigned.step(50);
  for (const Simulation* s : {&moved, static_cast<const Simulation*>(&assigned)}) {
    EXPECT_EQ(s->step_count(), 60);
    EXPECT_TRUE(same_bits(s->q(), a.q()));
    EXPECT_TRUE(same_bits(s->qd(), a.qd()));
    EXPECT_TRUE(same_bits(s->drive_force(), a.drive_force()));
    EXPECT_TRUE(same_bits(s->actuator_force(), a.actuator_force()));
  }
}

}  // namespace
}  // namespace featherdrive::settings_test
