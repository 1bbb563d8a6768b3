// The MuJoCo bridge against MuJoCo 2.2.2 itself: featherdrive's step responses and MuJoCo's runs
// of the exported MJCF with translated gains (and, for the record, with the same numbers), on a
// slider and on the 7-dof arm, for a grid of stiffness, damping ratio and solver.
#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include <unistd.h>
#include <urdf_parser/urdf_parser.h>

#include "featherdrive/algorithm/frame_kinematics.hpp"
#include "featherdrive/algorithm/kinematics.hpp"
#include "featherdrive/io/files.hpp"
#include "featherdrive/io/mjcf.hpp"
#include "featherdrive/io/mjcf_export.hpp"
#include "featherdrive/io/mujoco_scene.hpp"
#include "featherdrive/io/scene.hpp"
#include "featherdrive/io/urdf.hpp"
#include "featherdrive/sim/gain_translation.hpp"
#include "support/models.hpp"

namespace featherdrive {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kDt = 1.0 / 60.0;

SimulationOptions solver(SolverType type, int position, int velocity) {
  SimulationOptions o;
  o.dt = kDt;
  o.solver = type;
  o.position_iterations = position;
  o.velocity_iterations = velocity;
  return o;
}

struct Response {
  VecX worst;  ///< per dof: largest |q_featherdrive - q_mujoco| / step size
  bool finite = true;
};

// Both engines from q0 at rest, every driven dof's target q0 + step; the largest q difference
// per dof over `steps` steps, relative to the step.
Response step_response(const Simulation& start, DriveMapping mapping, double step, int steps) {
  Simulation sim = start;
  for (int d = 0; d < sim.model().nv; ++d) {
    Drive drive = sim.drive(d);
    drive.target_position = sim.q()[d] + step;
    sim.set_drive(d, drive);
  }
  MjcfExportOptions options;
  options.drives = mapping;
  const MjcfExport mjcf = export_mjcf(sim, options);
  MujocoRun mj(mjcf);
  mj.set_state(sim.q(), sim.qd());
  Response run;
  run.worst = VecX::Zero(sim.model().nv);
  for (int k = 0; k < steps; ++k) {
    mj.step(sim);
    sim.step();
    const VecX diff = (sim.q() - mj.q()).cwiseAbs() / step;
    if (mj.diverged() || !diff.allFinite()) {  // MuJoCo resets a diverging run
      run.finite = false;
      run.worst.setConstant(kInf);
      break;
    }
    run.worst = run.worst.cwiseMax(diff);
  }
  return run;
}

struct GridPoint {
  double s;     ///< kp dt^2 / m
  double zeta;  ///< damping ratio, kd = 2 zeta sqrt(kp m)
};

const std::vector<GridPoint>& grid() {
  // kp dt^2 / m from 1e-3 to 3.9, just inside MuJoCo's explicit limit of 4 (undamped).
  static const std::vector<GridPoint> points = [] {
    std::vector<GridPoint> p;
    for (double s : {1e-3, 3e-2, 0.5, 3.9})
      for (double zeta : {0.1, 0.7, 2.0}) p.push_back({s, zeta});
    return p;
  }();
  return points;
}

TEST(MujocoBridge, TranslatedSliderTracksFeatherdriveStepResponse) {
  // A 1.5 kg slider, gravity across its axis: the step response alone (a force along the axis
  // enters TGS once per step and MuJoCo once per sub-step; compare-mujoco measures that).
  const double mass = 1.5;
  const auto model = test::make_slider(mass, Vec3(0.8, 0.6, 0), Vec3(0, 0, -9.81));
  const double m = effective_inertia(*model, VecX::Zero(1))[0];
  ASSERT_NEAR(m, mass, 1e-12);
  const double step = 0.1;
  double worst_translated = 0.0;
  std::printf("[ bridge   ] slider: largest |q_fd - q_mj| / step over the run\n");
  std::printf("[ bridge   ] %-8s %-7s %-5s %12s %12s\n", "solver", "s", "zeta", "translated",
              "literal");
  for (const SimulationOptions& o :
       {solver(SolverType::pgs, 4, 1), solver(SolverType::tgs, 4, 1)}) {
    for (DriveType type : {DriveType::force, DriveType::acceleration}) {
      for (const GridPoint& g : grid()) {
        const double kp = g.s * m / (kDt * kDt), kd = 2.0 * g.zeta * std::sqrt(kp * m);
        const double scale = type == DriveType::acceleration ? 1.0 / m : 1.0;
        Simulation sim(model, o);
        sim.set_drive(0, Drive{type, kp * scale, kd * scale, kInf, 0.0, 0.0});
        // Settled in ~6 time constants of the slowest mode, 600 steps at most.
        const int steps = 240;
        const Response translated = step_response(sim, DriveMapping::translated, step, steps);
        const Response literal = step_response(sim, DriveMapping::literal, step, steps);
        EXPECT_LE(translated.worst[0], 0.02)
            << to_string(o.solver) << " " << to_string(type) << " s " << g.s << " zeta " << g.zeta;
        worst_translated = std::max(worst_translated, translated.worst[0]);
        if (type == DriveType::force)
          std::printf("[ bridge   ] %-8s %-7.3g %-5.2g %12.2e %12.2e\n",
                      (std::string(to_string(o.solver)) + " 4/1").c_str(), g.s, g.zeta,
                      translated.worst[0], literal.worst[0]);
      }
    }
  }
  std::printf("[ bridge   ] slider, worst translated: %.2e of the step\n", worst_translated);
}

TEST(MujocoBridge, TranslatedArmTracksFeatherdriveStepResponsePerJoint) {
  const UrdfRobot robot = load_urdf(std::string(FEATHERDRIVE_SOURCE_DIR) + "/examples/arm7.urdf");
  // Without gravity: the drives' step response, not the fall of an arm on soft drives.
  Model weightless = *robot.model;
  weightless.gravity.setZero();
  const auto model = std::make_shared<const Model>(weightless);
  VecX q0 = VecX::Zero(model->nv);
  q0 << 0.2, 0.5, -0.3, 1.2, 0.4, 0.6, -0.2;
  const VecX m = effective_inertia(*model, q0);
  const double step = 0.1;
  // MuJoCo solves the coupled implicit step exactly; featherdrive's Gauss-Seidel sweeps converge
  // to it. With 64 sweeps the engines agree to rounding at every grid point; PGS 4/1 keeps a
  // residual that grows with stiffness (within 5 % up to kp dt^2/m = 0.5) and TGS 4/1 runs one
  // sweep per sub-step (printed: docs/mujoco_bridge.md has the figures).
  for (const SimulationOptions& o : {solver(SolverType::pgs, 64, 1), solver(SolverType::pgs, 4, 1),
                                     solver(SolverType::tgs, 4, 1)}) {
    double worst = 0.0, worst_literal = 0.0;
    for (const GridPoint& g : grid()) {
      if (g.zeta != 0.7 && g.s != 0.5) continue;  // a cross through the grid
      Simulation sim(model, o);
      sim.set_q(q0);
      for (int d = 0; d < model->nv; ++d) {
        // MuJoCo gets neither the URDF's <dynamics> friction nor its velocity limits.
        sim.set_joint_friction(d, JointFriction{});
        sim.set_max_joint_velocity(d, kInf);
        const double kp = g.s * m[d] / (kDt * kDt);
        sim.set_drive(
            d, Drive{DriveType::force, kp, 2.0 * g.zeta * std::sqrt(kp * m[d]), kInf, 0.0, 0.0});
      }
      const Response translated = step_response(sim, DriveMapping::translated, step, 240);
      const Response literal = step_response(sim, DriveMapping::literal, step, 240);
      const std::string label = std::string(to_string(o.solver)) + " " +
                                std::to_string(o.position_iterations) + "/1 s " +
                                std::to_string(g.s) + " zeta " + std::to_string(g.zeta);
      for (int d = 0; d < model->nv; ++d) {
        if (o.position_iterations == 64) {
          EXPECT_LE(translated.worst[d], 1e-6) << label << " joint " << d;
        } else if (o.solver == SolverType::pgs && g.s <= 0.5) {
          EXPECT_LE(translated.worst[d], 0.05) << label << " joint " << d;
        }
      }
      worst = std::max(worst, translated.worst.maxCoeff());
      worst_literal = std::max(worst_literal, literal.worst.maxCoeff());
      std::printf("[ bridge   ] arm %s: worst joint translated %.2e, literal %.2e\n", label.c_str(),
                  translated.worst.maxCoeff(), literal.worst.maxCoeff());
    }
    std::printf("[ bridge   ] arm %s %d/1: worst translated %.2e, worst literal %.2e of the step\n",
                to_string(o.solver), o.position_iterations, worst, worst_literal);
  }
}

TEST(MujocoBridge, LiteralCopyPastTheLimitDivergesInMujocoAndTheMapSaysSo) {
  const auto model = test::make_slider(1.0, Vec3(1, 0, 0), Vec3(0, 0, -9.81));
  Simulation sim(model, solver(SolverType::pgs, 4, 1));
  const double kp = 6.0 / (kDt * kDt);  // kp dt^2 / m = 6, past Euler's 4
  const Drive drive{DriveType::force, kp, 0.1 * std::sqrt(kp), kInf, 0.0, 0.0};
  sim.set_drive(0, drive);
  EXPECT_FALSE(
      stable(mujoco_step_map(1.0, literal_mujoco_drive(1.0, drive, MujocoIntegrator::euler), kDt)));
  EXPECT_FALSE(step_response(sim, DriveMapping::literal, 0.1, 300).finite);
  const Response translated = step_response(sim, DriveMapping::translated, 0.1, 300);
  EXPECT_LE(translated.worst[0], 1e-9);
}

// MuJoCo's own model of MJCF text (through its virtual file system); nullptr and its message
// when it refuses the text.
mjModel* load_in_mujoco(const std::string& xml, std::string& message) {
  std::array<char, 1000> error{};
  auto vfs = std::make_unique<mjVFS>();
  mj_defaultVFS(vfs.get());
  if (mj_makeEmptyFileVFS(vfs.get(), "a.xml", static_cast<int>(xml.size())) != 0) return nullptr;
  std::copy(xml.begin(), xml.end(), static_cast<char*>(vfs->filedata[0]));
  mjModel* m = mj_loadXML("a.xml", vfs.get(), error.data(), 1000);
  mj_deleteVFS(vfs.get());
  message = error.data();
  return m;
}

TEST(MujocoBridge, ExportLoadsWithItsSettings) {
  const UrdfRobot robot = load_urdf(std::string(FEATHERDRIVE_SOURCE_DIR) + "/examples/arm7.urdf");
  Simulation sim(robot.model, solver(SolverType::tgs, 4, 1));
  sim.set_drive(0, Drive{DriveType::force, 1e4, 50.0, 20.0, 0.0, 0.0});
  sim.set_joint_limits(1, -1.0, 1.5);
  const MjcfExport e = export_mjcf(sim);
  ASSERT_EQ(mujoco_compile_error(e.xml), "");
  std::string error;
  mjModel* m = load_in_mujoco(e.xml, error);
  ASSERT_NE(m, nullptr) << error;
  EXPECT_EQ(m->opt.integrator, mjINT_EULER);
  EXPECT_DOUBLE_EQ(m->opt.timestep, kDt / 4);  // TGS's 4 sub-steps
  EXPECT_TRUE(m->opt.disableflags & mjDSBL_CONTACT);
  ASSERT_EQ(m->nu, 1);
  EXPECT_EQ(m->actuator_gainprm[0], 1e4);
  EXPECT_EQ(m->actuator_biasprm[1], -1e4);
  EXPECT_EQ(m->actuator_forcerange[1], 20.0);
  EXPECT_NEAR(m->dof_damping[0], 50.0 + kDt / 4 * 1e4, 1e-9);
  EXPECT_EQ(m->jnt_limited[1], 1);
  EXPECT_EQ(m->jnt_range[2], -1.0);
  EXPECT_EQ(m->jnt_range[3], 1.5);
  mj_deleteModel(m);
}

}  // namespace
}  // namespace featherdrive

