// Batch through the SIMD lanes against the scalar step (Simulation, Batch with lanes off: another
// operation order), and its bits against themselves across lanes, batch sizes, widths and thread
// counts. docs/simd_batch.md.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "featherdrive/sim/batch.hpp"
#include "support/compare.hpp"
#include "support/drives.hpp"
#include "support/lanes.hpp"
#include "support/models.hpp"

namespace featherdrive {
namespace {

using test::kInf;
using test::same_bits;

// A random fixed-base tree of revolute, prismatic and fixed joints (general axes and frames,
// branches), force or acceleration drives with random targets, a force limit on some dofs and
// joint limits, joint friction or a velocity limit (that the drives reach) on others, started
// away from rest.
Simulation simd_prototype(unsigned seed, SolverType solver, int links = 9) {
  auto model = test::make_random_tree(seed, links, false, false, 0.01);
  Simulation sim(model, test::lane_test_options(solver));
  std::mt19937 rng(seed);
  test::drive_every_joint(sim, rng, 300.0, 20.0);
  for (int d = 0; d < model->nv; ++d) {
    Drive drive = sim.drive(d);
    if (d % 3 == 1) drive.type = DriveType::acceleration;
    if (d % 4 == 2) drive.max_force = 5.0;
    sim.set_drive(d, drive);
    if (d % 3 == 0) sim.set_joint_limits(d, -0.3, 0.4);
    if (d % 4 == 1) sim.set_joint_friction(d, JointFriction{0.3, 0.2, 0.1});
    if (d % 5 == 3) sim.set_max_joint_velocity(d, 0.3);
  }
  sim.set_qd(test::random_vector(model->nv, rng, 0.5));
  return sim;
}

// Asserts that the batch's next step() runs in the lanes, one group (Batch::step_path), of
// vectors or one-lane blocks.
#define ASSERT_LANES(batch)                                             \
  ASSERT_TRUE((batch).step_path().ends_with(" lanes") ||                \
              (batch).step_path().ends_with(" at one lane)"))          \
      << (batch).step_path()

double simd_relative_difference(const Eigen::Ref<const RowMatrix>& a,
                                const Eigen::Ref<const RowMatrix>& b) {
  return test::relative_difference(a, b);
}

// Steps both, then every environment's q, qd (1e-12) and drive, friction and velocity limit
// forces (force_tol) against the lone Simulation's; prints environment 0's q, qd difference for
// docs/simd_batch.md.
void step_and_expect_near(Batch& simd, Simulation& sim, int steps, double force_tol,
                          const std::string& what) {
  ASSERT_LANES(simd);
  simd.step(steps);
  sim.step(steps);
  for (int e = 0; e < simd.size(); ++e) {
    EXPECT_LE(simd_relative_difference(simd.q().row(e), sim.q().transpose()), 1e-12) << what;
    EXPECT_LE(simd_relative_difference(simd.qd().row(e), sim.qd().transpose()), 1e-12) << what;
    EXPECT_LE(simd_relative_difference(simd.drive_force().row(e), sim.drive_force().transpose()),
              force_tol)
        << what;
    EXPECT_LE(
        simd_relative_difference(simd.friction_force().row(e), sim.friction_force().transpose()),
        force_tol)
        << what;
    EXPECT_LE(simd_relative_difference(simd.velocity_limit_force().row(e),
                                       sim.velocity_limit_force().transpose()),
              force_tol)
        << what;
  }
  std::printf("%s: q, qd %.1e (docs/simd_batch.md)\n", what.c_str(),
              std::max(simd_relative_difference(simd.q().row(0), sim.q().transpose()),
                       simd_relative_difference(simd.qd().row(0), sim.qd().transpose())));
}

// Per-environment gains, targets, limits, friction, armature and link inertias of the
// randomisation API.
void randomise(Batch& simd, Batch& scalar, unsigned seed) {
  const int n = simd.size(), nv = simd.model().nv;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.5, 1.5);
  RowMatrix kp(n, nv), kd(n, nv), xt(n, nv), vt(n, nv), lo(n, nv), hi(n, nv), arm(n, nv);
  RowMatrix fs(n, nv), fv(n, nv);
  for (int e = 0; e < n; ++e)
    for (int d = 0; d < nv; ++d) {
      kp(e, d) = 400.0 * u(rng), kd(e, d) = 20.0 * u(rng);
      xt(e, d) = u(rng) - 1.0, vt(e, d) = 0.2 * (u(rng) - 1.0);
      lo(e, d) = d % 2 ? -kInf : -0.5 * u(rng), hi(e, d) = d % 2 ? kInf : 0.5 * u(rng);
      arm(e, d) = 0.02 * u(rng);
      fs(e, d) = d % 3 == 2 ? 0.2 * u(rng) : 0.0, fv(e, d) = d % 3 == 2 ? 0.1 * u(rng) : 0.0;
    }
  std::vector<int> all(static_cast<size_t>(n));
  for (int e = 0; e < n; ++e) all[static_cast<size_t>(e)] = e;
  const DriveType type = seed % 2 ? DriveType::acceleration : DriveType::force;
  simd.set_drive_gains(all, kp, kd, type);
  scalar.set_drive_gains(all, kp, kd, type);
  simd.set_drive_targets(all, xt, vt);
  scalar.set_drive_targets(all, xt, vt);
  simd.set_joint_limits(all, lo, hi);
  scalar.set_joint_limits(all, lo, hi);
  simd.set_armature(all, arm);
  scalar.set_armature(all, arm);
  simd.set_joint_friction(all, fs, 0.5 * fs, fv);
  scalar.set_joint_friction(all, fs, 0.5 * fs, fv);
  // Two environments without drives: their blocks mix driven and undriven lanes at every dof.
  // Viscous friction on every joint keeps these free trees from chaos, which would grow the last
  // bits' difference between the two step orders far beyond 1e-12 in 300 steps.
  const int undriven[] = {2, 5};
  const RowMatrix kp_undriven = kp.topRows(2), kd_undriven = kd.topRows(2);
  simd.set_drive_gains(undriven, kp_undriven, kd_undriven, DriveType::none);
  scalar.set_drive_gains(undriven, kp_undriven, kd_undriven, DriveType::none);
  const RowMatrix no_friction = RowMatrix::Zero(2, nv), damping = RowMatrix::Constant(2, nv, 2.0);
  simd.set_joint_friction(undriven, no_friction, no_friction, damping);
  scalar.set_joint_friction(undriven, no_friction, no_friction, damping);
  VecX mass(n);
  RowMatrix com(n, 3);
  for (int e = 0; e < n; ++e) {
    mass[e] = simd.model().links[2].mass * u(rng);
    com.row(e) = Vec3(u(rng) - 1.0, u(rng) - 1.0, u(rng) - 1.0).transpose() * 0.2;
  }
  simd.set_link_mass(all, 2, mass);
  scalar.set_link_mass(all, 2, mass);
  simd.set_link_com(all, 3, com);
  scalar.set_link_com(all, 3, com);
}

// Each environment as the scalar batch steps it, within twice the scalar step's own spread from
// starts a last bit off (kLastBitStarts scalar batches, test::nudge_start), at least 1e-12 and at
// most 1e-11 (test::expect_lanes_as_alone's bound): where a limit and a drive split a force, the
// split carries the last bits of either order (TGS environment 7: the lanes 1.9e-12 apart, the
// scalar batch's own spread 2.3e-12).
TEST(BatchLanes, RandomisedLanesEqualScalarBatchWithTheSameParameters) {
  for (SolverType solver : {SolverType::pgs, SolverType::tgs}) {
    // Without the prototype's velocity limits: with them env 1's TGS path runs through stick-slip
    // steps that grow the two step orders' last bits to 5e-10 (WithinTol... checks the limits).
    Simulation proto = simd_prototype(11, solver);
    for (int d = 0; d < proto.model().nv; ++d) proto.set_max_joint_velocity(d, test::kInf);
    const unsigned seed = solver == SolverType::pgs ? 3 : 4;
    Batch simd(proto, 11);
    Batch scalar(proto, 11);
    scalar.set_num_threads(1);
    scalar.set_lanes(false);
    randomise(simd, scalar, seed);
    std::vector<Batch> nudged;
    for (size_t k = 0; k < test::kLastBitStarts; k += 2) {
      Batch up(proto, 11), down(proto, 11);
      randomise(up, down, seed);
      nudged.push_back(std::move(up));
      nudged.push_back(std::move(down));
    }
    for (size_t k = 0; k < nudged.size(); ++k) {
      nudged[k].set_lanes(false);
      std::mt19937 signs(static_cast<unsigned>(k) + 1);
      for (int e = 0; e < 11; ++e) test::nudge_start(nudged[k].sim(e), k, signs);
    }
    ASSERT_LANES(simd);
    ASSERT_EQ(scalar.step_path(), "scalar: lanes off (set_lanes)");
    simd.step(300);
    scalar.step(300);
    for (Batch& b : nudged) b.step(300);
    const auto outputs = [](const Batch& b) {
      return std::array<const RowMatrix*, 5>{&b.q(), &b.qd(), &b.drive_force(), &b.limit_force(),
                                             &b.velocity_limit_force()};
    };
    const auto reference = outputs(scalar), lanes = outputs(simd);
    for (int e = 0; e < 11; ++e) {
      double own = 0.0, apart = 0.0;
      for (size_t f = 0; f < reference.size(); ++f) {
        apart = std::max(apart, simd_relative_difference(lanes[f]->row(e), reference[f]->row(e)));
        for (const Batch& b : nudged)
          own =
              std::max(own, simd_relative_difference(outputs(b)[f]->row(e), reference[f]->row(e)));
      }
      EXPECT_LE(apart, std::clamp(2.0 * own, test::kLaneTolerance, 10.0 * test::kLaneTolerance))
          << to_string(solver) << ", environment " << e << ", own spread " << own;
    }
    EXPECT_GT(scalar.limit_force().cwiseAbs().maxCoeff(), 0.0);  // the limits acted
    EXPECT_GT(scalar.friction_force().cwiseAbs().maxCoeff(), 0.0);
    EXPECT_EQ(simd.step_count()[10], 300);
    EXPECT_EQ(simd.link_mass(2), scalar.link_mass(2));
  }
}

// A long run of one environment per lane against Simulation::step, 1000 steps.
TEST(BatchLanes, WithinTolOfSimulationOverAThousandSteps) {
  for (SolverType solver : {SolverType::pgs, SolverType::tgs}) {
    Simulation sim = simd_prototype(21, solver, 12);
    Batch simd(sim, 3);
    ASSERT_LANES(simd);
    // The velocity limits act in the first steps (the drives pull harder than 0.3 rad/s).
    simd.step(20);
    sim.step(20);
    EXPECT_GT(sim.velocity_limit_force().cwiseAbs().maxCoeff(), 1.0) << to_string(solver);
    EXPECT_LE(simd_relative_difference(simd.velocity_limit_force().row(1),
                                       sim.velocity_limit_force().transpose()),
              1e-12);
    step_and_expect_near(simd, sim, 980, 1e-12, std::string("random tree, ") + to_string(solver));
  }
}

// Actuator envelopes (docs/math/joint_constraints.md J7) that bind, with an applied joint force
// in their effort: the lanes clamp the drive as Simulation does, on every lane of a block that
// mixes enveloped and free dofs. Without position limits and static friction: a joint at rest
// on a limit, or at the static threshold, is a knife edge where the two step orders' last bits
// choose different branches (Batch.RandomisedEnvironmentsEqual...); viscous friction on every
// joint keeps the tree from chaos, which grows those bits past 1e-12 in 700 steps without it.
TEST(BatchLanes, ActuatorEnvelopesAsSimulation) {
  for (SolverType solver : {SolverType::pgs, SolverType::tgs}) {
    Simulation sim = simd_prototype(23, solver, 10);
    const int nv = sim.model().nv;
    for (int d = 0; d < nv; ++d) {
      sim.set_joint_limits(d, -kInf, kInf);
      sim.set_joint_friction(d, JointFriction{0.0, 0.0, 0.5});
    }
    for (int d = 0; d < nv; d += 2)
      sim.set_actuator_envelope(d, ActuatorEnvelope{2.0 + 0.5 * d, d % 4 ? 3.0 : kInf, 0.2, 0.05});
    VecX tau = VecX::Zero(nv);
    tau[0] = 0.2;
    tau[2] = -0.1;
    sim.set_applied_force(tau);
    Batch simd(sim, 3);
    const RowMatrix applied = tau.transpose().replicate(3, 1);
    const int all[] = {0, 1, 2};
    simd.set_applied_force(all, applied);
    // The unclamped drives of the same start pull harder than the envelopes allow.
    Simulation free = sim;
    for (int d = 0; d < nv; ++d) free.set_actuator_envelope(d, ActuatorEnvelope{});
    free.step(20);
    simd.step(20);
    sim.step(20);
    EXPECT_GT((free.drive_force() - sim.drive_force()).cwiseAbs().maxCoeff(), 0.1);
    for (int e = 0; e < 3; ++e)
      EXPECT_LE(simd_relative_difference(simd.drive_force().row(e), sim.drive_force().transpose()),
                1e-12);
    // A bound drive's force follows the envelope's bound, which follows v through
    // r (lambda - accumulated): 5.7e-12 measured (PGS) where q and qd keep 6.3e-13.
    step_and_expect_near(simd, sim, 980, 2e-11,
                         std::string("random tree with envelopes, ") + to_string(solver));
  }
}

// PhysX's transmitted-force friction (docs/math/joint_constraints.md J6) on every joint: the
// lanes form each joint's transmitted force from the articulated-body equation, Simulation by
// summing the subtree's Newton-Euler forces; joints with static or viscous friction keep theirs.
TEST(BatchLanes, FrictionCoefficientAsSimulation) {
  for (SolverType solver : {SolverType::pgs, SolverType::tgs}) {
    Simulation sim = simd_prototype(29, solver, 10);
    const int nv = sim.model().nv;
    for (int d = 0; d < nv; ++d) sim.set_friction_coefficient(d, 0.1 + 0.05 * d);
    Batch simd(sim, 3);
    ASSERT_LANES(simd);
    simd.step(20);
    sim.step(20);
    double transmitted = 0.0;  // on the joints without static or viscous friction
    for (int d = 0; d < nv; ++d)
      if (sim.joint_friction(d).static_effort == 0.0)
        transmitted = std::max(transmitted, std::abs(sim.friction_force()[d]));
    EXPECT_GT(transmitted, 0.1) << to_string(solver);
    step_and_expect_near(
        simd, sim, 980, 1e-12,
        std::string("random tree with friction coefficients, ") + to_string(solver));
  }
}

// PhysX's per-link parameters: cfm (the rows' 1 / (r + cfm)), link damping and link velocity
// limits (forces on the free velocity) on some links each, in the lanes as in Simulation.
TEST(BatchLanes, LinkParametersAsSimulation) {
  for (SolverType solver : {SolverType::pgs, SolverType::tgs}) {
    Simulation sim = simd_prototype(31, solver, 10);
    Simulation plain = sim;
    for (int i = 1; i < sim.model().num_links(); ++i) {
      LinkParameters p;
      if (i % 2 == 1) p.cfm_scale = 0.025 * i;
      if (i % 3 == 0) p.linear_damping = 0.5, p.angular_damping = 2.0;
      if (i % 3 == 1) p.max_linear_velocity = 0.3, p.max_angular_velocity = 0.6;
      sim.set_link_parameters(i, p);
    }
    Batch simd(sim, 3);
    ASSERT_LANES(simd);
    simd.step(20);
    sim.step(20);
    plain.step(20);
    // The parameters act: the drive forces differ from the same start without them.
    EXPECT_GT((plain.drive_force() - sim.drive_force()).cwiseAbs().maxCoeff(), 0.1);
    step_and_expect_near(simd, sim, 980, 1e-12,
                         std::string("random tree with link parameters, ") + to_string(solver));
  }
}

// The same environments, given the same parameters, give the same bits at any lane, in a batch
// of any size, at every width this CPU has and on any number of threads.
TEST(BatchLanes, BitsIndependentOfLaneBatchSizeWidthAndThreads) {
  const Simulation proto = simd_prototype(5, SolverType::tgs);
  const int n = 13;
  auto run = [&](int size, SimdIsa isa, int threads, int shift, int first_call = 40) {
    Batch simd(proto, size);
    simd.set_isa(isa);
    simd.set_num_threads(threads);
    // Environment e of the reference gets gains of its own; here it sits at (e + shift) % size.
    RowMatrix kp(size, proto.model().nv);
    for (int e = 0; e < size; ++e) kp.row((e + shift) % size).setConstant(200.0 + 37.0 * e);
    std::vector<int> all;
    for (int e = 0; e < size; ++e) all.push_back(e);
    simd.set_drive_gains(all, kp, RowMatrix::Constant(1, proto.model().nv, 15.0));
    // 40 steps in calls of first_call, then one at a time: a block's scratch is reused by the
    // thread's other blocks and calls, so nothing may be read from it before it is written.
    EXPECT_EQ(simd.step_path(), std::string(to_string(isa)) + " lanes");
    simd.step(first_call);
    for (int s = first_call; s < 40; ++s) simd.step(1);
    RowMatrix out(size, proto.model().nv + proto.model().nq);
    for (int e = 0; e < size; ++e)
      out.row(e) << simd.qd().row((e + shift) % size), simd.q().row((e + shift) % size);
    return out;
  };
  const RowMatrix reference = run(n, SimdIsa::sse2, 1, 0);
  for (SimdIsa isa : available_simd_isas())
    for (int threads : {1, 2, 3})
      for (int shift : {0, 5}) {
        const RowMatrix x = run(n, isa, threads, shift);
        EXPECT_TRUE(same_bits(x, reference))
            << to_string(isa) << ", " << threads << " threads, shift " << shift;
      }
  // A batch of 40 fills blocks of four vectors with AVX2 (simd::interleave), where 13 had two:
  // its first 13 environments are the same ones, at every width.
  for (SimdIsa isa : available_simd_isas())
    for (int threads : {1, 2}) {
      const RowMatrix x = run(40, isa, threads, 0);
      EXPECT_TRUE(same_bits(RowMatrix(x.topRows(n)), reference))
          << to_string(isa) << ", 40 environments, " << threads << " threads";
    }
  // The same 40 steps in calls of 1 or 37 + 1 + 1 + 1.
  for (SimdIsa isa : available_simd_isas())
    for (int first_call : {0, 37}) {
      const RowMatrix x = run(40, isa, 2, 0, first_call);
      EXPECT_TRUE(same_bits(RowMatrix(x.topRows(n)), reference))
          << to_string(isa) << ", calls after " << first_call << " steps";
    }
  // Alone in a batch of one: environment 7.
  for (SimdIsa isa : available_simd_isas()) {
    Batch one(proto, 1);
    one.set_isa(isa);
    ASSERT_LANES(one);
    RowMatrix kp = RowMatrix::Constant(1, proto.model().nv, 200.0 + 37.0 * 7);
    const int e0[] = {0};
    one.set_drive_gains(e0, kp, RowMatrix::Constant(1, proto.model().nv, 15.0));
    one.step(40);
    EXPECT_TRUE(same_bits(RowMatrix(one.qd()), RowMatrix(reference.row(7).head(proto.model().nv))))
        << to_string(isa);
  }
}

// An environment that diverges stops with the state before that step and the scalar guard's
// message; the others make all their steps, bit for bit as without it.
TEST(BatchLanes, DivergenceStopsOnlyThatEnvironment) {
  Simulation proto = simd_prototype(8, SolverType::pgs);
  // Without velocity limits, which would scale the huge velocity below back to theirs.
  for (int d = 0; d < proto.model().nv; ++d) proto.set_max_joint_velocity(d, test::kInf);
  Batch calm(proto, 6), simd(proto, 6);
  const int bad[] = {4};
  ASSERT_LANES(simd);
  simd.step(3);
  calm.step(3);
  const VecX q_before = simd.q().row(4).transpose();
  simd.set_qd(bad, RowMatrix::Constant(1, proto.model().nv, 1e200));
  Simulation alone = simd.simulation(4);
  const std::string scalar_message = test::divergence_of(alone);
  ASSERT_FALSE(scalar_message.empty());
  const std::string batch_message = test::divergence_of(simd, 5);
  EXPECT_NE(batch_message.find("batch copy 4 (1 of 6"), std::string::npos) << batch_message;
  calm.step(5);
  ASSERT_TRUE(simd.divergences()[4].has_value());
  EXPECT_EQ(simd.divergences()[4]->message, scalar_message);
  EXPECT_EQ(simd.divergences()[4]->step, 4);
  EXPECT_EQ(simd.step_count()[4], 3);
  EXPECT_TRUE(same_bits(VecX(simd.q().row(4).transpose()), q_before));
  for (int e : {0, 1, 2, 3, 5}) {
    EXPECT_FALSE(simd.divergences()[e].has_value());
    EXPECT_EQ(simd.step_count()[e], 8);
    EXPECT_TRUE(same_bits(RowMatrix(simd.q().row(e)), RowMatrix(calm.q().row(e))));
  }
  simd.reset(bad);  // steps again
  simd.step(1);
  EXPECT_EQ(simd.step_count()[4], 1);
  EXPECT_FALSE(simd.divergences()[4].has_value());
}

// A wrapped revolute joint spun at 15 rad/s: its position wraps by 4 pi at each step's end past
// 2 pi (revolute_wrap.md eq. 1), in the lanes as in Simulation; unwrapped it would reach 75 rad.
TEST(BatchLanes, WrappedRevoluteJointWrapsAsSimulation) {
  for (SolverType solver : {SolverType::pgs, SolverType::tgs}) {
    Simulation sim = simd_prototype(21, solver, 12);
    int spun = -1;
    for (int d = 0; d < sim.model().nv && spun < 0; ++d)
      if (sim.model().links[sim.model().dof_link[d]].joint_type == JointType::revolute &&
          !std::isfinite(sim.lower_limit(d)) && std::isinf(sim.max_joint_velocity(d)))
        spun = d;
    ASSERT_GE(spun, 0);
    sim.set_joint_friction(spun, JointFriction{});
    sim.set_drive(spun, Drive{DriveType::force, 0.0, 50.0, kInf, 0.0, 15.0});
    sim.set_revolute_wrap(spun, RevoluteWrap::wrapped);
    Batch simd(sim, 3);
    ASSERT_LANES(simd);
    const int q_index = sim.model().links[sim.model().dof_link[spun]].q_index;
    double widest = 0.0;
    int wraps = 0;
    for (int s = 0; s < 1000; ++s) {
      const double before = sim.q()[q_index];
      simd.step(1);
      sim.step(1);
      widest = std::max(widest, std::abs(sim.q()[q_index]));
      wraps += std::abs(sim.q()[q_index] - before) > 6.0;
    }
    EXPECT_GT(wraps, 3) << to_string(solver);
    EXPECT_LE(widest, 2.0 * std::numbers::pi + 0.1) << to_string(solver);
    for (int e = 0; e < 3; ++e) {
      EXPECT_LE(simd_relative_difference(simd.q().row(e), sim.q().transpose()), 1e-12);
      EXPECT_LE(simd_relative_difference(simd.qd().row(e), sim.qd().transpose()), 1e-12);
    }
  }
}

// Every setting the scalar step takes steps in the lanes (step_path says so), the ones the lanes
// took last among them.
TEST(BatchLanes, StepPathTakesEverySetting) {
  // A floating root whose joint frame turns, under compat physx (lane_floating_test.cpp).
  Model turned = *test::make_random_tree(2, 4, true, false);
  turned.links[0].tree_transform.E = rotation_about(Vec3::UnitZ(), 0.3);
  SimulationOptions physx;
  physx.compat = Compat::physx;
  Batch turned_root(Simulation(std::make_shared<const Model>(turned), physx), 2);
  ASSERT_LANES(turned_root);
  Simulation s = simd_prototype(9, SolverType::pgs, 5);
  // The step guard the lanes take (step_guard_test.cpp), with ground contacts too.
  SimulationOptions guard = s.options();
  guard.guard.enabled = true;
  Simulation guarded = s;
  guarded.set_options(guard);
  Batch guarded_batch(guarded, 2);
  ASSERT_LANES(guarded_batch);
  // A ground with the model's shapes: the lanes solve their rows (lane_contact_test.cpp), under
  // compat none and physx.
  Model shaped = s.model();
  CollisionShape ball;
  ball.link = shaped.num_links() - 1;
  ball.size = Vec3(0.1, 0.0, 0.0);
  shaped.shapes.push_back(ball);
  Simulation grounded(std::make_shared<const Model>(shaped), s.options());
  Ground ground;
  ground.enabled = true;
  grounded.set_ground(ground);
  Batch on_ground(grounded, 2);
  ASSERT_LANES(on_ground);
  Simulation guarded_on_ground = grounded;
  guarded_on_ground.set_options(guard);
  Batch guarded_grounded_batch(guarded_on_ground, 2);
  ASSERT_LANES(guarded_grounded_batch);
  SimulationOptions physx_options = grounded.options();
  physx_options.compat = Compat::physx;
  Simulation grounded_physx(grounded.model_ptr(), physx_options);
  grounded_physx.set_ground(ground);
  Batch on_ground_physx(grounded_physx, 2);
  ASSERT_LANES(on_ground_physx);
  ground.enabled = false;
  grounded.set_ground(ground);
  Batch shapes_alone(grounded, 2);  // shapes alone do nothing
  ASSERT_LANES(shapes_alone);
  // Self-collision rows too: two shapes on links that are not parent and child.
  Model paired = shaped;
  CollisionShape base_ball = ball;
  base_ball.link = 0;
  paired.shapes.insert(paired.shapes.begin(), base_ball);
  Simulation self(std::make_shared<const Model>(paired), s.options());
  ContactOptions contact;
  contact.self_collision = true;
  self.set_contact_options(contact);
  Batch selfish(self, 2);
  ASSERT_LANES(selfish);
  // An implicit actuator's row and convergence tracking are the lanes' (lane_actuator_test.cpp).
  Simulation actuated = s;
  actuated.set_drive(1, Drive{});
  ExplicitActuator a;
  a.kind = ActuatorKind::ideal_pd;
  a.stiffness = 10.0;
  a.integration = ActuatorIntegration::implicit_law;
  actuated.set_actuator(1, a);
  actuated.set_track_convergence(true);
  Batch implicit(actuated, 2);
  ASSERT_LANES(implicit);
  Batch ok(s, 2);
  ASSERT_LANES(ok);
  const int ids[] = {1, 1};
  EXPECT_THROW(ok.set_q(ids, RowMatrix::Zero(1, s.model().nq)), std::invalid_argument);
  const int one[] = {1};
  try {
    ok.set_drive_gains(one, RowMatrix::Constant(1, s.model().nv, -5.0),
                       RowMatrix::Zero(1, s.model().nv));
    ADD_FAILURE();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("environment 1: set_drive_gains: dof 0: drive on joint"),
              std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("stiffness = -5"), std::string::npos) << e.what();
  }
  EXPECT_EQ(ok.stiffness()(1, 0), s.drive(0).stiffness);  // nothing changed
}

}  // namespace
}  // namespace featherdrive
