// featherdrive's ground contact against PhysX 5.6.1 itself (issue 34), free-running, on the cases
// of docs/math/contact.md, section 11 (tests/support/contact_models.hpp; physx_contact_test.cpp
// checks that the harness builds them as the bench does). featherdrive's side is read through the
// Simulation API only: q(), contacts(), link_contact_force(), drive forces.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "featherdrive/algorithm/floating_base.hpp"
#include "featherdrive/io/physx_runner.hpp"
#include "featherdrive/io/scene.hpp"
#include "support/contact_models.hpp"

namespace featherdrive {
namespace {

constexpr size_t kRootPz = 2, kRootPx = 0, kRootVx = 10;  // JointTrajectory::root's columns

JointTrajectory physx(const Simulation& sim, int steps) {
  return run_physx(PhysxInstall{FEATHERDRIVE_NODE, FEATHERDRIVE_PHYSX_DIR}, sim, steps);
}

// Sum of the normal impulses of sim's last step over dt: the ground's normal force.
double normal_force(const Simulation& sim) {
  double sum = 0.0;
  for (const ContactReport& c : sim.contacts()) sum += c.normal_impulse;
  return sum / sim.options().dt;
}

Vec3 base_position(const Simulation& sim) {
  return base_state(sim.model(), sim.q(), sim.qd()).position;
}

const SolverType kSolvers[] = {SolverType::pgs, SolverType::tgs};

// (a) The resting box carries its weight and sits where PhysX's does: its height within 5e-6 m of
// PhysX's at every step after the first 100 (PhysX's own z moves by 1.8e-6 m over them), the sum
// of its normal forces within PhysX's float32 spread of m g (2e-5 of it per step, PGS; the mean to
// 1e-6), and link_contact_force's normal part equal to that sum.
TEST(PhysxContactParity, RestingBox) {
  const double m = 1.0, mg = m * test::kContactGravity;
  for (const SolverType solver : kSolvers) {
    Simulation sim = test::ground_box_simulation(solver, 0.0);
    const JointTrajectory px = physx(sim, 1100);
    const int box = sim.model().link_index("box");
    double worst_z = 0.0, worst_step = 0.0, worst_link = 0.0, mean = 0.0, mean_px = 0.0;
    for (int k = 1; k <= 1100; ++k) {
      sim.step();
      if (k <= 100) continue;
      const size_t row = static_cast<size_t>(k);
      worst_z = std::max(worst_z, std::abs(base_position(sim).z() - px.root[row][kRootPz]));
      const double f = normal_force(sim);
      worst_step = std::max(worst_step, std::abs(f / mg - 1.0));
      mean += f / mg / 1000;
      mean_px += px.contact_force[row][0].z() / mg / 1000;
      worst_link = std::max(
          worst_link, std::abs(sim.link_contact_force()[static_cast<size_t>(box)].z() - f));
    }
    std::printf("a %s: |z - z_physx| <= %.2e m, |sum f_n / m g - 1| <= %.2e, mean %.10f (PhysX "
                "%.10f)\n",
                to_string(solver), worst_z, worst_step, mean, mean_px);
    EXPECT_LE(worst_z, 5e-6);
    EXPECT_LE(worst_step, 2e-5);
    EXPECT_NEAR(mean, 1.0, 1e-6);
    EXPECT_LE(worst_link, 1e-9 * mg);
  }
}

// (b) The box sliding at 2 m/s, mu 0.5: it stops within 1e-3 (relative) of PhysX's distance.
TEST(PhysxContactParity, SlidingBox) {
  for (const SolverType solver : kSolvers) {
    Simulation sim = test::ground_box_simulation(solver, 2.0);
    const JointTrajectory px = physx(sim, 80);
    size_t k = 1;
    while (k < px.rows() && px.root[k][kRootVx] > 1e-9) ++k;
    ASSERT_LT(k, px.rows());
    const double d_px = px.root[k][kRootPx] - px.root[0][kRootPx];
    const double x0 = base_position(sim).x();
    double d = 0.0;
    for (int step = 1; step <= 80; ++step) {
      sim.step();
      if (base_state(sim.model(), sim.q(), sim.qd()).linear_velocity.x() <= 1e-9) {
        d = base_position(sim).x() - x0;
        break;
      }
    }
    std::printf("b %s: %.9f m (PhysX %.9f m), relative %.2e\n", to_string(solver), d, d_px,
                (d - d_px) / d_px);
    EXPECT_NEAR(d, d_px, 1e-3 * d_px);
  }
}

// (d, e) The quadruped after 2 s: base height within 1e-3 of PhysX's (issue 34's figure; measured
// 3.6e-5 PGS, 6.0e-5 TGS standing, 2.8e-4 and 6.8e-4 dropped). Joint positions, drive forces and
// each foot's normal force (what the bindings report) do not meet 1e-3 yet: with the friction
// between the feet statically indeterminate, they depend on each row's history (docs/math/
// contact.md, sections 11 and 13). Measured, as shares of PhysX's largest |q|, |f| and of the
// weight: q 2.8e-3 / 6.6e-4 standing (PGS / TGS), 4.4e-3 / 4.0e-3 dropped; f 0.15 / 0.031,
// 0.072 / 0.046; feet 4.9e-3 / 3.2e-3, 8.8e-3 / 1.5e-2. Asserted at twice those.
void expect_quadruped_as_physx(double lift) {
  const char* legs[] = {"fl", "fr", "hl", "hr"};
  for (const SolverType solver : kSolvers) {
    Simulation sim = test::quadruped_simulation(solver, lift);
    const Model& model = sim.model();
    const JointTrajectory px = physx(sim, 200);
    for (int k = 0; k < 200; ++k) sim.step();
    const size_t end = 200;
    const double z = base_position(sim).z(), z_px = px.root[end][kRootPz];
    double scale_q = 0, scale_f = 0, dq = 0, df = 0;
    for (size_t j = 0; j < px.joints.size(); ++j) {
      const int dof = model.dof_index(px.joints[j]);
      scale_q = std::max(scale_q, std::abs(px.q[end][j]));
      scale_f = std::max(scale_f, std::abs(px.f[end][j]));
      dq = std::max(dq, std::abs(sim.q()[model.links[model.dof_link[dof]].q_index] - px.q[end][j]));
      df = std::max(df, std::abs(physx_joint_force(sim, dof) - px.f[end][j]));
    }
    double mass = 0.0;
    for (const Link& l : model.links) mass += l.mass;
    const double weight = mass * test::kContactGravity;
    double dfoot = 0.0;
    for (const char* leg : legs) {
      const std::string shin = std::string(leg) + "_shin";
      const auto it = std::find(px.contact_links.begin(), px.contact_links.end(), shin);
      ASSERT_NE(it, px.contact_links.end());
      const Vec3 f_px = px.contact_force[end][static_cast<size_t>(it - px.contact_links.begin())];
      const Vec3 f = sim.link_contact_force()[static_cast<size_t>(model.link_index(shin))];
      dfoot = std::max(dfoot, std::abs(f.z() - f_px.z()));  // the normal part: PhysX reports no friction
    }
    std::printf("%c %s: base z %.6f (PhysX %.6f), q %.2e, f %.2e, feet %.2e of the scale\n",
                lift > 0 ? 'e' : 'd', to_string(solver), z, z_px, dq / scale_q, df / scale_f,
                dfoot / weight);
    EXPECT_NEAR(z, z_px, 1e-3 * z_px);
    EXPECT_LE(dq, 1e-2 * scale_q);
    EXPECT_LE(df, 0.3 * scale_f);
    EXPECT_LE(dfoot, 3e-2 * weight);
  }
}

TEST(PhysxContactParity, QuadrupedStanding) { expect_quadruped_as_physx(0.0); }

TEST(PhysxContactParity, QuadrupedDroppedFrom20cm) { expect_quadruped_as_physx(0.2); }

// (f) OpenAI Gym's Ant standing on its floor (examples/ant_standing.yaml, friction 1, its feet on
// the ground at t = 0): the legs' arch locks by static friction, so the drives carry almost nothing
// (docs/mujoco_bridge.md, "Ground contact"). Steps 101-300, PGS against PhysX: base height 6.1e-5
// m, x and y 9.5e-5 m, joints 4.1e-4 rad, drive forces 0.021 N m (of a frictionless load of 0.59),
// foot normal forces 1.9e-2 of the weight (asserted 2e-4 m, 2e-4 m, 1e-3 rad, 0.03 N m, 3e-2).
// TGS at 4/1 creeps where PhysX stands (docs/math/contact.md, section 13: the base walks 6.8 mm in
// 3 s, PhysX's 0.1 mm; at 8 position iterations ours does not): only its height is held to
// PhysX's, within 3e-3 of it (measured 1.8e-3).
TEST(PhysxContactParity, AntStandsOnItsFloor) {
  for (const SolverType solver : kSolvers) {
    SCOPED_TRACE(to_string(solver));
    Scene scene = load_scene(std::string(FEATHERDRIVE_SOURCE_DIR) + "/examples/ant_standing.yaml");
    scene.options.solver = solver;
    Simulation sim = make_simulation(scene);
    const JointTrajectory px = physx(sim, 300);
    const Model& model = sim.model();
    double mass = 0.0;
    for (const Link& l : model.links) mass += l.mass;
    const double weight = mass * 9.81;
    double worst_z = 0.0, worst_xy = 0.0, worst_q = 0.0, worst_f = 0.0, worst_foot = 0.0;
    for (int k = 1; k <= 300; ++k) {
      sim.step();
      if (k <= 100) continue;
      const size_t row = static_cast<size_t>(k);
      const Vec3 p = base_position(sim);
      worst_z = std::max(worst_z, std::abs(p.z() - px.root[row][kRootPz]));
      worst_xy = std::max({worst_xy, std::abs(p.x() - px.root[row][kRootPx]),
                           std::abs(p.y() - px.root[row][kRootPx + 1])});
      for (size_t j = 0; j < px.joints.size(); ++j) {
        const int dof = model.dof_index(px.joints[j]);
        worst_q = std::max(worst_q, std::abs(sim.q()[model.links[model.dof_link[dof]].q_index] - px.q[row][j]));
        worst_f = std::max(worst_f, std::abs(physx_joint_force(sim, dof) - px.f[row][j]));
      }
      for (size_t l = 0; l < px.contact_links.size(); ++l) {
        const int link = model.link_index(px.contact_links[l]);
        worst_foot = std::max(worst_foot, std::abs(sim.link_contact_force()[static_cast<size_t>(link)].z() -
                                                   px.contact_force[row][l].z()) / weight);
      }
    }
    std::printf("f %s: |z - z_physx| <= %.2e m, |x, y| <= %.2e m, |q| <= %.2e rad, |f| <= %.2e N m, "
                "feet <= %.2e of the weight\n",
                to_string(solver), worst_z, worst_xy, worst_q, worst_f, worst_foot);
    if (solver == SolverType::pgs) {
      EXPECT_LT(worst_z, 2e-4);
      EXPECT_LT(worst_xy, 2e-4);
      EXPECT_LT(worst_q, 1e-3);
      EXPECT_LT(worst_f, 0.03);
      EXPECT_LT(worst_foot, 3e-2);
    } else {
      EXPECT_LT(worst_z, 3e-3 * px.root[300][kRootPz]);
    }
  }
}

}  // namespace
}  // namespace featherdrive
