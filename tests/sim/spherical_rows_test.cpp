// A spherical joint's rows in the step against closed forms: an isotropic rotor turning about one
// axis is a 1-dof implicit drive whose error is PhysX's 2 sin((target - angle) / 2); a speculative
// limit stops an axis exactly at its limit; and the setters' one-line errors for spherical axes.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "featherdrive/constraint/spherical_axes.hpp"
#include "featherdrive/model/model_builder.hpp"
#include "featherdrive/sim/simulation.hpp"
#include "support/compare.hpp"

namespace featherdrive {
namespace {

using test::kInf;

// A rotor on a spherical joint at its centre of mass: inertia I 1, no gravity.
std::shared_ptr<const Model> spherical_rotor(double inertia) {
  ModelBuilder b;
  b.set_gravity(Vec3::Zero());
  b.add_link(make_link("base", "", 1.0, Vec3::Zero(), Mat3::Identity(), fixed_joint("fix")));
  b.add_link(make_link("rotor", "base", 2.0, Vec3::Zero(), inertia * Mat3::Identity(),
                       spherical_joint("ball", Vec3(0, 0, 1), Vec3(0.3, -0.2, 0.5))));
  return std::make_shared<const Model>(b.build());
}

void rotor_turn(Simulation& sim, int axis, double angle) {
  const Quat Q(Eigen::AngleAxisd(angle, Vec3::Unit(axis)));
  VecX q = sim.q();
  q.segment<4>(0) << Q.w(), Q.x(), Q.y(), Q.z();
  sim.set_q(q);
}

double rotor_position(const Simulation& sim, int axis) {
  const VecX& q = sim.q();
  return spherical_joint_positions(Quat(q[0], q[1], q[2], q[3]))[axis];
}

TEST(SphericalRows, OneAxisDriveIsTheImplicitStepWithPhysxsError) {
  const double I = 0.1, kp = 50.0, kd = 2.0, h = 1.0 / 60.0;
  for (const SolverType solver : {SolverType::pgs, SolverType::tgs})
    for (int axis = 0; axis < 3; ++axis)
      for (const auto& [angle, target] : {std::pair{0.2, 1.5}, {-2.0, 2.5}}) {
        SimulationOptions o;
        o.solver = solver;
        o.position_iterations = solver == SolverType::tgs ? 1 : 4;
        Simulation sim(spherical_rotor(I), o);
        rotor_turn(sim, axis, angle);
        const char* names[] = {"ball:twist", "ball:swing1", "ball:swing2"};
        sim.set_drive(names[axis], Drive{DriveType::force, kp, kd, kInf, target, 0.0});
        sim.step();
        // I (v1 - 0) = h (kp (e - h v1) - kd v1), e = 2 sin((target - angle) / 2), short way.
        const double e = 2.0 * std::sin(std::remainder(target - angle, 2 * std::numbers::pi) / 2);
        const double v1 = h * kp * e / (I + h * h * kp + h * kd);
        EXPECT_NEAR(sim.qd()[axis], v1, 1e-12) << to_string(solver) << " axis " << axis;
        EXPECT_NEAR(sim.qd().norm(), std::abs(v1), 1e-12);
        EXPECT_NEAR(rotor_position(sim, axis), angle + h * v1, 1e-12);
        EXPECT_NEAR(sim.drive_force()[axis], I * v1 / h, 1e-9);
      }
}

TEST(SphericalRows, ASpeculativeLimitStopsTheAxisAtItsLimit) {
  const double h = 1.0 / 60.0, upper = 0.375, start = 0.3;
  Simulation sim(spherical_rotor(0.1));
  rotor_turn(sim, 1, start);
  sim.set_joint_limits("ball:swing1", -0.5, upper);
  VecX qd = VecX::Zero(3);
  qd[1] = 12.0;  // would pass the limit within the step
  sim.set_qd(qd);
  sim.step();
  EXPECT_NEAR(sim.qd()[1], (upper - start) / h, 1e-11);
  EXPECT_NEAR(rotor_position(sim, 1), upper, 1e-13);
  EXPECT_LT(sim.limit_force()[1], 0.0);  // the upper limit pushes back
}

TEST(SphericalRows, SettersNameTheAxisAndTheValue) {
  Simulation sim(spherical_rotor(0.1));
  auto error_of = [](auto f) -> std::string {
    try {
      f();
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "(no error)";
  };
  EXPECT_EQ(error_of([&] { sim.set_joint_limits("ball:swing2", -0.5, 3.5); }),
            "limits on joint 'ball:swing2': upper = 3.5 is outside [-pi, pi], where a spherical "
            "axis's position lies");
  EXPECT_EQ(error_of([&] { sim.set_drive("ball", Drive{DriveType::force, 1, 1}); }),
            "joint 'ball' is spherical: name one of its axes, 'ball:twist', 'ball:swing1' or "
            "'ball:swing2'");
  EXPECT_EQ(error_of([&] { sim.set_drive("ball:tilt", Drive{DriveType::force, 1, 1}); }),
            "no joint named 'ball:tilt' in the model");
  EXPECT_EQ(error_of([&] {
              ExplicitActuator pd;
              pd.kind = ActuatorKind::ideal_pd;
              pd.stiffness = 1.0;
              sim.set_actuator("ball:twist", pd);
            }),
            "joint 'ball' is spherical: explicit actuators act on revolute and prismatic joints "
            "only");
  // Limits within [-pi, pi] and open sides are fine.
  sim.set_joint_limits("ball:twist", -std::numbers::pi, kInf);
  EXPECT_EQ(sim.lower_limit(0), -std::numbers::pi);
}

}  // namespace
}  // namespace featherdrive
