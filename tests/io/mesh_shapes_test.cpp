// Collision meshes as convex hulls (issue 34; docs/math/contact.md, G3): MuJoCo's compiler reads
// the file and computes the hull. A cube written as a binary STL rests exactly as the box
// primitive of the same size (same heights and impulses: the hull's corners are the box's), bad
// meshes are refused in one line naming the file, link and value, MJCF mesh geoms carry the same
// hull, and DART's robots import with every collision as a shape: Atlas, held by PD drives,
// stands on its feet' hulls carrying its weight.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "featherdrive/algorithm/data.hpp"
#include "featherdrive/algorithm/floating_base.hpp"
#include "featherdrive/algorithm/kinematics.hpp"
#include "featherdrive/io/error.hpp"
#include "featherdrive/io/mjcf.hpp"
#include "featherdrive/io/scene.hpp"
#include "featherdrive/io/urdf.hpp"
#include "featherdrive/sim/simulation.hpp"

namespace featherdrive {
namespace {

namespace fs = std::filesystem;

// A folder of its own per test process.
fs::path temp_folder() {
  const fs::path dir =
      fs::temp_directory_path() / ("featherdrive-meshes-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  return dir;
}

// A box of half extents h as a binary STL (12 triangles, outward winding).
void write_box_stl(const fs::path& path, const Vec3& h) {
  std::ofstream out(path, std::ios::binary);
  const char header[80] = {};
  out.write(header, 80);
  const std::uint32_t count = 12;
  out.write(reinterpret_cast<const char*>(&count), 4);
  for (int axis = 0; axis < 3; ++axis)
    for (const int sign : {-1, 1}) {
      const int u = (axis + 1) % 3, w = (axis + 2) % 3;
      Vec3 quad[4];
      const int corners[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
      for (int k = 0; k < 4; ++k) {
        Vec3 p = Vec3::Zero();
        p[axis] = sign * h[axis];
        p[u] = corners[k][0] * h[u];
        p[w] = corners[k][1] * h[w];
        quad[sign > 0 ? k : 3 - k] = p;
      }
      for (const auto& tri : {std::array<int, 3>{0, 1, 2}, std::array<int, 3>{0, 2, 3}}) {
        const float normal[3] = {0, 0, 0};
        out.write(reinterpret_cast<const char*>(normal), 12);
        for (int v : tri) {
          const float x[3] = {static_cast<float>(quad[v].x()), static_cast<float>(quad[v].y()),
                              static_cast<float>(quad[v].z())};
          out.write(reinterpret_cast<const char*>(x), 12);
        }
        const char attribute[2] = {};
        out.write(attribute, 2);
      }
    }
}

std::string one_link_urdf(const std::string& geometry) {
  return "<robot name='r'><link name='body'><inertial><mass value='2'/><inertia ixx='0.02' "
         "ixy='0' ixz='0' iyy='0.03' iyz='0' izz='0.04'/></inertial><collision name='c'>"
         "<origin xyz='0.01 0 0' rpy='0 0 0.2'/><geometry>" +
         geometry + "</geometry></collision></link></robot>";
}

Simulation dropped(const std::shared_ptr<const Model>& model, SolverType solver) {
  SimulationOptions o;
  o.dt = 0.01;
  o.solver = solver;
  o.position_iterations = 50;
  Simulation sim(model, o);
  Ground g;
  g.enabled = true;
  sim.set_ground(g);
  VecX q = sim.q(), qd = sim.qd();
  BaseState base;
  base.angular_velocity = Vec3(0, 0, 0.3);   // turning about the normal: friction acts too
  base.position = Vec3(0, 0, 0.0625 + 0.01);  // 1 cm up
  set_base_state(sim.model(), base, q, qd);
  sim.set_q(q);
  sim.set_qd(qd);
  return sim;
}

// Dyadic half extents: the STL's float32 holds them exactly, and MuJoCo's principal axes of the
// box are the file's axes permuted, so the hull's vertices are the box's corners bit for bit.
TEST(ConvexShapes, BoxMeshRestsAsTheBoxPrimitive) {
  const Vec3 h(0.125, 0.25, 0.0625);
  const fs::path stl = temp_folder() / "box.stl";
  write_box_stl(stl, h);
  const UrdfOptions floating{.fixed_base = false};
  const UrdfRobot mesh = parse_urdf(one_link_urdf("<mesh filename='" + stl.string() + "'/>"),
                                    (temp_folder() / "r.urdf").string(), floating);
  const UrdfRobot box = parse_urdf(one_link_urdf("<box size='0.25 0.5 0.125'/>"), "r.urdf",
                                   floating);
  ASSERT_EQ(mesh.model->shapes.size(), 1u);
  const CollisionShape& hull = mesh.model->shapes[0];
  EXPECT_EQ(hull.type, ShapeType::convex);
  ASSERT_EQ(hull.vertices.size(), 8u);
  for (const Vec3& v : hull.vertices) EXPECT_EQ(v.cwiseAbs(), h) << v.transpose();
  EXPECT_EQ(hull.position, box.model->shapes[0].position);
  for (const SolverType solver : {SolverType::pgs, SolverType::tgs}) {
    Simulation a = dropped(mesh.model, solver), b = dropped(box.model, solver);
    double worst_height = 0.0, worst_impulse = 0.0;
    for (int step = 0; step < 200; ++step) {
      a.step();
      b.step();
      worst_height = std::max(worst_height, std::abs(a.q()[2] - b.q()[2]));
      // The same points with the same impulses, in another order.
      ASSERT_EQ(a.contacts().size(), b.contacts().size()) << step;
      for (const ContactReport& c : a.contacts()) {
        const auto same =
            std::find_if(b.contacts().begin(), b.contacts().end(),
                         [&](const auto& d) { return (d.position - c.position).norm() < 1e-12; });
        ASSERT_NE(same, b.contacts().end()) << step;
        worst_impulse = std::max(worst_impulse, std::abs(same->normal_impulse - c.normal_impulse));
      }
    }
    EXPECT_LT(worst_height, 1e-12) << to_string(solver);
    EXPECT_LT(worst_impulse, 1e-12) << to_string(solver);
  }
}

// A scene's `type: convex` shape: the hull of the given points (the corners of the box of half
// extents h and its centre, which the hull leaves out) rests as the scene's box primitive does.
TEST(ConvexShapes, ASceneConvexShapeRestsAsTheBoxPrimitive) {
  const Vec3 h(0.125, 0.25, 0.0625);
  const fs::path urdf = temp_folder() / "bare.urdf";
  std::ofstream(urdf) << "<robot name='r'><link name='body'><inertial><mass value='2'/><inertia "
                         "ixx='0.02' ixy='0' ixz='0' iyy='0.03' iyz='0' izz='0.04'/></inertial>"
                         "</link></robot>";
  const std::string scene =
      "model: " + urdf.string() + "\nfixed_base: false\nsteps: 1\nshapes:\n";
  const std::string pose = ", xyz: [0.01, 0, 0], rpy: [0, 0, 0.2]}\n";
  std::string corners = "[0, 0, 0]";
  for (int v = 0; v < 8; ++v)
    corners += ", [" + std::to_string(v & 4 ? -h.x() : h.x()) + ", " +
               std::to_string(v & 2 ? -h.y() : h.y()) + ", " +
               std::to_string(v & 1 ? -h.z() : h.z()) + "]";
  const Scene hull = parse_scene(
      scene + "  - {link: body, type: convex, vertices: [" + corners + "]" + pose, "s.yaml");
  const Scene box = parse_scene(
      scene + "  - {link: body, type: box, half_extents: [0.125, 0.25, 0.0625]" + pose, "s.yaml");
  ASSERT_EQ(hull.robot.model->shapes.size(), 1u);
  const CollisionShape& shape = hull.robot.model->shapes[0];
  EXPECT_EQ(shape.type, ShapeType::convex);
  ASSERT_EQ(shape.vertices.size(), 8u);
  for (const Vec3& v : shape.vertices) EXPECT_EQ(v.cwiseAbs(), h) << v.transpose();
  for (const SolverType solver : {SolverType::pgs, SolverType::tgs}) {
    Simulation a = dropped(hull.robot.model, solver), b = dropped(box.robot.model, solver);
    double worst = 0.0;
    for (int step = 0; step < 200; ++step) {
      a.step();
      b.step();
      worst = std::max(worst, std::abs(a.q()[2] - b.q()[2]));
    }
    EXPECT_LT(worst, 1e-12) << to_string(solver);
  }
}

TEST(ConvexShapes, BadMeshesAreRefusedNamingTheFileLinkAndValue) {
  const fs::path dir = temp_folder();
  std::ofstream(dir / "garbage.stl") << "not an STL file";
  {  // a square: no volume
    std::ofstream out(dir / "flat.stl", std::ios::binary);
    const char header[80] = {};
    out.write(header, 80);
    const std::uint32_t count = 2;
    out.write(reinterpret_cast<const char*>(&count), 4);
    const float tris[2][12] = {{0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 1, 0},
                               {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0}};
    for (const auto& t : tris) {
      out.write(reinterpret_cast<const char*>(t), 48);
      out.write("\0\0", 2);
    }
  }
  write_box_stl(dir / "box.stl", Vec3(0.125, 0.125, 0.125));
  const std::string urdf = (dir / "r.urdf").string();
  auto error = [&](const std::string& geometry) {
    try {
      (void)parse_urdf(one_link_urdf(geometry), urdf);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const std::string at = urdf + ": link 'body': <collision name='c'> ";
  EXPECT_EQ(error("<mesh filename='missing.stl'/>"),
            at + "<mesh filename> = 'missing.stl': " + (dir / "missing.stl").string() +
                " not found");
  EXPECT_EQ(error("<mesh filename='garbage.stl'/>"),
            at + "<mesh filename> = 'garbage.stl': MuJoCo cannot use it: invalid header in STL "
                 "file 'garbage.stl'");
  EXPECT_EQ(error("<mesh filename='flat.stl'/>"),
            at + "<mesh filename> = 'flat.stl': MuJoCo cannot use it: mesh volume is too small");
  EXPECT_EQ(error("<mesh filename='box.stl' scale='1 0 1'/>"),
            at + "<mesh scale> = [1, 0, 1]: must be finite and > 0");
  EXPECT_EQ(error("<mesh filename='box.stl' scale='1 -2 1'/>"),
            at + "<mesh scale> = [1, -2, 1]: must be finite and > 0");
  EXPECT_EQ(error("<mesh filename='http://example/box.stl'/>"),
            at + "<mesh filename> = 'http://example/box.stl': only package:// and file:// "
                 "addresses are read");
  // package://NAME/REST: REST in the URDF's folder when no folder NAME lies above it; scaled.
  const UrdfRobot scaled =
      parse_urdf(one_link_urdf("<mesh filename='package://robot/box.stl' scale='1 2 4'/>"), urdf);
  ASSERT_EQ(scaled.model->shapes.size(), 1u);
  for (const Vec3& v : scaled.model->shapes[0].vertices)
    EXPECT_EQ(v.cwiseAbs(), Vec3(0.125, 0.25, 0.5)) << v.transpose();
}

TEST(ConvexShapes, MjcfMeshGeomsAreTheirHullsInTheGeomFrame) {
  const fs::path stl = temp_folder() / "mj_box.stl";
  write_box_stl(stl, Vec3(0.125, 0.25, 0.0625));
  const std::string xml = "<mujoco><asset><mesh name='box' file='" + stl.string() +
                          "'/></asset><worldbody><body name='b' pos='0 0 1'><freejoint/>"
                          "<geom name='hull' type='mesh' mesh='box' pos='0.5 0 0'/>"
                          "</body></worldbody></mujoco>";
  const MjcfRobot robot = parse_mjcf(xml, "m.xml", UrdfOptions{.fixed_base = false});
  ASSERT_EQ(robot.model->shapes.size(), 1u);
  const CollisionShape& s = robot.model->shapes[0];
  EXPECT_EQ(s.type, ShapeType::convex);
  EXPECT_TRUE(robot.model->unsupported_shapes.empty());
  ASSERT_EQ(s.vertices.size(), 8u);
  // In the link frame the corners are the file's, moved by the geom's pos.
  for (const Vec3& v : s.vertices) {
    const Vec3 x = s.position + s.rotation * v - Vec3(0.5, 0, 0);
    EXPECT_LT((x.cwiseAbs() - Vec3(0.125, 0.25, 0.0625)).norm(), 1e-15) << x.transpose();
  }
}

TEST(ConvexShapes, DartsArmsImportWithEveryCollisionAsAShape) {
  const std::string dart = "/usr/share/doc/dart/data/urdf/";
  for (const auto& [path, count] : {std::pair{dart + "KR5/KR5 sixx R650.urdf", 7u},
                                    std::pair{dart + "wam/wam.urdf", 8u}}) {
    const UrdfRobot robot = load_urdf(path);
    EXPECT_EQ(robot.model->shapes.size(), count) << path;
    EXPECT_TRUE(robot.model->unsupported_shapes.empty()) << path;
    Simulation sim(robot.model);
    Ground ground;
    ground.enabled = true;
    ground.height = -2.0;
    EXPECT_NO_THROW(sim.set_ground(ground)) << path;
    sim.step(10);
    EXPECT_TRUE(sim.q().allFinite()) << path;
  }
}

// Atlas (all-STL collisions) floating, its joints held at zero by PD drives, dropped 1 cm onto
// the ground: it stays on its feet (no point deeper than 1 cm) for 2 s and the normal force
// averaged over the last 0.5 s is its weight (a steady state carries it: linear momentum).
TEST(ConvexShapes, AtlasStandsOnItsFeetHullsUnderPdDrives) {
  const UrdfRobot robot = load_urdf("/usr/share/doc/dart/data/sdf/atlas/atlas_v3_no_head.urdf",
                                    UrdfOptions{.fixed_base = false});
  const Model& model = *robot.model;
  EXPECT_TRUE(model.unsupported_shapes.empty());
  SimulationOptions o;
  o.dt = 0.002;
  Simulation sim(robot.model, o);
  // Stiff drives (1e5 Nm/rad): at 3e3 its knees give way and it sinks to the ground over 2 s.
  for (int i = 1; i < model.num_links(); ++i)
    if (model.links[static_cast<size_t>(i)].nv == 1)
      sim.set_drive(model.links[static_cast<size_t>(i)].joint_name,
                    Drive{DriveType::force, 1e5, 2e3});
  // The lowest hull vertex at the rest pose, 1 cm above the ground.
  Data data(model);
  forward_kinematics(model, data, sim.q());
  double lowest = 1e9;
  for (const CollisionShape& s : model.shapes)
    for (const Vec3& v : s.vertices) {
      const auto L = static_cast<size_t>(s.link);
      const Vec3 x = data.world_position[L] + data.world_rotation[L] * (s.position + s.rotation * v);
      lowest = std::min(lowest, x.z());
    }
  Ground ground;
  ground.enabled = true;
  ground.height = lowest - 0.01;
  ground.material = Material{1.0, 1.0, 0.0};
  sim.set_ground(ground);
  double mass = 0.0;
  for (const Link& l : model.links) mass += l.mass;
  const int steps = 1000, last = 250;
  double deepest = 0.0, normal = 0.0;
  for (int k = 0; k < steps; ++k) {
    sim.step();
    for (const ContactReport& c : sim.contacts()) {
      deepest = std::min(deepest, c.separation);
      if (k >= steps - last) normal += c.normal_impulse;
    }
  }
  const double g = 9.81;
  EXPECT_GT(deepest, -0.01);
  EXPECT_NEAR(normal / (last * o.dt) / (mass * g), 1.0, 0.03) << "mass " << mass;
  EXPECT_TRUE(sim.q().allFinite());
}

}  // namespace
}  // namespace featherdrive
