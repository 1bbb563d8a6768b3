// Ground contact against MuJoCo 2.2.2 itself: OpenAI Gym's Ant (examples/ant.xml) standing under PD
// drives, featherdrive's rigid contact rows beside MuJoCo's soft contacts of the exported MJCF
// (issue 34; docs/mujoco_bridge.md, "Ground contact").
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <tuple>

#include "featherdrive/io/mjcf_export.hpp"
#include "featherdrive/io/scene.hpp"
#include "featherdrive/model/model_builder.hpp"

namespace featherdrive {
namespace {

struct Standing {
  double z_fd = 0.0, z_mj = 0.0;  // base heights after 3 s
  VecX f_fd, f_mj;                // drive forces, averaged over the last second
};

// The Ant of examples/ant_standing.yaml with every surface's friction mu, run 3 s in both engines.
Standing stand(double mu, SolverType solver) {
  Scene scene = load_scene(std::string(FEATHERDRIVE_SOURCE_DIR) + "/examples/ant_standing.yaml");
  Model model = *scene.robot.model;
  for (CollisionShape& s : model.shapes)
    s.material.static_friction = s.material.dynamic_friction = mu;
  scene.robot.model = std::make_shared<const Model>(model);
  scene.ground.material.static_friction = scene.ground.material.dynamic_friction = mu;
  scene.options.solver = solver;
  Simulation sim = make_simulation(scene);
  MujocoRun mj(export_mjcf(sim));
  mj.set_state(sim.q(), sim.qd());
  const int steps = 300, average = 100;
  Standing out;
  out.f_fd = out.f_mj = VecX::Zero(model.nv);
  for (int k = 0; k < steps; ++k) {
    mj.step(sim);
    sim.step();
    if (k >= steps - average) {
      out.f_fd += VecX(sim.drive_force()) / average;
      out.f_mj += mj.drive_force() / average;
    }
  }
  EXPECT_FALSE(mj.diverged());
  out.z_fd = sim.q()[2];
  out.z_mj = mj.q()[2];
  return out;
}

// Frictionless feet: the legs' drives carry the weight in both engines, and the rest poses agree
// but for MuJoCo's soft contacts sinking ~0.3 mm (measured: heights 6.2e-4 / 5.5e-4 relative, joint
// forces 0.8 % / 0.3 % of the largest, PGS / TGS).
TEST(MujocoContact, FrictionlessAntRestsAtMujocosHeightWithItsJointForces) {
  for (const SolverType solver : {SolverType::pgs, SolverType::tgs}) {
    SCOPED_TRACE(to_string(solver));
    const Standing s = stand(0.0, solver);
    EXPECT_LT(std::abs(s.z_fd / s.z_mj - 1.0), 2e-2) << s.z_fd << " vs " << s.z_mj;
    EXPECT_GT(s.z_fd, s.z_mj);  // MuJoCo's contacts let the feet sink
    const double scale = s.f_mj.cwiseAbs().maxCoeff();
    EXPECT_GT(scale, 0.5);  // the ankles hold about 0.59 N m each
    EXPECT_LT((s.f_fd - s.f_mj).cwiseAbs().maxCoeff() / scale, 2e-2)
        << s.f_fd.transpose() << "\n" << s.f_mj.transpose();
  }
}

// The file's friction (1): the four legs and the ground make a rigid arch that static friction
// locks (the feet need |f_t| / f_n = 0.64 to carry the legs' moment), so featherdrive's drives,
// like PhysX's (`compare-physx examples/ant_standing.yaml`: 0.0077 N m at most under PGS), carry
// almost nothing once the arch has settled, while MuJoCo's soft friction lets the feet creep
// outwards until its drives carry the frictionless load. The heights still agree within 2 %
// (measured 7.0e-3 / 8.0e-3).
TEST(MujocoContact, AntOnItsFloorLocksItsLegsWhereMujocoCreeps) {
  for (const SolverType solver : {SolverType::pgs, SolverType::tgs}) {
    SCOPED_TRACE(to_string(solver));
    const Standing s = stand(1.0, solver);
    const Standing frictionless = stand(0.0, solver);
    EXPECT_LT(std::abs(s.z_fd / s.z_mj - 1.0), 2e-2) << s.z_fd << " vs " << s.z_mj;
    const double load = frictionless.f_fd.cwiseAbs().maxCoeff();
    EXPECT_LT(s.f_fd.cwiseAbs().maxCoeff(), 0.3 * load) << s.f_fd.transpose();
    EXPECT_GT(s.f_mj.cwiseAbs().maxCoeff(), 0.9 * load) << s.f_mj.transpose();
  }
}

// examples/ant_walk.yaml: a trot whose stance pushes each foot backward (the hips of the front
// legs rise while their ankles press down, the back legs' fall) walks along +x. featherdrive, both
// solvers, and MuJoCo on the exported MJCF with the translated gains: forward at least 0.4 m/s
// over 10 s, sideways less than a fifth of that, the torso upright and off the ground all along
// (measured, PGS / TGS: featherdrive 8.18 / 9.03 m, MuJoCo 5.45 / 8.22 m; docs/examples.md).
TEST(MujocoContact, AntTrotsForwardInBothEngines) {
  const Scene scene = load_scene(std::string(FEATHERDRIVE_SOURCE_DIR) + "/examples/ant_walk.yaml");
  for (const SolverType solver : {SolverType::pgs, SolverType::tgs}) {
    SCOPED_TRACE(to_string(solver));
    Scene s = scene;
    s.options.solver = solver;
    Simulation sim = make_simulation(s);
    apply_targets(s, sim, 0);
    MujocoRun mj(export_mjcf(sim));
    mj.set_state(sim.q(), sim.qd());
    double lowest = 1.0, lowest_mj = 1.0, tilt = 1.0, tilt_mj = 1.0;
    for (int k = 0; k < s.steps; ++k) {
      apply_targets(s, sim, k);
      mj.step(sim);
      sim.step();
      for (const auto& [q, low, up] : {std::tuple(VecX(sim.q()), &lowest, &tilt),
                                       std::tuple(mj.q(), &lowest_mj, &tilt_mj)}) {
        *low = std::min(*low, q[2]);
        // The torso's z axis along the world's: 1 - 2 (qx^2 + qy^2).
        *up = std::min(*up, 1.0 - 2.0 * (q[4] * q[4] + q[5] * q[5]));
      }
    }
    const double t = s.steps * s.options.dt;
    std::printf("%s: featherdrive x %.3f y %.3f, MuJoCo x %.3f y %.3f; lowest %.3f / %.3f, "
                "tilt cos %.3f / %.3f\n",
                to_string(solver), sim.q()[0], sim.q()[1], mj.q()[0], mj.q()[1], lowest, lowest_mj,
                tilt, tilt_mj);
    EXPECT_FALSE(mj.diverged());
    for (const VecX& q : {VecX(sim.q()), mj.q()}) {
      EXPECT_GT(q[0], 0.4 * t);
      EXPECT_LT(std::abs(q[1]), 0.2 * q[0]);
    }
    EXPECT_GT(std::min(lowest, lowest_mj), 0.4);
    EXPECT_GT(std::min(tilt, tilt_mj), 0.9);
  }
}

// Self-collision travels to MuJoCo: a ball (2 kg, r 0.05 m) on two sliders of a fixed base comes
// to rest on the base's own sphere (r 0.1 m), at centre distance r1 + r2 in featherdrive (closed
// form) and within MuJoCo's soft-contact sink of it in MuJoCo (measured 4.1e-5 m lower).
TEST(MujocoContact, SelfCollisionTravelsToMujoco) {
  ModelBuilder b;
  b.add_link(make_link("base", "", 0.0, Vec3::Zero(), Mat3::Zero(), fixed_joint("weld")));
  b.add_link(make_link("carriage", "base", 0.5, Vec3::Zero(), Mat3::Identity() * 0.01,
                       prismatic_joint("across", Vec3::UnitX())));
  b.add_link(make_link("ball", "carriage", 2.0, Vec3::Zero(), Mat3::Identity() * 0.002,
                       prismatic_joint("drop", Vec3::UnitZ())));
  for (const auto& [link, radius] : {std::pair{"base", 0.1}, std::pair{"ball", 0.05}}) {
    CollisionShape s;
    s.size = Vec3(radius, 0, 0);
    b.add_shape(link, s);
  }
  SimulationOptions o;
  o.dt = 0.01;
  o.position_iterations = 50;
  Simulation sim(std::make_shared<const Model>(b.build()), o);
  ContactOptions c;
  c.self_collision = true;
  sim.set_contact_options(c);
  VecX q = sim.q();
  q[1] = 0.16;
  sim.set_q(q);
  const MjcfExport mjcf = export_mjcf(sim);
  EXPECT_NE(mjcf.xml.find("conaffinity=\"1\""), std::string::npos);
  MujocoRun mj(mjcf);
  mj.set_state(sim.q(), sim.qd());
  for (int k = 0; k < 300; ++k) {
    mj.step(sim);
    sim.step();
  }
  std::printf("ball at %.9f (featherdrive) / %.9f (MuJoCo)\n", sim.q()[1], mj.q()[1]);
  EXPECT_NEAR(sim.q()[1], 0.15, 1e-9);
  EXPECT_NEAR(mj.q()[1], 0.15, 2e-3);
}

}  // namespace
}  // namespace featherdrive
