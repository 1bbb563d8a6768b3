// Ground contacts in Batch's SIMD lanes on the examples' legged robot, loaded through io: OpenAI
// Gym's Ant (examples/ant.xml) standing (TGS) and in the walking scene's set-up (PGS) against
// each environment stepped alone as a Simulation, bounded by the scalar step's own sensitivity
// to a last-bit change of its start (docs/simd_batch.md, "Contacts").
#include <gtest/gtest.h>

#include <string>

#include "featherdrive/io/scene.hpp"
#include "featherdrive/sim/batch.hpp"
#include "support/lanes.hpp"
#include "support/source_tree.hpp"

namespace featherdrive {
namespace {

// Environments of their own: on the ground as the scene starts, dropped from 1 to 10 cm, turned
// about z, one high above the ground for the whole run. (Dropped from 30 cm under TGS, the Ant
// lands where a friction decision rests on the last bits: the lanes parted from the scalar run by
// 2.9e-2 where four last-bit changes of its start parted it by 1.6e-3, a sample of the same
// chaos; docs/simd_batch.md, "Contacts".)
void ant_starts(Batch& batch) {
  const double lift[] = {0.0, 0.05, 0.1, 0.01, 1000.0, 0.02};
  for (int e = 0; e < batch.size(); ++e) {
    VecX q = batch.sim(e).q();
    q[2] += lift[e];
    q[3] = 1.0, q[4] = 0.0, q[5] = 0.0, q[6] = 0.05 * e;  // set_q normalises
    batch.sim(e).set_q(q);
  }
}

TEST(LaneContactIo, AntOnTheGroundAsSimulation) {
  for (const char* file : {"ant_standing.yaml", "ant_walk.yaml"}) {
    const Simulation ant = make_simulation(load_scene(test::kExamples + file));
    ASSERT_TRUE(ant.ground().enabled) << file;
    Batch lanes(ant, 6);
    ant_starts(lanes);
    const std::string what = std::string("Ant on the ground (") + file + ", " +
                             to_string(ant.options().solver) + ")";
    const test::LaneFigures f = test::batch_against_alone(lanes, 1000, 10, what);
    EXPECT_LE(f.ratio, test::kSensitivityFactor) << what;
    EXPECT_FALSE(lanes.contacts(0).empty()) << what;
    EXPECT_TRUE(lanes.contacts(4).empty()) << what;
  }
}

// The features compose in the lanes: the standing Ant's hinges driven by implicit DC motors (their
// rows in the drives' place, the speed-dependent clip solved in the sweep) while its feet are on
// the ground, against each environment alone, bounded as above.
TEST(LaneContactIo, AntOnTheGroundWithImplicitActuators) {
  Simulation ant = make_simulation(load_scene(test::kExamples + std::string("ant_standing.yaml")));
  for (int d = 6; d < ant.model().nv; ++d) {
    const Drive drive = ant.drive(d);
    ExplicitActuator motor;
    motor.kind = ActuatorKind::dc_motor;
    motor.stiffness = drive.stiffness;
    motor.damping = drive.damping;
    motor.effort_limit = 0.1;
    motor.saturation_effort = 0.12;
    motor.velocity_limit = 1.0;
    motor.integration = ActuatorIntegration::implicit_law;
    ant.set_drive(d, Drive{});
    ant.set_actuator(d, motor);
    ant.set_drive_target(d, drive.target_position, 0.0);
  }
  Batch lanes(ant, 6);
  ant_starts(lanes);
  const test::LaneFigures f =
      test::batch_against_alone(lanes, 1000, 10, "Ant on the ground, implicit DC motors");
  EXPECT_LE(f.ratio, test::kSensitivityFactor);
  EXPECT_FALSE(lanes.contacts(0).empty());
  // The motors' rows replaced the drives' and their clip binds (the drives alone push up to
  // 0.13 Nm here).
  for (int e = 0; e < lanes.size(); ++e) {
    EXPECT_EQ(lanes.sim(e).drive_force().cwiseAbs().maxCoeff(), 0.0) << e;
    EXPECT_LE(lanes.sim(e).actuator_force().cwiseAbs().maxCoeff(), 0.1 * (1 + 1e-12)) << e;
  }
  EXPECT_GE(lanes.sim(0).actuator_force().cwiseAbs().maxCoeff(), 0.1 * (1 - 1e-12));
}

}  // namespace
}  // namespace featherdrive
