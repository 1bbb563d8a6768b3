// Cross-check against MuJoCo 2.2.2: the io layer writes MJCF from a featherdrive::Model
// (model_to_mjcf, whose mapping mjcf_export.hpp describes), the test steps both engines with
// semi-implicit Euler from the same state and compares joint positions and velocities at every
// step. Nothing else is added: no contacts, limits, damping, armature, stiffness or actuators, so
// MuJoCo's Euler integrator is explicit in velocity (it goes implicit only for dof_damping > 0) and
// integrates positions with the new velocity, as Simulation does without drives.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include <unistd.h>

#include "featherdrive/algorithm/aba.hpp"
#include "featherdrive/algorithm/center_of_mass.hpp"
#include "featherdrive/algorithm/crba.hpp"
#include "featherdrive/algorithm/energy.hpp"
#include "featherdrive/algorithm/jacobian.hpp"
#include "featherdrive/algorithm/kinematics.hpp"
#include "featherdrive/algorithm/rnea.hpp"
#include "featherdrive/io/mjcf_export.hpp"
#include "featherdrive/io/urdf.hpp"
#include "featherdrive/sim/simulation.hpp"
#include "support/models.hpp"

namespace featherdrive {
namespace {

constexpr double kDt = 1.0 / 240.0;
constexpr int kSteps = 200;
constexpr double kPositionTolerance = 1e-9;
// The two engines round differently (MuJoCo factors M, we run ABA), so accelerations differ by
// ~1e-13 and velocities accumulate it: over 300 random trees the worst velocity difference in 200
// steps was 3e-12 and the worst position difference 2e-13. 1e-9 leaves three orders of margin and
// is still far below what any modelling difference (a frame, inertia or bias term) produces.
constexpr double kVelocityTolerance = 1e-9;

/// MJCF for a model: gravity, time step, Euler, contacts off, nothing else (the io layer's
/// writer; this test checks MuJoCo's dynamics of it against ours).
std::string to_mjcf(const Model& model, double dt) { return model_to_mjcf(model, dt); }

struct MjModelDeleter {
  void operator()(mjModel* m) const { mj_deleteModel(m); }
};
struct MjDataDeleter {
  void operator()(mjData* d) const { mj_deleteData(d); }
};
using MjModelPtr = std::unique_ptr<mjModel, MjModelDeleter>;
using MjDataPtr = std::unique_ptr<mjData, MjDataDeleter>;

/// Compiles MJCF text through a file in a fresh temporary directory (removed afterwards).
MjModelPtr load_mjcf(const std::string& xml) {
  namespace fs = std::filesystem;
  static int counter = 0;
  const fs::path dir =
      fs::temp_directory_path() /
      ("featherdrive_mujoco_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
  fs::create_directories(dir);
  const fs::path file = dir / "model.xml";
  {
    std::ofstream out(file);
    out << xml;
  }
  std::array<char, 1000> error{};
  MjModelPtr m(mj_loadXML(file.c_str(), nullptr, error.data(), static_cast<int>(error.size())));
  std::error_code ignored;
  fs::remove_all(dir, ignored);
  EXPECT_NE(m, nullptr) << "mj_loadXML: " << error.data() << "\n" << xml;
  return m;
}

double max_abs_diff(const VecX& a, const mjtNum* b) {
  double d = 0.0;
  for (Eigen::Index k = 0; k < a.size(); ++k) d = std::max(d, std::abs(a[k] - b[k]));
  return d;
}

struct Comparison {
  double max_position_diff = 0.0;
  double max_velocity_diff = 0.0;
  double max_initial_qacc_diff = 0.0;
  double max_initial_bias_diff = 0.0;
  double max_initial_mass_diff = 0.0;
};

/// Loads the model into MuJoCo, checks that nothing beyond the model came in, starts both engines
/// from (q, qd) and steps them, expecting agreement at every step.
Comparison compare_with_mujoco(const std::shared_ptr<const Model>& model, const VecX& q,
                               const VecX& qd) {
  Comparison out;
  if (model->floating_base()) {
    ADD_FAILURE() << "compare_with_mujoco needs a fixed root";
    return out;
  }
  const std::string xml = to_mjcf(*model, kDt);
  MjModelPtr m = load_mjcf(xml);
  if (!m) return out;

  // The compiled model is ours and nothing more.
  EXPECT_EQ(m->nq, model->nq);
  EXPECT_EQ(m->nv, model->nv);
  EXPECT_EQ(m->nbody, model->num_links() + 1);  // + the world body
  EXPECT_EQ(m->nu, 0);
  EXPECT_EQ(m->neq, 0);
  EXPECT_EQ(m->opt.integrator, mjINT_EULER);
  EXPECT_EQ(m->opt.timestep, kDt);
  EXPECT_TRUE(m->opt.disableflags & mjDSBL_CONTACT);
  EXPECT_EQ(m->opt.density, 0.0);
  EXPECT_EQ(m->opt.viscosity, 0.0);
  for (int k = 0; k < 3; ++k) EXPECT_EQ(m->opt.gravity[k], model->gravity[k]);
  for (int j = 0; j < m->njnt; ++j) {
    EXPECT_EQ(m->jnt_limited[j], 0);
    EXPECT_EQ(m->jnt_stiffness[j], 0.0);
  }
  for (int k = 0; k < m->nv; ++k) {
    EXPECT_EQ(m->dof_damping[k], 0.0);
    EXPECT_EQ(m->dof_armature[k], 0.0);
    EXPECT_EQ(m->dof_frictionloss[k], 0.0);
  }
  // The compiled inertials are ours to rounding.
  for (int i = 0; i < model->num_links(); ++i) {
    const Link& link = model->links[i];
    const int body = i + 1;
    const mjtNum* iq = m->body_iquat + 4 * body;
    const mjtNum* moments = m->body_inertia + 3 * body;
    const Mat3 axes = Quat(iq[0], iq[1], iq[2], iq[3]).toRotationMatrix();
    const Mat3 I = axes * Vec3(moments[0], moments[1], moments[2]).asDiagonal() * axes.transpose();
    EXPECT_LE((I - link.inertia_com).cwiseAbs().maxCoeff(),
              1e-14 * link.inertia_com.cwiseAbs().maxCoeff())
        << link.name;
    EXPECT_EQ(m->body_mass[body], link.mass) << link.name;
    for (int k = 0; k < 3; ++k)
      EXPECT_NEAR(m->body_ipos[3 * body + k], link.com[k], 1e-15) << link.name;
  }
  // MuJoCo's joint and dof order is ours.
  for (const Link& link : model->links) {
    if (link.nv == 0) continue;
    const int j = mj_name2id(m.get(), mjOBJ_JOINT, link.joint_name.c_str());
    EXPECT_GE(j, 0) << link.joint_name;
    if (j < 0) return out;
    EXPECT_EQ(m->jnt_qposadr[j], link.q_index) << link.joint_name;
    EXPECT_EQ(m->jnt_dofadr[j], link.v_index) << link.joint_name;
  }
  if (::testing::Test::HasFailure()) return out;

  SimulationOptions options;
  options.dt = kDt;
  Simulation sim(model, options);
  sim.set_q(q);  // normalises quaternions
  sim.set_qd(qd);

  MjDataPtr d(mj_makeData(m.get()));
  std::copy(sim.q().data(), sim.q().data() + model->nq, d->qpos);
  std::copy(sim.qd().data(), sim.qd().data() + model->nv, d->qvel);

  // The dynamics terms at the start: M, the bias force (Coriolis, centrifugal, gravity), qdd.
  mj_forward(m.get(), d.get());
  Data data(*model);
  const VecX zero = VecX::Zero(model->nv);
  out.max_initial_qacc_diff = max_abs_diff(aba(*model, data, sim.q(), sim.qd(), zero), d->qacc);
  out.max_initial_bias_diff =
      max_abs_diff(rnea(*model, data, sim.q(), sim.qd(), zero), d->qfrc_bias);
  std::vector<mjtNum> M_mj(static_cast<size_t>(model->nv * model->nv));
  mj_fullM(m.get(), M_mj.data(), d->qM);
  const MatX& M = crba(*model, data, sim.q());
  for (int r = 0; r < model->nv; ++r)
    for (int c = 0; c < model->nv; ++c)
      out.max_initial_mass_diff =
          std::max(out.max_initial_mass_diff,
                   std::abs(M(r, c) - M_mj[static_cast<size_t>(r * model->nv + c)]));

  for (int step = 1; step <= kSteps; ++step) {
    mj_step(m.get(), d.get());
    sim.step();
    const double dq = max_abs_diff(sim.q(), d->qpos);
    const double dv = max_abs_diff(sim.qd(), d->qvel);
    out.max_position_diff = std::max(out.max_position_diff, dq);
    out.max_velocity_diff = std::max(out.max_velocity_diff, dv);
    EXPECT_LE(dq, kPositionTolerance) << "step " << step;
    EXPECT_LE(dv, kVelocityTolerance) << "step " << step;
    if (dq > kPositionTolerance || dv > kVelocityTolerance) break;  // one report is enough
  }
  EXPECT_EQ(d->time, sim.time());
  return out;
}

void report(const char* what, const Comparison& c) {
  std::printf(
      "[ mujoco   ] %s: max |dq| %.3g, max |dqd| %.3g over %d steps; at the start |dqdd| %.3g, "
      "|d bias| %.3g, |dM| %.3g\n",
      what, c.max_position_diff, c.max_velocity_diff, kSteps, c.max_initial_qacc_diff,
      c.max_initial_bias_diff, c.max_initial_mass_diff);
}

void expect_initial_terms_agree(const Comparison& c) {
  EXPECT_LE(c.max_initial_mass_diff, 1e-12);
  EXPECT_LE(c.max_initial_bias_diff, 1e-11);
  EXPECT_LE(c.max_initial_qacc_diff, 1e-10);
}

TEST(MuJoCo, MjcfWriterMapsFramesInertiaAndJoints) {
  // One revolute joint below a rotated, offset fixed root: MuJoCo's compiled body frames and
  // inertia must be the ones we meant.
  ModelBuilder b;
  b.set_gravity(Vec3(0.1, 0.2, -9.81));
  b.add_link(make_link("base", "", 2.0, Vec3(0.1, 0, 0),
                       test::box_inertia(2.0, Vec3(0.2, 0.3, 0.4)),
                       fixed_joint("weld", Vec3(0.5, -0.2, 1.0), Vec3(0.3, -0.4, 0.5))));
  Mat3 I;
  I << 0.02, 0.001, -0.002, 0.001, 0.03, 0.003, -0.002, 0.003, 0.04;
  b.add_link(
      make_link("arm", "base", 1.5, Vec3(0.2, -0.1, 0.3), I,
                revolute_joint("hinge", Vec3(1, 2, 3), Vec3(0.1, 0.2, 0.3), Vec3(-0.7, 0.2, 1.1))));
  const auto model = std::make_shared<const Model>(b.build());
  MjModelPtr m = load_mjcf(to_mjcf(*model, kDt));
  ASSERT_NE(m, nullptr);
  MjDataPtr d(mj_makeData(m.get()));
  d->qpos[0] = 0.7;
  mj_forward(m.get(), d.get());
  Data data(*model);
  VecX q(1);
  q << 0.7;
  forward_kinematics(*model, data, q);
  for (int i = 0; i < model->num_links(); ++i) {
    const int body = i + 1;
    for (int r = 0; r < 3; ++r) {
      EXPECT_NEAR(d->xpos[3 * body + r], data.world_position[i][r], 1e-14) << i;
      for (int c = 0; c < 3; ++c)
        EXPECT_NEAR(d->xmat[9 * body + 3 * r + c], data.world_rotation[i](r, c), 1e-14) << i;
    }
    // Centre of mass in the world.
    const Vec3 com = data.world_position[i] + data.world_rotation[i] * model->links[i].com;
    for (int r = 0; r < 3; ++r) EXPECT_NEAR(d->xipos[3 * body + r], com[r], 1e-14) << i;
    EXPECT_EQ(m->body_mass[body], model->links[i].mass);
  }
}

TEST(MuJoCo, PlanarChainMatchesEuler) {
  const auto model = test::make_planar_chain(3, 1.3, 0.7);
  std::mt19937 rng(11);
  const VecX q = test::random_configuration(*model, rng);
  const VecX qd = test::random_vector(model->nv, rng, 2.0);
  const Comparison c = compare_with_mujoco(model, q, qd);
  report("planar 3-link chain", c);
  expect_initial_terms_agree(c);
}

TEST(MuJoCo, SpatialChainMatchesEuler) {
  // Three revolute joints and a prismatic one with skew axes, rotated joint frames, offset centres
  // of mass and full inertia tensors.
  ModelBuilder b;
  b.set_gravity(Vec3(0.0, 0.0, -9.81));
  b.add_link(make_link("base", "", 1.0, Vec3::Zero(), test::box_inertia(1.0, Vec3(0.1, 0.1, 0.1)),
                       fixed_joint("world_joint", Vec3(0, 0, 1))));
  Mat3 I;
  I << 0.05, 0.004, -0.003, 0.004, 0.06, 0.002, -0.003, 0.002, 0.03;
  b.add_link(make_link(
      "l1", "base", 1.2, Vec3(0.05, 0.1, -0.2), I,
      revolute_joint("j1", Vec3(0.3, 1.0, 0.2), Vec3(0.0, 0.1, 0.0), Vec3(0.4, -0.2, 0.9))));
  b.add_link(make_link(
      "l2", "l1", 0.9, Vec3(-0.1, 0.0, -0.25), I * 0.8,
      revolute_joint("j2", Vec3(1.0, 0.0, 0.5), Vec3(0.1, 0.0, -0.4), Vec3(-0.6, 0.3, 0.1))));
  b.add_link(make_link(
      "l3", "l2", 0.6, Vec3(0.0, 0.05, -0.15), I * 0.5,
      prismatic_joint("j3", Vec3(0.2, -0.3, 1.0), Vec3(0.0, 0.1, -0.3), Vec3(0.2, 0.5, -0.4))));
  b.add_link(make_link(
      "l4", "l3", 0.4, Vec3(0.02, -0.03, -0.1), I * 0.3,
      revolute_joint("j4", Vec3(-0.5, 0.4, 0.7), Vec3(0.05, 0.0, -0.2), Vec3(1.2, -0.8, 0.3))));
  const auto model = std::make_shared<const Model>(b.build());
  std::mt19937 rng(12);
  const VecX q = test::random_configuration(*model, rng);
  const VecX qd = test::random_vector(model->nv, rng, 2.0);
  const Comparison c = compare_with_mujoco(model, q, qd);
  report("spatial 4-link chain", c);
  expect_initial_terms_agree(c);
}

TEST(MuJoCo, RandomTreesOfHingesAndSlidesMatchEuler) {
  Comparison worst;
  for (unsigned seed = 1; seed <= 10; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    const auto model = test::make_random_tree(seed, 10, /*floating=*/false, /*spherical=*/false);
    std::mt19937 rng(100 + seed);
    const VecX q = test::random_configuration(*model, rng);
    const VecX qd = test::random_vector(model->nv, rng, 1.0);
    const Comparison c = compare_with_mujoco(model, q, qd);
    expect_initial_terms_agree(c);
    worst.max_position_diff = std::max(worst.max_position_diff, c.max_position_diff);
    worst.max_velocity_diff = std::max(worst.max_velocity_diff, c.max_velocity_diff);
    worst.max_initial_qacc_diff = std::max(worst.max_initial_qacc_diff, c.max_initial_qacc_diff);
    worst.max_initial_bias_diff = std::max(worst.max_initial_bias_diff, c.max_initial_bias_diff);
    worst.max_initial_mass_diff = std::max(worst.max_initial_mass_diff, c.max_initial_mass_diff);
  }
  report("10 random 10-link trees (hinge, slide, fixed)", worst);
}

TEST(MuJoCo, RandomTreesWithBallJointsMatchEuler) {
  Comparison worst;
  for (unsigned seed = 1; seed <= 10; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    const auto model = test::make_random_tree(seed, 10, /*floating=*/false, /*spherical=*/true);
    std::mt19937 rng(200 + seed);
    const VecX q = test::random_configuration(*model, rng);
    const VecX qd = test::random_vector(model->nv, rng, 1.0);
    const Comparison c = compare_with_mujoco(model, q, qd);
    expect_initial_terms_agree(c);
    worst.max_position_diff = std::max(worst.max_position_diff, c.max_position_diff);
    worst.max_velocity_diff = std::max(worst.max_velocity_diff, c.max_velocity_diff);
    worst.max_initial_qacc_diff = std::max(worst.max_initial_qacc_diff, c.max_initial_qacc_diff);
    worst.max_initial_bias_diff = std::max(worst.max_initial_bias_diff, c.max_initial_bias_diff);
    worst.max_initial_mass_diff = std::max(worst.max_initial_mass_diff, c.max_initial_mass_diff);
  }
  report("10 random 10-link trees (hinge, slide, ball, fixed)", worst);
}

TEST(MuJoCo, FloatingRootAccelerationsMatch) {
  // Floating root (MuJoCo free joint) over a random tree with ball joints: the joint accelerations
  // at a random state, with the root's velocity and acceleration converted between our body-frame
  // [w; v] and MuJoCo's [world linear velocity of the body origin; body-frame w]:
  //   v_mj = [R v; w],  qacc_mj = [R (dv/dt + w x v); dw/dt].
  double worst = 0.0;
  for (unsigned seed = 1; seed <= 10; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    const auto model = test::make_random_tree(seed, 10, /*floating=*/true, /*spherical=*/true);
    ASSERT_TRUE(model->links[0].tree_transform.E.isIdentity(0.0));
    ASSERT_TRUE(model->links[0].tree_transform.r.isZero(0.0));
    MjModelPtr m = load_mjcf(to_mjcf(*model, kDt));
    ASSERT_NE(m, nullptr);
    ASSERT_EQ(m->nq, model->nq);
    ASSERT_EQ(m->nv, model->nv);
    std::mt19937 rng(300 + seed);
    VecX q = test::random_configuration(*model, rng);
    q.head<3>() *= 2.0;
    const VecX v = test::random_vector(model->nv, rng, 1.0);
    const Mat3 R = Quat(q[3], q[4], q[5], q[6]).toRotationMatrix();
    const Vec3 w = v.head<3>();
    const Vec3 lin = v.segment<3>(3);

    MjDataPtr d(mj_makeData(m.get()));
    std::copy(q.data(), q.data() + model->nq, d->qpos);
    VecX v_mj = v;
    v_mj.head<3>() = R * lin;
    v_mj.segment<3>(3) = w;
    std::copy(v_mj.data(), v_mj.data() + model->nv, d->qvel);
    mj_forward(m.get(), d.get());

    Data data(*model);
    VecX qdd = aba(*model, data, q, v, VecX::Zero(model->nv));
    VecX qdd_mj = qdd;
    qdd_mj.head<3>() = R * (qdd.segment<3>(3) + w.cross(lin));
    qdd_mj.segment<3>(3) = qdd.head<3>();
    const double diff = max_abs_diff(qdd_mj, d->qacc);
    EXPECT_LE(diff, 1e-10);
    worst = std::max(worst, diff);
  }
  std::printf("[ mujoco   ] floating root, 10 random 10-link trees: max |dqdd| %.3g\n", worst);
}

TEST(MuJoCo, ArmMassMatrixBiasJacobiansAndCentreOfMassMatch) {
  // examples/arm7.urdf at random states: M against mj_fullM, the bias and gravity forces against
  // qfrc_bias, every link's world-aligned Jacobian (origin and an offset point) against mj_jac,
  // the centre of mass and its Jacobian against subtree_com and mj_jacSubtreeCom of the root.
  const UrdfRobot robot = load_urdf(std::string(FEATHERDRIVE_SOURCE_DIR) + "/examples/arm7.urdf");
  const Model& model = *robot.model;
  ASSERT_EQ(model.nv, 7);
  MjModelPtr m = load_mjcf(to_mjcf(model, kDt));
  ASSERT_NE(m, nullptr);
  ASSERT_EQ(m->nbody, model.num_links() + 1);
  MjDataPtr d(mj_makeData(m.get()));
  Data data(model);
  const int nv = model.nv;
  std::vector<mjtNum> M_mj(static_cast<size_t>(nv * nv)), jacp(3 * static_cast<size_t>(nv)),
      jacr(3 * static_cast<size_t>(nv));
  // Row-major 3 x nv from MuJoCo as a matrix.
  auto rows = [nv](const std::vector<mjtNum>& j) {
    return Eigen::Map<const Eigen::Matrix<double, 3, Eigen::Dynamic, Eigen::RowMajor>>(j.data(), 3,
                                                                                      nv);
  };
  double worst_M = 0.0, worst_bias = 0.0, worst_J = 0.0, worst_com = 0.0;
  MatX J, J_com;
  std::mt19937 rng(20);
  for (int trial = 0; trial < 5; ++trial) {
    const VecX q = test::random_configuration(model, rng);
    const VecX v = test::random_vector(nv, rng, 1.5);
    std::copy(q.data(), q.data() + nv, d->qpos);
    std::fill(d->qvel, d->qvel + nv, 0.0);
    mj_forward(m.get(), d.get());
    worst_bias = std::max(worst_bias, max_abs_diff(generalized_gravity(model, data, q),
                                                   d->qfrc_bias));
    std::copy(v.data(), v.data() + nv, d->qvel);
    mj_forward(m.get(), d.get());
    worst_bias = std::max(worst_bias, max_abs_diff(nonlinear_effects(model, data, q, v),
                                                   d->qfrc_bias));
    mj_fullM(m.get(), M_mj.data(), d->qM);
    const MatX& M = crba(model, data, q);
    for (int r = 0; r < nv; ++r)
      for (int c = 0; c < nv; ++c)
        worst_M = std::max(worst_M, std::abs(M(r, c) - M_mj[static_cast<size_t>(r * nv + c)]));

    forward_kinematics(model, data, q, v);
    const Vec3 point(0.03, -0.05, 0.07);
    for (int i = 0; i < model.num_links(); ++i) {
      for (const Vec3& p : {Vec3(Vec3::Zero()), point}) {
        const Vec3 world = frame_position(model, data, i, p);
        mj_jac(m.get(), d.get(), jacp.data(), jacr.data(), world.data(), i + 1);
        frame_jacobian(model, data, i, p, ReferenceFrame::world_aligned, J);
        worst_J = std::max(worst_J, (J.bottomRows<3>() - rows(jacp)).cwiseAbs().maxCoeff());
        worst_J = std::max(worst_J, (J.topRows<3>() - rows(jacr)).cwiseAbs().maxCoeff());
      }
    }
    const Vec3 com = center_of_mass(model, data);
    for (int k = 0; k < 3; ++k)
      worst_com = std::max(worst_com, std::abs(com[k] - d->subtree_com[3 + k]));
    mj_jacSubtreeCom(m.get(), d.get(), jacp.data(), 1);
    center_of_mass_jacobian(model, data, J_com);
    worst_com = std::max(worst_com, (J_com - rows(jacp)).cwiseAbs().maxCoeff());
  }
  EXPECT_LE(worst_M, 1e-12);
  EXPECT_LE(worst_bias, 1e-11);
  EXPECT_LE(worst_J, 1e-13);
  EXPECT_LE(worst_com, 1e-13);
  std::printf("[ mujoco   ] arm7, 5 states: max |dM| %.3g, |d bias| %.3g, |dJ| %.3g, "
              "|d com, J_com| %.3g\n", worst_M, worst_bias, worst_J, worst_com);
}

}  // namespace
}  // namespace featherdrive