namespace featherdrive {
namespace {

// translate --to physx: an MJCF slider with a position actuator and joint damping becomes a
// scene whose featherdrive run reproduces MuJoCo's own run of the MJCF (ctrl = the target).
TEST(MujocoBridge, MjcfDrivesTranslateToAScene) {
  namespace fs = std::filesystem;
  const fs::path dir =
      fs::temp_directory_path() / ("featherdrive_bridge_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const double kp = 900.0;
  for (double damping : {40.0, 5.0}) {  // above and below dt kp = 15
    const fs::path xml = dir / "slider.xml";
    {
      std::ofstream out(xml);
      out << "<mujoco><option timestep=\"0.016666666666666666\" gravity=\"0 0 -9.81\"/>"
             "<worldbody><body name=\"cart\"><joint name=\"slide\" type=\"slide\" axis=\"1 0 0\""
             " damping=\""
          << damping
          << "\" armature=\"0.1\"/>"
             "<inertial pos=\"0 0 0\" mass=\"2\" diaginertia=\"0.01 0.01 0.01\"/></body>"
             "</worldbody><actuator><position joint=\"slide\" kp=\""
          << kp
          << "\"/></actuator>"
             "</mujoco>\n";
    }
    const fs::path scene_path = dir / "scene.yaml";
    SimulationOptions options;  // PGS 4/1
    const SceneTranslation t = translate_mjcf_to_scene(xml, scene_path, options, 120);
    ASSERT_EQ(t.joints.size(), 1u);
    const PhysxTranslation& p = t.joints[0].physx;
    EXPECT_NEAR(t.joints[0].effective_inertia, 2.1, 1e-12);  // mass + armature
    if (damping < kp * t.dt) {
      EXPECT_FALSE(p.reproducible);
      EXPECT_NE(p.note.find("not reproducible"), std::string::npos) << p.note;
      continue;
    }
    ASSERT_TRUE(p.exact) << p.note;
    EXPECT_NEAR(p.drive.damping, damping - t.dt * kp, 1e-9);
    {
      std::ofstream out(scene_path);
      out << t.yaml;
    }
    const Scene scene = load_scene(scene_path);
    Simulation sim = make_simulation(scene);
    std::array<char, 1000> error{};
    mjModel* m = mj_loadXML(xml.c_str(), nullptr, error.data(), 1000);
    ASSERT_NE(m, nullptr) << error.data();
    mjData* d = mj_makeData(m);
    const double target = 0.1;
    Drive drive = sim.drive(0);
    drive.target_position = target;
    sim.set_drive(0, drive);
    d->ctrl[0] = target;
    double worst = 0.0;
    for (int k = 0; k < scene.steps; ++k) {
      mj_step(m, d);
      sim.step();
      worst = std::max(worst, std::abs(sim.q()[0] - d->qpos[0]));
    }
    EXPECT_LE(worst, 1e-12 * target) << t.yaml;
    std::printf("[ bridge   ] MJCF -> scene, PGS 4/1: largest |q_fd - q_mj| %.2e of the step\n",
                worst / target);
    mj_deleteData(d);
    mj_deleteModel(m);
  }
  std::error_code ignored;
  fs::remove_all(dir, ignored);
}

}  // namespace
}  // namespace featherdrive

namespace featherdrive {
namespace {

mjModel* load_text(const std::string& xml) {
  auto vfs = std::make_unique<mjVFS>();
  mj_defaultVFS(vfs.get());
  EXPECT_EQ(mj_makeEmptyFileVFS(vfs.get(), "a.xml", static_cast<int>(xml.size())), 0);
  std::copy(xml.begin(), xml.end(), static_cast<char*>(vfs->filedata[0]));
  std::array<char, 1000> error{};
  mjModel* m = mj_loadXML("a.xml", vfs.get(), error.data(), 1000);
  mj_deleteVFS(vfs.get());
  EXPECT_NE(m, nullptr) << error.data();
  return m;
}

// MuJoCo's humanoid has bodies with two and three joints, which load_mjcf splits into massless
// links: the export writes each such chain back as one body with its joints (MuJoCo refuses a
// massless moving body). Against MuJoCo's own humanoid.xml: the same bodies and joints, the same
// body poses relative to the torso at a configuration away from qpos0; and MuJoCo's passive
// swing of the export equals featherdrive's (both semi-implicit Euler, no drives, no rows).
TEST(MujocoBridge, BodiesWithSeveralJointsExportAsOneBody) {
  const std::string source = "/usr/share/mujoco/model/humanoid/humanoid.xml";
  if (!std::filesystem::exists(source)) GTEST_SKIP() << source << " is not installed";
  UrdfOptions fixed;
  const MjcfRobot robot = load_mjcf(source, fixed);
  const Model& model = *robot.model;
  ASSERT_GT(model.num_links(), 14);  // the helper links are there
  SimulationOptions o;
  o.dt = 0.002;
  Simulation sim(robot.model, o);
  VecX q = robot.q0;
  for (int d = 0; d < model.nv; ++d) {
    q[d] = 0.3 * std::sin(1.7 * d + 0.4);
    sim.set_joint_friction(d, JointFriction{});  // MuJoCo's damping is a passive force
    sim.set_joint_limits(d, -kInf, kInf);        // and its limits soft ones
  }
  sim.set_q(q);
  const MjcfExport e = export_mjcf(sim);
  mjModel* original = load_text(read_input_file(source));
  mjModel* exported = load_text(e.xml);
  ASSERT_TRUE(original && exported);
  EXPECT_EQ(exported->nbody, original->nbody);
  ASSERT_EQ(exported->njnt, original->njnt - 1);  // the torso's free joint: welded here
  for (int j = 0; j < exported->njnt; ++j)
    EXPECT_STREQ(mj_id2name(exported, mjOBJ_JOINT, j), mj_id2name(original, mjOBJ_JOINT, j + 1));
  mjData* d0 = mj_makeData(original);
  mjData* d1 = mj_makeData(exported);
  std::copy(q.data(), q.data() + model.nq, d0->qpos + 7);  // after the free joint's qpos
  std::copy(q.data(), q.data() + model.nq, d1->qpos);
  mj_kinematics(original, d0);
  mj_kinematics(exported, d1);
  const int torso0 = mj_name2id(original, mjOBJ_BODY, "torso");
  const int torso1 = mj_name2id(exported, mjOBJ_BODY, "torso");
  auto relative = [](const mjData* d, int torso, int b) {
    const Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> R(d->xmat + 9 * torso);
    return Vec3(R.transpose() * (Vec3(d->xpos + 3 * b) - Vec3(d->xpos + 3 * torso)));
  };
  for (int b = 1; b < original->nbody; ++b) {
    const char* name = mj_id2name(original, mjOBJ_BODY, b);
    const int b1 = mj_name2id(exported, mjOBJ_BODY, name);
    ASSERT_GE(b1, 0) << name;
    // The export's body frame is MuJoCo's body frame shifted to the first joint's anchor.
    const Vec3 anchor(original->jnt_pos + 3 * original->body_jntadr[b]);
    const Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> R0(d0->xmat + 9 * b);
    const Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> Rt(d0->xmat + 9 * torso0);
    const Vec3 expected =
        relative(d0, torso0, b) +
        (original->body_jntnum[b] > 0 && b != torso0 ? Vec3(Rt.transpose() * R0 * anchor)
                                                     : Vec3::Zero());
    EXPECT_LT((relative(d1, torso1, b1) - expected).norm(), 1e-12) << name;
  }
  // The passive swing from q over 200 steps.
  MujocoRun mj(e);
  mj.set_state(sim.q(), sim.qd());
  double worst = 0.0, scale = 0.0;
  for (int k = 0; k < 200; ++k) {
    mj.step(sim);
    sim.step();
    worst = std::max(worst, (sim.q() - mj.q()).cwiseAbs().maxCoeff());
    scale = std::max(scale, (sim.q() - q).cwiseAbs().maxCoeff());
  }
  EXPECT_FALSE(mj.diverged());
  EXPECT_GT(scale, 0.1);  // it swings
  EXPECT_LT(worst, 1e-9 * scale);
  std::printf("[ bridge   ] humanoid's passive swing: largest |q_fd - q_mj| %.2e of %.2e\n", worst,
              scale);
  mj_deleteData(d0);
  mj_deleteData(d1);
  mj_deleteModel(original);
  mj_deleteModel(exported);
}

// ---- The URDF's visual and collision geometry in the export ----

// A row-major 3x3 of MuJoCo's.
Mat3 mj_mat(const double* m) {
  return Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(m);
}

// The three corners of a binary STL's triangle k (its header: 80 bytes and a count; each triangle
// a normal, three corners and 2 bytes).
std::array<Vec3, 3> stl_triangle(const std::string& path, int k) {
  std::ifstream in(path, std::ios::binary);
  in.seekg(84 + 50 * k + 12);
  std::array<Vec3, 3> corners;
  for (Vec3& c : corners) {
    float v[3];
    in.read(reinterpret_cast<char*>(v), sizeof v);
    c = Vec3(v[0], v[1], v[2]);
  }
  EXPECT_TRUE(in.good()) << path;
  return corners;
}

struct GeomCheck {
  int geoms = 0, meshes = 0;
  double worst = 0.0;  ///< the largest position error of a geom or mesh corner
};

// Each of the URDF's <visual> and <collision> elements (read here with urdfdom, .dae meshes
// left out) against the exported geom of its name in `m` at featherdrive's configuration q: its
// type and size, and its pose = the URDF link's frame in featherdrive (merged links: the frame
// they keep) * the element's <origin>. MuJoCo moves a mesh's frame to its centroid, so a mesh is
// checked by the world position of corners of its STL's triangles among the compiled vertices.
GeomCheck check_geoms(const UrdfRobot& robot, const std::string& urdf_text,
                      const std::map<std::string, std::string>& packages, const mjModel* m,
                      const VecX& q) {
  const urdf::ModelInterfaceSharedPtr urdf_model = urdf::parseURDF(urdf_text);
  EXPECT_TRUE(urdf_model);
  const Model& model = *robot.model;
  Data data(model);
  forward_kinematics(model, data, q);
  mjData* d = mj_makeData(m);
  std::copy(q.data(), q.data() + m->nq, d->qpos);
  mj_forward(m, d);
  GeomCheck check;
  for (const auto& [name, link] : urdf_model->links_) {
    const NamedFrame frame = model.frame(name);
    const Mat3 R = frame_rotation(model, data, frame);
    const Vec3 p = frame_position(model, data, frame);
    auto check_one = [&](const std::string& geom_name, const urdf::Pose& origin,
                         const urdf::Geometry& g) {
      if (g.type == urdf::Geometry::MESH &&
          static_cast<const urdf::Mesh&>(g).filename.find(".dae") != std::string::npos)
        return;
      const int id = mj_name2id(m, mjOBJ_GEOM, geom_name.c_str());
      ASSERT_GE(id, 0) << geom_name;
      ++check.geoms;
      const urdf::Rotation& r = origin.rotation;
      const Mat3 R_geom = R * Quat(r.w, r.x, r.y, r.z).toRotationMatrix();
      const Vec3 p_geom = p + R * Vec3(origin.position.x, origin.position.y, origin.position.z);
      const double* size = m->geom_size + 3 * id;
      switch (g.type) {
        case urdf::Geometry::BOX: {
          const urdf::Vector3& dim = static_cast<const urdf::Box&>(g).dim;
          EXPECT_EQ(m->geom_type[id], mjGEOM_BOX) << geom_name;
          EXPECT_EQ(Vec3(size[0], size[1], size[2]), Vec3(dim.x / 2, dim.y / 2, dim.z / 2));
          break;
        }
        case urdf::Geometry::CYLINDER: {
          const auto& c = static_cast<const urdf::Cylinder&>(g);
          EXPECT_EQ(m->geom_type[id], mjGEOM_CYLINDER) << geom_name;
          EXPECT_EQ(size[0], c.radius) << geom_name;
          EXPECT_EQ(size[1], c.length / 2) << geom_name;
          break;
        }
        case urdf::Geometry::SPHERE:
          EXPECT_EQ(m->geom_type[id], mjGEOM_SPHERE) << geom_name;
          EXPECT_EQ(size[0], static_cast<const urdf::Sphere&>(g).radius) << geom_name;
          break;
        case urdf::Geometry::MESH: {
          const auto& mesh = static_cast<const urdf::Mesh&>(g);
          EXPECT_EQ(m->geom_type[id], mjGEOM_MESH) << geom_name;
          ++check.meshes;
          std::string file = mesh.filename;
          if (file.rfind("package://", 0) == 0) {
            const std::string rest = file.substr(10);
            const size_t slash = rest.find('/');
            file = packages.at(rest.substr(0, slash)) + rest.substr(slash);
          } else {
            file = (std::filesystem::path(robot.path).parent_path() / file).string();
          }
          const int mesh_id = m->geom_dataid[id];
          const Mat3 R_mj = mj_mat(d->geom_xmat + 9 * id);
          const Vec3 p_mj(d->geom_xpos + 3 * id);
          const Vec3 scale(mesh.scale.x, mesh.scale.y, mesh.scale.z);
          for (int t : {0, 1}) {
            for (const Vec3& corner : stl_triangle(file, t)) {
              const Vec3 expected = p_geom + R_geom * scale.cwiseProduct(corner);
              double nearest = kInf;
              for (int v = m->mesh_vertadr[mesh_id];
                   v < m->mesh_vertadr[mesh_id] + m->mesh_vertnum[mesh_id]; ++v) {
                const float* x = m->mesh_vert + 3 * v;
                const Vec3 world = p_mj + R_mj * Vec3(x[0], x[1], x[2]);
                nearest = std::min(nearest, (world - expected).norm());
              }
              check.worst = std::max(check.worst, nearest);
            }
          }
          return;  // the geom's own frame is the mesh's centroid frame
        }
      }
      check.worst = std::max(check.worst, (Vec3(d->geom_xpos + 3 * id) - p_geom).norm());
      EXPECT_LT((mj_mat(d->geom_xmat + 9 * id) - R_geom).cwiseAbs().maxCoeff(), 1e-12)
          << geom_name;
      // Visuals in group 1, collisions in group 0; neither collides.
      const bool visual = geom_name.find(":visual") != std::string::npos;
      EXPECT_EQ(m->geom_group[id], visual ? 1 : 0) << geom_name;
      EXPECT_EQ(m->geom_contype[id], 0) << geom_name;  // the model's shapes carry contacts
    };
    for (size_t k = 0; k < link->visual_array.size(); ++k)
      check_one(name + ":visual" + std::to_string(k), link->visual_array[k]->origin,
                *link->visual_array[k]->geometry);
    for (size_t k = 0; k < link->collision_array.size(); ++k)
      check_one(name + ":collision" + std::to_string(k), link->collision_array[k]->origin,
                *link->collision_array[k]->geometry);
  }
  mj_deleteData(d);
  return check;
}

// The export of `robot` with its geometry (geometry: true) or without, compiled by MuJoCo.
struct GeomExport {
  MjcfExport mjcf;
  std::vector<std::string> warnings;
  mjModel* m = nullptr;
};

// The robot with a drive on every dof towards 0.2.
Simulation driven(const UrdfRobot& robot) {
  Simulation sim(robot.model, SimulationOptions{});
  for (int dof = 0; dof < robot.model->nv; ++dof) {
    Drive drive;
    drive.type = DriveType::force;
    drive.stiffness = 400.0;
    drive.damping = 40.0;
    drive.target_position = 0.2;
    sim.set_drive(dof, drive);
  }
  return sim;
}

GeomExport export_robot(const UrdfRobot& robot, const std::map<std::string, std::string>& packages,
                        bool geometry) {
  const Simulation sim = driven(robot);
  GeomExport out;
  MjcfExportOptions options;
  if (geometry) options.geometry = mjcf_geometry(robot, packages, out.warnings);
  out.mjcf = export_mjcf(sim, options);
  out.m = load_text(out.mjcf.xml);
  return out;
}

// The geoms leave MuJoCo's bodies and their motion as they are without them.
void expect_same_dynamics(const UrdfRobot& robot, const GeomExport& with, const GeomExport& without) {
  ASSERT_EQ(with.m->nbody, without.m->nbody);
  EXPECT_EQ(without.m->ngeom, 0);
  auto same = [](const double* a, const double* b, int n) { return std::equal(a, a + n, b); };
  EXPECT_TRUE(same(with.m->body_mass, without.m->body_mass, with.m->nbody));
  EXPECT_TRUE(same(with.m->body_inertia, without.m->body_inertia, 3 * with.m->nbody));
  EXPECT_TRUE(same(with.m->body_ipos, without.m->body_ipos, 3 * with.m->nbody));
  EXPECT_TRUE(same(with.m->body_iquat, without.m->body_iquat, 4 * with.m->nbody));
  const Simulation sim = driven(robot);
  MujocoRun a(with.mjcf), b(without.mjcf);
  a.set_state(sim.q(), sim.qd());
  b.set_state(sim.q(), sim.qd());
  for (int k = 0; k < 30; ++k) {
    a.step(sim);
    b.step(sim);
  }
  EXPECT_GT((a.q() - sim.q()).norm(), 1e-3);  // it moved
  EXPECT_EQ(a.q(), b.q());
}

TEST(MujocoBridge, UrdfGeometryExportsAsGeoms) {
  const std::string path = FEATHERDRIVE_SOURCE_DIR "/tests/data/geometry.urdf";
  const UrdfRobot robot = load_urdf(path);
  const GeomExport with = export_robot(robot, {}, true);
  const GeomExport without = export_robot(robot, {}, false);
  ASSERT_TRUE(with.m && without.m);
  EXPECT_TRUE(with.warnings.empty());
  // base: a box visual and collision; link1: a cylinder of each; tool (merged into link1): a
  // sphere visual.
  EXPECT_EQ(with.m->ngeom, 5);
  const int tool = mj_name2id(with.m, mjOBJ_GEOM, "tool:visual0");
  ASSERT_GE(tool, 0);
  EXPECT_EQ(with.m->geom_bodyid[tool], mj_name2id(with.m, mjOBJ_BODY, "link1"));
  EXPECT_EQ(with.m->geom_size[3 * tool], 0.06);
  const int box = mj_name2id(with.m, mjOBJ_GEOM, "base:visual0");
  ASSERT_GE(box, 0);
  EXPECT_EQ(Vec3(with.m->geom_size + 3 * box), Vec3(0.2, 0.15, 0.05));
  const std::string text = read_input_file(path);
  for (const double angle : {0.0, 0.7}) {
    const GeomCheck check =
        check_geoms(robot, text, {}, with.m, VecX::Constant(robot.model->nq, angle));
    EXPECT_EQ(check.geoms, 5);
    EXPECT_LT(check.worst, 1e-12);
  }
  expect_same_dynamics(robot, with, without);
  mj_deleteModel(with.m);
  mj_deleteModel(without.m);
}

// DART's KR5 (STL meshes relative to the URDF) and WAM (package:// meshes: COLLADA visuals left
// out with a warning, STL collisions kept).
TEST(MujocoBridge, UrdfMeshesExportAsMeshGeoms) {
  const std::string dart = "/usr/share/doc/dart/data/urdf/";
  const std::string kr5 = dart + "KR5/KR5 sixx R650.urdf", wam = dart + "wam/wam.urdf";
  if (!std::filesystem::exists(kr5) || !std::filesystem::exists(wam))
    GTEST_SKIP() << "DART's data are not installed";
  const std::map<std::string, std::string> packages{{"herb_description", dart + "wam"}};
  for (const std::string& path : {kr5, wam}) {
    SCOPED_TRACE(path);
    const UrdfRobot robot = load_urdf(path);
    const GeomExport with = export_robot(robot, packages, true);
    const GeomExport without = export_robot(robot, packages, false);
    ASSERT_TRUE(with.m && without.m);
    const std::string text = read_input_file(path);
    const GeomCheck check = check_geoms(robot, text, packages, with.m,
                                        VecX::LinSpaced(robot.model->nq, -0.4, 0.6));
    EXPECT_EQ(with.m->ngeom, check.geoms);  // every geom is one of the URDF's
    EXPECT_GT(check.meshes, 6);
    EXPECT_LT(check.worst, 1e-5);  // MuJoCo keeps vertices as floats
    std::printf("[ bridge   ] %s: %d geoms (%d meshes), largest position error %.1e\n",
                robot.name.c_str(), check.geoms, check.meshes, check.worst);
    // WAM: its 8 visuals are COLLADA, named on one warning line.
    if (path == wam) {
      ASSERT_EQ(with.warnings.size(), 1u);
      EXPECT_NE(with.warnings[0].find("8 COLLADA (.dae) meshes left out"), std::string::npos)
          << with.warnings[0];
    } else {
      EXPECT_TRUE(with.warnings.empty());
    }
    expect_same_dynamics(robot, with, without);
    mj_deleteModel(with.m);
    mj_deleteModel(without.m);
  }
}

// DART's Atlas: COLLADA visuals, STL collisions and shapes; it exports and MuJoCo loads it.
TEST(MujocoBridge, AtlasExportsWithItsCollisionMeshes) {
  const std::string path = "/usr/share/doc/dart/data/sdf/atlas/atlas_v3_no_head.urdf";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << path << " is not installed";
  const UrdfRobot robot = load_urdf(path);
  const GeomExport with = export_robot(robot, {}, true);
  ASSERT_TRUE(with.m);
  const std::string text = read_input_file(path);
  int collada = 0;  // as urdfdom reads the file (some of its elements are commented out)
  const urdf::ModelInterfaceSharedPtr urdf_model = urdf::parseURDF(text);
  ASSERT_TRUE(urdf_model);
  auto is_collada = [](const urdf::GeometrySharedPtr& g) {
    return g->type == urdf::Geometry::MESH &&
           static_cast<const urdf::Mesh&>(*g).filename.find(".dae") != std::string::npos;
  };
  for (const auto& [name, link] : urdf_model->links_) {
    for (const urdf::VisualSharedPtr& v : link->visual_array) collada += is_collada(v->geometry);
    for (const urdf::CollisionSharedPtr& c : link->collision_array)
      collada += is_collada(c->geometry);
  }
  EXPECT_GT(collada, 20);
  ASSERT_EQ(with.warnings.size(), 1u);
  EXPECT_NE(with.warnings[0].find(std::to_string(collada) + " COLLADA (.dae) meshes left out"),
            std::string::npos)
      << with.warnings[0];
  const GeomCheck check = check_geoms(robot, text, {}, with.m, VecX::Zero(robot.model->nq));
  EXPECT_EQ(with.m->ngeom, check.geoms);
  EXPECT_GT(check.meshes, 20);
  EXPECT_LT(check.worst, 1e-5);
  mj_deleteModel(with.m);
}

}  // namespace
}  // namespace featherdrive

namespace featherdrive {
namespace {

// The gripper's URDF mimic tags (joint = multiplier leader + offset) are MuJoCo's joint
// equalities joint1 = c0 + c1 joint2: c0 = offset, c1 = multiplier, read off the URDF's text; the
// exported file loads back with the URDF's rows.
TEST(MujocoBridge, MimicJointsExportAsJointEqualities) {
  const Scene scene =
      load_scene(FEATHERDRIVE_SOURCE_DIR "/tests/data/composition/mimic_gripper.yaml");
  const Simulation sim = make_simulation(scene);
  const MjcfExport e = export_mjcf(sim);
  std::string error;
  mjModel* m = load_in_mujoco(e.xml, error);
  ASSERT_NE(m, nullptr) << error;
  struct Tag {
    const char *joint, *leader;
    double multiplier, offset;
  };
  const std::array<Tag, 2> tags{{{"right_finger", "left_finger", -1.0, 0.0},
                                 {"knuckle", "left_finger", 12.5, -0.1}}};
  ASSERT_EQ(m->neq, 2);
  for (int i = 0; i < m->neq; ++i) {
    const Tag& tag = tags[static_cast<size_t>(i)];
    EXPECT_EQ(m->eq_type[i], mjEQ_JOINT);
    EXPECT_EQ(m->eq_obj1id[i], mj_name2id(m, mjOBJ_JOINT, tag.joint)) << tag.joint;
    EXPECT_EQ(m->eq_obj2id[i], mj_name2id(m, mjOBJ_JOINT, tag.leader)) << tag.joint;
    const mjtNum* c = m->eq_data + mjNEQDATA * i;
    EXPECT_EQ(c[0], tag.offset) << tag.joint;
    EXPECT_EQ(c[1], tag.multiplier) << tag.joint;
    for (int k = 2; k < 5; ++k) EXPECT_EQ(c[k], 0.0) << tag.joint;
    // a_ref = -k r - b v with k = 1 / h^2, b = 1 / h: an error is gone after one Euler step.
    const double h = m->opt.timestep;
    EXPECT_DOUBLE_EQ(m->eq_solref[2 * i], -1.0 / (h * h));
    EXPECT_DOUBLE_EQ(m->eq_solref[2 * i + 1], -1.0 / h);
  }
  mj_deleteModel(m);

  const MjcfRobot back = parse_mjcf(e.xml, "gripper.xml");
  ASSERT_EQ(back.mimic_joints.size(), tags.size());
  for (size_t i = 0; i < tags.size(); ++i) {
    const MimicJoint& row = back.mimic_joints[i];
    EXPECT_EQ(row.dof_a, back.model->dof_index(tags[i].joint));
    EXPECT_EQ(row.dof_b, back.model->dof_index(tags[i].leader));
    EXPECT_EQ(row.gear_ratio, -tags[i].multiplier);
    EXPECT_EQ(row.offset, -tags[i].offset);
    EXPECT_EQ(row.dof_a, scene.robot.mimic_joints[i].dof_a);
    EXPECT_EQ(row.dof_b, scene.robot.mimic_joints[i].dof_b);
  }
}

// Only q1 = c0 + c1 q2 between hinges and slides is a mimic row; other equalities stay refused.
TEST(MujocoBridge, OtherEqualitiesStayRefused) {
  const std::string bodies =
      R"(<mujoco><worldbody><body name="a"><joint name="j"/><geom size=".1"/>
      <body name="b" pos="0 0 1"><joint name="k"/><geom size=".1"/></body></body></worldbody>)";
  const auto error = [&](const std::string& equality) {
    try {
      parse_mjcf(bodies + "<equality>" + equality + "</equality></mujoco>", "eq.xml");
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("(no error)");
  };
  EXPECT_EQ(error(R"(<joint name="q" joint1="j" joint2="k" polycoef="0 1 0.5 0 0"/>)"),
            "eq.xml: <equality><joint> 'q' (1 in all): equality constraints are not supported");
  EXPECT_EQ(error(R"(<joint name="fix" joint1="j"/>)"),
            "eq.xml: <equality><joint> 'fix' (1 in all): equality constraints are not supported");
  EXPECT_EQ(error(R"(<joint name="z" joint1="j" joint2="k" polycoef="0 0 0 0 0"/>)"),
            "eq.xml: <equality><joint> 'z' (1 in all): equality constraints are not supported");
  EXPECT_EQ(error(R"(<joint name="off" joint1="j" joint2="k" active="false"/>)"),
            "eq.xml: <equality><joint> 'off' (1 in all): equality constraints are not supported");
  EXPECT_EQ(error(R"(<joint joint1="j" joint2="k"/><connect name="c" body1="a" body2="b"
      anchor="0 0 0"/>)"),
            "eq.xml: <equality><connect> 'c' (2 in all): equality constraints are not supported");
  const MjcfRobot robot = parse_mjcf(
      bodies + R"(<equality><joint joint1="k" joint2="j" polycoef="0.25 -2 0 0 0"/></equality>
      </mujoco>)", "eq.xml");
  ASSERT_EQ(robot.mimic_joints.size(), 1u);
  EXPECT_EQ(robot.mimic_joints[0].dof_a, 1);
  EXPECT_EQ(robot.mimic_joints[0].dof_b, 0);
  EXPECT_EQ(robot.mimic_joints[0].gear_ratio, 2.0);  // k - (-2) j - 0.25 = 0
  EXPECT_EQ(robot.mimic_joints[0].offset, -0.25);
  // MuJoCo's law is relative to the refs: k - 0.5 = 0.25 - 2 (j - 0.25), so k + 2 j - 1.25 = 0.
  const MjcfRobot refs = parse_mjcf(
      R"(<mujoco><compiler angle="radian"/><worldbody><body name="a">
      <joint name="j" ref="0.25"/><geom size=".1"/><body name="b" pos="0 0 1">
      <joint name="k" ref="0.5"/><geom size=".1"/></body></body></worldbody>
      <equality><joint joint1="k" joint2="j" polycoef="0.25 -2 0 0 0"/></equality></mujoco>)",
      "refs.xml");
  ASSERT_EQ(refs.mimic_joints.size(), 1u);
  EXPECT_EQ(refs.mimic_joints[0].gear_ratio, 2.0);
  EXPECT_DOUBLE_EQ(refs.mimic_joints[0].offset, -1.25);
}

// Joint springs (docs/math/joint_constraints.md, JS1-JS4) export as MuJoCo's stiffness and
// springref with their damper in the joint's damping: MuJoCo's passive spring is explicit and
// featherdrive's row implicit, so both are first-order approximations of one ODE and part by
// O(dt): a three-link chain without gravity swinging on its springs, 0.3 s, differs about ten
// times less at dt = 1e-4 than at 1e-3, and by less than 1e-3 rad there.
TEST(MujocoBridge, JointSpringsExportAsStiffnessAndConvergeWithMujocoAsDtShrinks) {
  auto model = test::make_planar_chain(3, 1.0, 0.4, Vec3::Zero());
  std::vector<double> apart;
  for (const double dt : {1e-3, 1e-4}) {
    SimulationOptions o;
    o.dt = dt;
    o.position_iterations = 8;
    Simulation sim(model, o);
    for (int d = 0; d < model->nv; ++d) {
      const double spring[] = {20.0 + 10.0 * d, 0.05, 0.3 - 0.2 * d};
      sim.set_row_parameters("joint_spring", d, spring);
    }
    sim.set_q(VecX::Constant(model->nv, -0.2));
    const MjcfExport mjcf = export_mjcf(sim);
    EXPECT_NE(mjcf.xml.find("stiffness=\"20\" springref=\"0.3\""), std::string::npos);
    MujocoRun mj(mjcf);
    mj.set_state(sim.q(), sim.qd());
    double worst = 0.0;
    for (int k = 0; k < static_cast<int>(std::lround(0.3 / dt)); ++k) {
      mj.step(sim);
      sim.step();
      worst = std::max(worst, (sim.q() - mj.q()).cwiseAbs().maxCoeff());
    }
    ASSERT_FALSE(mj.diverged());
    apart.push_back(worst);
    std::printf("joint springs, dt %g: largest |q - q_MuJoCo| %.2e rad over 0.3 s\n", dt, worst);
  }
  EXPECT_LT(apart[1], 0.2 * apart[0]);
  EXPECT_LT(apart[1], 1e-3);
  EXPECT_GT(apart[0], 0.0);
}

}  // namespace
}  // namespace featherdrive
