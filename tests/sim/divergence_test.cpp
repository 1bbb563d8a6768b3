// A step that would produce a non-finite velocity, force or position throws DivergenceError naming
// the step, the joint and the quantity, and leaves q, qd, time, step count and the reported forces
// exactly (bit for bit) as they were before the step. Bad arguments to the public entry points
// are refused with std::invalid_argument naming the field and value.
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstring>
#include <limits>

#include "featherdrive/core/format.hpp"
#include "featherdrive/sim/batch.hpp"
#include "featherdrive/sim/simulation.hpp"
#include "support/models.hpp"
#include "support/compare.hpp"

namespace featherdrive {
namespace {

using test::kInf;
const double kNaN = std::numeric_limits<double>::quiet_NaN();

using test::same_bits;

// Everything a failed step must leave alone.
struct Snapshot {
  VecX q, qd, drive, limit, friction, velocity_limit;
  double time;
  long steps;
  explicit Snapshot(const Simulation& s)
      : q(s.q()), qd(s.qd()), drive(s.drive_force()), limit(s.limit_force()),
        friction(s.friction_force()), velocity_limit(s.velocity_limit_force()), time(s.time()),
        steps(s.step_count()) {}
  void expect_equal(const Simulation& s) const {
    EXPECT_TRUE(same_bits(q, s.q()));
    EXPECT_TRUE(same_bits(qd, s.qd()));
    EXPECT_TRUE(same_bits(drive, s.drive_force()));
    EXPECT_TRUE(same_bits(limit, s.limit_force()));
    EXPECT_TRUE(same_bits(friction, s.friction_force()));
    EXPECT_TRUE(same_bits(velocity_limit, s.velocity_limit_force()));
    EXPECT_EQ(std::bit_cast<std::uint64_t>(time), std::bit_cast<std::uint64_t>(s.time()));
    EXPECT_EQ(steps, s.step_count());
  }
};

std::string divergence_of(Simulation& sim) {
  try {
    sim.step();
  } catch (const DivergenceError& e) {
    return e.what();
  }
  return "(no error)";
}

// A 1 kg slider along x without gravity, driven towards 0.2 m; three ordinary steps first so that
// the state and the reported forces are not the initial ones.
Simulation driven_slider(SolverType solver) {
  SimulationOptions o;
  o.solver = solver;
  Simulation sim(test::make_slider(1.0, Vec3::UnitX(), Vec3::Zero()), o);
  sim.set_drive("slide", Drive{DriveType::force, 100.0, 10.0, kInf, 0.2, 0.0});
  sim.step(3);
  return sim;
}

class Divergence : public ::testing::TestWithParam<SolverType> {};

// 1e308 N on a 1 kg slider for dt = 10 s: the free velocity 1e309 m/s overflows.
TEST_P(Divergence, NonFiniteVelocityFromAnAbsurdForce) {
  Simulation sim = driven_slider(GetParam());
  const Snapshot before(sim);
  sim.set_applied_force(VecX::Constant(1, 1e308));
  SimulationOptions o = sim.options();
  o.dt = 10.0;
  sim.set_options(o);
  // The free velocity is +inf; the drive row then turns it into inf - inf = NaN.
  const std::string e = divergence_of(sim);
  const std::string head = "simulation diverged at step 4 (t = 0.05 s): joint 'slide' velocity qd = ";
  const std::string tail = "; the state is left as it was before this step (lower dt or the gains)";
  ASSERT_GT(e.size(), head.size() + tail.size()) << e;
  EXPECT_EQ(e.substr(0, head.size()), head) << e;
  EXPECT_EQ(e.substr(e.size() - tail.size()), tail) << e;
  const std::string value = e.substr(head.size(), e.size() - head.size() - tail.size());
  EXPECT_TRUE(value == "inf" || value == "nan") << value;  // a NaN is "nan", whatever its sign
  before.expect_equal(sim);
}

// A drive whose impulse stays finite over a tiny step of 1e-300 s: the reported force,
// impulse / dt, overflows while q and qd stay finite.
TEST_P(Divergence, NonFiniteDriveForceFromATinyTimeStep) {
  Simulation sim = driven_slider(GetParam());
  const Snapshot before(sim);
  SimulationOptions o = sim.options();
  o.dt = 1e-300;
  sim.set_options(o);
  sim.set_drive("slide", Drive{DriveType::force, 1e308, 0.0, kInf, 1e6, 0.0});
  const std::string e = divergence_of(sim);
  EXPECT_NE(e.find("simulation diverged at step 4"), std::string::npos) << e;
  EXPECT_NE(e.find("joint 'slide' drive force = inf"), std::string::npos) << e;
  before.expect_equal(sim);
}

// Overflowing gains: stiffness 1e308 with dt = 1000 makes h (h kp + kd) infinite.
TEST_P(Divergence, OverflowingGainsAreCaught) {
  Simulation sim = driven_slider(GetParam());
  const Snapshot before(sim);
  SimulationOptions o = sim.options();
  o.dt = kMaxDt;
  sim.set_options(o);
  sim.set_drive("slide", Drive{DriveType::force, 1e308, 1e308, kInf, 1e6, 1e6});
  const std::string e = divergence_of(sim);
  EXPECT_NE(e.find("simulation diverged at step 4"), std::string::npos) << e;
  EXPECT_NE(e.find("joint 'slide'"), std::string::npos) << e;
  before.expect_equal(sim);
}

// The time step is a normal number up to 1000 s, so the clock cannot overflow (dt = 1e308 twice
// did, a fuzzing find): such options are refused before any step, naming dt and its value.
TEST_P(Divergence, TimeStepsOutsideTheirRangeAreRefusedUpFront) {
  SimulationOptions o;
  o.solver = GetParam();
  const auto error = [&](double dt) {
    o.dt = dt;
    try {
      validate_options(o);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("(no error)");
  };
  const std::string range = " must be a normal number in [2.2250738585072014e-308, 1000] s";
  for (double dt : {1e308, 1000.0000000000001, 1e-310, 4.9e-324, std::nextafter(kMinDt, 0.0)})
    EXPECT_EQ(error(dt), "simulation options: dt = " + format_double(dt) + range) << dt;
  for (double dt : {0.0, -1.0, kInf, std::nan("")})
    EXPECT_EQ(error(dt),
              "simulation options: dt = " + format_double(dt) + " must be finite and > 0")
        << dt;
  for (double dt : {kMinDt, 1e-300, kMaxDt}) EXPECT_EQ(error(dt), "(no error)") << dt;
  o.dt = 1e308;
  EXPECT_THROW(Simulation(test::make_slider(1.0, Vec3::UnitX(), Vec3::Zero()), o),
               std::invalid_argument);
  // The iteration counts have their range too.
  o.dt = 0.01;
  o.position_iterations = kMaxIterations + 1;
  EXPECT_THROW(validate_options(o), std::invalid_argument);
  o.position_iterations = kMaxIterations;
  o.velocity_iterations = kMaxIterations + 1;
  EXPECT_THROW(validate_options(o), std::invalid_argument);
}

// After a refused step, sane inputs continue exactly as if the bad step had never been tried.
TEST_P(Divergence, TheSimulationContinuesAsIfTheStepHadNotBeenTried) {
  Simulation reference = driven_slider(GetParam());
  Simulation sim = driven_slider(GetParam());
  sim.set_applied_force(VecX::Constant(1, 1e308));
  SimulationOptions o = sim.options();
  const SimulationOptions good = o;
  o.dt = 10.0;
  sim.set_options(o);
  EXPECT_THROW(sim.step(), DivergenceError);
  sim.set_applied_force(VecX::Zero(1));
  sim.set_options(good);
  sim.step(5);
  reference.step(5);
  Snapshot(reference).expect_equal(sim);
}

// The steps of step(count) before the diverging one stand; the count stops at the failure.
TEST_P(Divergence, StepCountStopsAtTheFailingStep) {
  SimulationOptions o;
  o.solver = GetParam();
  Simulation sim(test::make_slider(1.0, Vec3::UnitX(), Vec3::Zero()), o);
  // q after k steps is about 1e307 (1/60)^2 k^2 / 2: it overflows near k = 360.
  sim.set_applied_force(VecX::Constant(1, 1e307));
  long last_good = 0;
  try {
    for (int k = 0; k < 1000; ++k) {
      sim.step();
      last_good = sim.step_count();
    }
    ADD_FAILURE() << "no divergence";
  } catch (const DivergenceError& e) {
    EXPECT_EQ(sim.step_count(), last_good);
    EXPECT_TRUE(sim.q().allFinite());
    EXPECT_TRUE(sim.qd().allFinite());
    EXPECT_NE(std::string(e.what()).find("at step " + std::to_string(last_good + 1)),
              std::string::npos) << e.what();
  }
}

INSTANTIATE_TEST_SUITE_P(Solvers, Divergence, ::testing::Values(SolverType::pgs, SolverType::tgs),
                         [](const auto& info) { return std::string(to_string(info.param)); });

// --- bad arguments -------------------------------------------------------------------------------

constexpr auto invalid_of = test::invalid_argument_message;

TEST(BadArguments, OptionsAreValidated) {
  auto model = test::make_slider(1.0, Vec3::UnitX(), Vec3::Zero());
  for (double dt : {0.0, -1.0, kNaN, kInf, -kInf}) {
    SimulationOptions o;
    o.dt = dt;
    EXPECT_NE(invalid_of([&] { Simulation s(model, o); }).find("simulation options: dt = "),
              std::string::npos) << dt;
    Simulation s(model);
    EXPECT_NE(invalid_of([&] { s.set_options(o); }).find("must be finite and > 0"), std::string::npos);
    EXPECT_EQ(s.options().dt, 1.0 / 60.0);
  }
  SimulationOptions o;
  o.position_iterations = 0;
  EXPECT_EQ(invalid_of([&] { Simulation s(model, o); }),
            "simulation options: position_iterations = 0 must be >= 1");
  o.position_iterations = 1;
  o.velocity_iterations = -1;
  EXPECT_EQ(invalid_of([&] { Simulation s(model, o); }),
            "simulation options: velocity_iterations = -1 must be >= 0");
  EXPECT_EQ(invalid_of([&] { Simulation s(nullptr); }), "Simulation: model is null");
  Simulation s(model);
  EXPECT_EQ(invalid_of([&] { s.step(-2); }), "step count = -2 must be >= 0");
}

TEST(BadArguments, VectorsAreCheckedForSizeAndFiniteness) {
  Simulation s(test::make_random_tree(4, 4, /*floating=*/true));
  const int nq = s.model().nq, nv = s.model().nv;
  const VecX q0 = s.q();
  EXPECT_EQ(invalid_of([&] { s.set_q(VecX::Zero(nq + 1)); }),
            "q: expected " + std::to_string(nq) + " values, got " + std::to_string(nq + 1));
  EXPECT_NE(invalid_of([&] { s.set_qd(VecX::Zero(nv - 1)); }).find("qd: expected"), std::string::npos);
  EXPECT_NE(invalid_of([&] { s.set_applied_force(VecX::Zero(0)); }).find("applied_force: expected"),
            std::string::npos);
  VecX bad = VecX::Zero(nv);
  bad[2] = kNaN;
  EXPECT_EQ(invalid_of([&] { s.set_qd(bad); }), "qd[2] = nan is not finite");
  bad[2] = kInf;
  EXPECT_EQ(invalid_of([&] { s.set_applied_force(bad); }), "applied_force[2] = inf is not finite");
  VecX q = q0;
  q.segment<4>(3).setZero();  // the floating root's quaternion
  EXPECT_NE(invalid_of([&] { s.set_q(q); }).find("has norm 0: it must not be zero"), std::string::npos);
  EXPECT_TRUE(same_bits(s.q(), q0));
}

TEST(BadArguments, JointsDofsAndSettings) {
  Simulation s(test::make_slider(1.0, Vec3::UnitX(), Vec3::Zero()));
  EXPECT_EQ(invalid_of([&] { s.set_drive("nope", Drive{}); }), "no joint named 'nope' in the model");
  EXPECT_EQ(invalid_of([&] { s.set_drive(1, Drive{}); }), "dof index 1 is out of range [0, 1)");
  EXPECT_EQ(invalid_of([&] { s.set_drive(-1, Drive{}); }), "dof index -1 is out of range [0, 1)");
  EXPECT_EQ(invalid_of([&] { s.set_drive("world_joint", Drive{DriveType::force, 1, 1}); }),
            "joint 'world_joint' is fixed: this setting acts on revolute, prismatic and "
            "spherical joints only");
  EXPECT_EQ(invalid_of([&] { s.set_drive("slide", Drive{DriveType::force, -5.0, 1.0}); }),
            "drive on joint 'slide': stiffness = -5 must be finite and >= 0");
  EXPECT_EQ(invalid_of([&] { s.set_drive("slide", Drive{DriveType::force, 1.0, kNaN}); }),
            "drive on joint 'slide': damping = nan must be finite and >= 0");
  EXPECT_EQ(invalid_of([&] { s.set_drive("slide", Drive{DriveType::force, 1.0, 1.0, 0.0}); }),
            "drive on joint 'slide': max_force = 0 must be > 0");
  // A target on a dof without a drive would do nothing: refused, naming the joint.
  EXPECT_EQ(invalid_of([&] { s.set_drive_target("slide", 0.5, 0.0); }),
            "joint 'slide' (dof 0) has no drive (type none), so a target would do nothing: give "
            "it one first (set_drive, set_drive_gains for every joint, or set_actuator)");
  EXPECT_EQ(s.drive(0).target_position, 0.0);
  s.set_drive("slide", Drive{DriveType::force, 1.0, 1.0});
  EXPECT_EQ(invalid_of([&] { s.set_drive_target("slide", kNaN, 0.0); }),
            "drive on joint 'slide': target_position = nan must be finite");
  EXPECT_EQ(invalid_of([&] { s.set_drive_target(0, 0.0, kInf); }),
            "drive on joint 'slide': target_velocity = inf must be finite");
  EXPECT_EQ(invalid_of([&] { s.set_joint_limits("slide", kNaN, 1.0); }),
            "limits on joint 'slide': lower = nan is not a number");
  EXPECT_EQ(invalid_of([&] { s.set_joint_limits("slide", 2.0, 1.0); }),
            "limits on joint 'slide': lower = 2 is above upper = 1");
  EXPECT_EQ(invalid_of([&] { s.set_max_joint_velocity("slide", 0.0); }),
            "velocity limit on joint 'slide': max_velocity = 0 must be > 0");
  EXPECT_EQ(invalid_of([&] { s.set_joint_friction("slide", {-1.0, 0.0, 0.0}); }),
            "friction on joint 'slide': static_effort = -1 must be finite and >= 0");
  EXPECT_EQ(invalid_of([&] { s.set_actuator_envelope("slide", {1.0, kNaN, 0.0, 0.0}); }),
            "actuator envelope on joint 'slide': max_actuator_velocity = nan must be > 0");
  // Nothing changed.
  EXPECT_EQ(s.drive(0).type, DriveType::force);
  EXPECT_EQ(s.drive(0).target_position, 0.0);
  EXPECT_EQ(s.lower_limit(0), -kInf);
  EXPECT_EQ(s.max_joint_velocity(0), kInf);
}

// Whole-vector target setters refuse a nonzero target on a dof without a drive (a floating root's,
// or a joint whose drive type is none) and accept zeros there; a refused vector changes nothing.
TEST(BadArguments, TargetVectorsNeedDrivesWhereTheyAreNonzero) {
  const auto model = test::make_random_tree(3, 5, /*floating=*/true, /*spherical=*/false);
  const int nv = model->nv;
  Simulation sim(model);
  VecX kp = VecX::Zero(nv);
  kp.tail(nv - 7).setConstant(10.0);
  set_drive_gains(sim, kp, VecX::Zero(nv));
  sim.set_drive(6, Drive{});  // dof 6 (the first joint after the root): no drive
  ASSERT_EQ(sim.drive(6).type, DriveType::none);
  VecX targets = VecX::Zero(nv);
  targets.tail(nv - 7).setConstant(0.25);
  set_drive_targets(sim, targets, VecX::Zero(nv));  // zeros on the root and on dof 6: accepted
  EXPECT_EQ(sim.drive(nv - 1).target_position, 0.25);
  targets[6] = 0.5;
  targets[nv - 1] = 0.75;
  EXPECT_EQ(invalid_of([&] { set_drive_targets(sim, targets, VecX::Zero(nv)); }),
            "set_drive_targets: joint '" + model->dof_names[6] +
                "' (dof 6) has no drive (type none), so a target would do nothing: give it one "
                "first (set_drive, set_drive_gains for every joint, or set_actuator); this vector "
                "sets its target to 0.5, velocity 0");
  EXPECT_EQ(sim.drive(nv - 1).target_position, 0.25);  // nothing changed
  VecX velocities = VecX::Zero(nv);
  velocities[1] = -1.0;
  EXPECT_EQ(invalid_of([&] { set_drive_targets(sim, VecX::Zero(nv), velocities); }),
            "set_drive_targets: joint '" + model->dof_names[1] +
                "' (dof 1) is floating: it takes no drive, so no target; this vector sets its "
                "target to 0, velocity -1");
  Batch batch(sim, 2);
  RowMatrix rows = RowMatrix::Zero(2, nv);
  rows(1, 6) = 0.5;
  EXPECT_THROW(batch.set_drive_targets(rows, RowMatrix::Zero(2, nv)), std::invalid_argument);
  EXPECT_EQ(batch.sim(1).drive(nv - 1).target_position, 0.25);
  EXPECT_NE(invalid_of([&] { sim.set_drive_target(6, 0.0, 0.0); }).find("(dof 6) has no drive"),
            std::string::npos);  // one dof: even a zero target is refused
}

TEST(BadArguments, ModelBuilderNamesTheField) {
  auto error = [](LinkSpec link) {
    ModelBuilder b;
    b.add_link(make_link("base", "", 1.0, Vec3::Zero(), Mat3::Identity(), fixed_joint("root")));
    b.add_link(std::move(link));
    try {
      b.build();
    } catch (const ModelError& e) {
      return std::string(e.what());
    }
    return std::string("(no error)");
  };
  const Mat3 I = Mat3::Identity() * 0.01;
  EXPECT_NE(error(make_link("a", "base", kNaN, Vec3::Zero(), I, revolute_joint("j", Vec3::UnitZ())))
                .find("mass = nan"), std::string::npos);
  EXPECT_NE(error(make_link("a", "base", -1.0, Vec3::Zero(), I, revolute_joint("j", Vec3::UnitZ())))
                .find("mass = -1"), std::string::npos);
  EXPECT_NE(error(make_link("a", "base", 1.0, Vec3::Zero(), I, revolute_joint("j", Vec3::Zero())))
                .find("axis = [0, 0, 0] is zero"), std::string::npos);
  EXPECT_NE(error(make_link("a", "base", 1.0, Vec3(kInf, 0, 0), I, revolute_joint("j", Vec3::UnitZ())))
                .find("is not finite"), std::string::npos);
  Mat3 bad = I;
  bad(0, 0) = -1.0;
  EXPECT_NE(error(make_link("a", "base", 1.0, Vec3::Zero(), bad, revolute_joint("j", Vec3::UnitZ())))
                .find("inertia"), std::string::npos);
  JointSpec j = revolute_joint("j", Vec3::UnitZ());
  j.lower_limit = kNaN;
  EXPECT_NE(error(make_link("a", "base", 1.0, Vec3::Zero(), I, j)).find("lower_limit is NaN"),
            std::string::npos);
  j = revolute_joint("j", Vec3::UnitZ());
  j.armature = {1.0, 2.0};
  EXPECT_NE(error(make_link("a", "base", 1.0, Vec3::Zero(), I, j)).find("armature has 2 values"),
            std::string::npos);
  EXPECT_NE(error(make_link("a", "nobody", 1.0, Vec3::Zero(), I, revolute_joint("j", Vec3::UnitZ())))
                .find("parent = 'nobody' is not a link of the model"), std::string::npos);
}

}  // namespace
}  // namespace featherdrive
