// COLLADA collision meshes (issue 34; docs/math/contact.md, G3): the hand-written box of
// tests/data/collada/box.dae becomes the hull its nodes, unit and URDF scale give in closed form,
// and rests on the ground as the URDF <box> of the same size and pose; DART's WAM with its .dae
// visuals as collisions gets hulls whose bounds are the files' own vertex bounds (read here with a
// regular expression, not the reader) and lie within its _collision.STL hulls; DART's Atlas with
// its .dae meshes as collisions gets the hulls of its STL collisions; bad files are refused in
// one line naming the file, link and reason.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <regex>
#include <sstream>

#include "featherdrive/algorithm/floating_base.hpp"
#include "featherdrive/core/format.hpp"
#include "featherdrive/io/error.hpp"
#include "featherdrive/io/urdf.hpp"
#include "featherdrive/sim/simulation.hpp"

namespace featherdrive {
namespace {

namespace fs = std::filesystem;

const std::string kDaeSource = FEATHERDRIVE_SOURCE_DIR;
const std::string kWam = "/usr/share/doc/dart/data/urdf/wam/";

std::string dae_box_urdf(const std::string& geometry) {
  return "<robot name='r'><link name='body'><inertial><mass value='2'/><inertia ixx='0.02' "
         "ixy='0' ixz='0' iyy='0.02' iyz='0' izz='0.02'/></inertial><collision name='c'>"
         "<geometry>" +
         geometry + "</geometry></collision></link></robot>";
}

// The box's corners by hand: (+-12.5, +-25, +-6.25) cm, the inner node's <scale> 1 1 2 and
// <rotate> 1 0 0 90 ((x, y, z) -> (x, -z, y)), the outer's <rotate> 0 0 1 30 and <translate>
// 1 2 3, then 0.01 m per unit; <up_axis> Y_UP is not applied (ROS's readers do not).
std::vector<Vec3> dae_box_corners(const Vec3& urdf_scale) {
  std::vector<Vec3> out;
  const double c = std::sqrt(3.0) / 2, s = 0.5;
  for (const double sz : {-1.0, 1.0})
    for (const double sy : {-1.0, 1.0})
      for (const double sx : {-1.0, 1.0}) {
        const Vec3 scaled(12.5 * sx, 25 * sy, 2 * 6.25 * sz);
        const Vec3 rolled(scaled.x(), -scaled.z(), scaled.y());
        const Vec3 yawed(c * rolled.x() - s * rolled.y(), s * rolled.x() + c * rolled.y(),
                         rolled.z());
        out.push_back((0.01 * (yawed + Vec3(1, 2, 3))).cwiseProduct(urdf_scale));
      }
  return out;
}

TEST(ColladaMeshes, HandWrittenBoxIsItsClosedFormHull) {
  const std::string urdf = kDaeSource + "/tests/data/dae_box.urdf";  // the mesh's folder
  for (const Vec3& scale : {Vec3(1, 1, 1), Vec3(2, 1, 0.5)}) {
    std::ostringstream geometry;
    geometry << "<mesh filename='collada/box.dae' scale='" << scale.x() << ' ' << scale.y() << ' '
             << scale.z() << "'/>";
    const UrdfRobot robot = parse_urdf(dae_box_urdf(geometry.str()), urdf);
    ASSERT_EQ(robot.model->shapes.size(), 1u);
    EXPECT_TRUE(robot.model->unsupported_shapes.empty());
    const CollisionShape& hull = robot.model->shapes[0];
    EXPECT_EQ(hull.type, ShapeType::convex);
    // Eight corners: the geometry no node places (1 km away) is not among them.
    ASSERT_EQ(hull.vertices.size(), 8u);
    for (const Vec3& corner : dae_box_corners(scale)) {
      double nearest = 1e300;
      for (const Vec3& v : hull.vertices) nearest = std::min(nearest, (v - corner).norm());
      EXPECT_LT(nearest, 1e-12) << corner.transpose();
    }
  }
}

// Dropped 1 cm, the .dae box and the URDF <box> of the same size (25 x 25 x 50 cm after the
// nodes) and pose (xyz 0.01 0.02 0.03, yaw 30 degrees) fall and rest alike, and both rest with
// the bottom face on the ground: the base at 0.25 - 0.03 = 0.22 m.
TEST(ColladaMeshes, BoxRestsAsTheUrdfBoxOfTheSameSizeAndPose) {
  const UrdfOptions floating{.fixed_base = false};
  const UrdfRobot dae = parse_urdf(dae_box_urdf("<mesh filename='collada/box.dae'/>"),
                                   kDaeSource + "/tests/data/dae_box.urdf", floating);
  const std::string box =
      "<robot name='r'><link name='body'><inertial><mass value='2'/><inertia ixx='0.02' "
      "ixy='0' ixz='0' iyy='0.02' iyz='0' izz='0.02'/></inertial><collision name='c'>"
      "<origin xyz='0.01 0.02 0.03' rpy='0 0 " +
      format_double(std::numbers::pi / 6) +
      "'/><geometry><box size='0.25 0.25 0.5'/></geometry></collision></link></robot>";
  const UrdfRobot primitive = parse_urdf(box, "box.urdf", floating);
  for (const SolverType solver : {SolverType::pgs, SolverType::tgs}) {
    SimulationOptions o;
    o.dt = 0.01;
    o.solver = solver;
    o.position_iterations = solver == SolverType::pgs ? 50 : 100;
    auto start = [&](const UrdfRobot& robot) {
      Simulation sim(robot.model, o);
      Ground g;
      g.enabled = true;
      sim.set_ground(g);
      VecX q = sim.q(), qd = sim.qd();
      BaseState base;
      base.position = Vec3(0, 0, 0.22 + 0.01);
      set_base_state(sim.model(), base, q, qd);
      sim.set_q(q);
      sim.set_qd(qd);
      return sim;
    };
    Simulation a = start(dae), b = start(primitive);
    double worst = 0.0;
    for (int step = 0; step < 400; ++step) {
      a.step();
      b.step();
      worst = std::max(worst, (a.q() - b.q()).cwiseAbs().maxCoeff());
    }
    // The file's own node rotation puts the hull's corners in another order than the box's
    // (contact.md C1a), so Gauss-Seidel visits the four contact rows in another order: what the
    // iterations leave unconverged differs (measured 1.2e-7 PGS, 1.2e-9 TGS); both rest at 0.22.
    EXPECT_LT(worst, 1e-6) << to_string(solver);
    EXPECT_NEAR(base_state(a.model(), a.q(), a.qd()).position.z(), 0.22, 1e-9) << to_string(solver);
    EXPECT_EQ(a.contacts().size(), 4u) << to_string(solver);
  }
}

// The bounds of a COLLADA file's position arrays, found by their ids' suffix: DART's WAM files
// place each mesh by one identity <matrix> in metres, so these are its vertices' bounds. (Plain
// string search: std::regex recurses per character and would overflow on 100 kB arrays.)
std::pair<Vec3, Vec3> dae_position_bounds(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  const std::string s = text.str();
  Vec3 lo = Vec3::Constant(1e300), hi = Vec3::Constant(-1e300);
  for (size_t at = 0; (at = s.find("-positions-array\"", at)) != std::string::npos;) {
    const size_t open = s.find('>', at), close = s.find('<', at);
    at = close;
    if (s.compare(s.rfind('<', open), 12, "<float_array") != 0) continue;  // an accessor's source
    std::istringstream values(s.substr(open + 1, close - open - 1));
    Vec3 p;
    while (values >> p.x() >> p.y() >> p.z()) {
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
  }
  return {lo, hi};
}

std::pair<Vec3, Vec3> hull_bounds(const CollisionShape& s) {
  Vec3 lo = Vec3::Constant(1e300), hi = Vec3::Constant(-1e300);
  for (const Vec3& v : s.vertices) {
    lo = lo.cwiseMin(v);
    hi = hi.cwiseMax(v);
  }
  return {lo, hi};
}

// DART's WAM with each link's .dae visual as its collision (written to a temporary folder): every
// hull's bounds are the file's vertex bounds exactly (the hull's vertices are the file's numbers),
// and lie within the link's _collision.STL hull's bounds, padded simplified copies of the visuals
// (the widest gap is wam3's 31 mm in x), within 1 mm. The files are marked Y_UP with z-up data:
// a Y_UP rotation (z -> y) would put wam3's 0.59 m reach along y, far outside its STL's 0.05 m.
// Fixed to the world with a ground under it, it steps.
TEST(ColladaMeshes, WamWithItsColladaVisualsAsCollisions) {
  std::ifstream in(kWam + "wam.urdf");
  std::stringstream text;
  text << in.rdbuf();
  const std::string stl = text.str();
  std::string dae = std::regex_replace(stl, std::regex("_collision\\.STL"), ".dae");
  dae = std::regex_replace(dae, std::regex("package://herb_description/"), "file://" + kWam);
  const fs::path dir =
      fs::temp_directory_path() / ("featherdrive-dae-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  std::ofstream(dir / "wam_dae.urdf") << dae;
  const UrdfRobot with_dae = load_urdf(dir / "wam_dae.urdf");
  const UrdfRobot with_stl = load_urdf(kWam + "wam.urdf");
  fs::remove_all(dir);
  const Model& m = *with_dae.model;
  ASSERT_EQ(m.shapes.size(), 8u);
  ASSERT_EQ(with_stl.model->shapes.size(), 8u);
  EXPECT_TRUE(m.unsupported_shapes.empty());
  const std::regex mesh("filename=\"package://herb_description/(meshes/wam/[a-z0-9_]+)\\.dae\"");
  std::vector<std::string> files;
  for (auto it = std::sregex_iterator(stl.begin(), stl.end(), mesh); it != std::sregex_iterator();
       ++it)
    files.push_back((*it)[1].str());
  ASSERT_EQ(files.size(), 8u);  // in link order, as the shapes
  for (size_t k = 0; k < 8; ++k) {
    const CollisionShape& s = m.shapes[k];
    EXPECT_EQ(s.type, ShapeType::convex);
    EXPECT_TRUE(s.position.isZero() && s.rotation.isIdentity()) << files[k];
    const auto [lo, hi] = hull_bounds(s);
    const auto [file_lo, file_hi] = dae_position_bounds(kWam + files[k] + ".dae");
    EXPECT_EQ(lo, file_lo) << files[k];
    EXPECT_EQ(hi, file_hi) << files[k];
    const auto [stl_lo, stl_hi] = hull_bounds(with_stl.model->shapes[k]);
    EXPECT_TRUE((lo.array() >= stl_lo.array() - 1e-3).all() &&
                (hi.array() <= stl_hi.array() + 1e-3).all())
        << files[k] << ": " << lo.transpose() << " .. " << hi.transpose() << " outside "
        << stl_lo.transpose() << " .. " << stl_hi.transpose();
  }
  Simulation sim(with_dae.model);
  Ground ground;
  ground.enabled = true;
  ground.height = -0.5;
  ASSERT_NO_THROW(sim.set_ground(ground));
  sim.step(50);
  EXPECT_TRUE(sim.q().allFinite());
}

// DART's Atlas with every collision's .stl replaced by the .dae of the same name (its visuals;
// Z_UP, <unit name="centimeter" meter="1">: the meter attribute counts): each of the 29 hulls has
// the bounds of the STL's hull within 1e-6 m, the STL path's float32 rounding (the file's
// float32 vertices, MuJoCo's float32 copy in principal axes) on extents below 1 m.
TEST(ColladaMeshes, AtlasColladaHullsMatchItsStlHulls) {
  const std::string atlas = "/usr/share/doc/dart/data/sdf/atlas/";
  std::ifstream in(atlas + "atlas_v3_no_head.urdf");
  std::stringstream text;
  text << in.rdbuf();
  std::string dae = std::regex_replace(text.str(), std::regex("\\.stl\""), ".dae\"");
  dae = std::regex_replace(dae, std::regex("filename=\""), "filename=\"" + atlas);
  const UrdfRobot with_dae = parse_urdf(dae, "atlas_dae.urdf");
  const UrdfRobot with_stl = load_urdf(atlas + "atlas_v3_no_head.urdf");
  ASSERT_EQ(with_dae.model->shapes.size(), 29u);
  ASSERT_EQ(with_stl.model->shapes.size(), 29u);
  EXPECT_TRUE(with_dae.model->unsupported_shapes.empty());
  for (size_t k = 0; k < 29; ++k) {
    const CollisionShape& a = with_dae.model->shapes[k];
    const CollisionShape& b = with_stl.model->shapes[k];
    ASSERT_EQ(a.type, b.type) << k;
    if (a.type != ShapeType::convex) continue;
    const auto [lo, hi] = hull_bounds(a);
    const auto [stl_lo, stl_hi] = hull_bounds(b);
    EXPECT_LT(std::max((lo - stl_lo).cwiseAbs().maxCoeff(), (hi - stl_hi).cwiseAbs().maxCoeff()),
              1e-6)
        << with_dae.model->links[static_cast<size_t>(a.link)].name;
  }
}

// Each bad file is refused in one line: the URDF, the link, the mesh and the reason.
TEST(ColladaMeshes, BadFilesAreRefusedInOneLine) {
  const std::string urdf = kDaeSource + "/tests/data/malformed/dae.urdf";
  auto error = [&](const std::string& mesh) {
    try {
      (void)parse_urdf(dae_box_urdf("<mesh filename='../meshes/" + mesh + "'/>"), urdf);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const std::string at = urdf + ": link 'body': <collision name='c'> <mesh filename> = '../meshes/";
  EXPECT_EQ(error("not_xml.dae"), at + "not_xml.dae': not XML: it holds no element");
  EXPECT_EQ(error("no_geometry.dae"),
            at + "no_geometry.dae': its visual scene places no <geometry> with a <mesh> of "
                 "vertices");
  EXPECT_EQ(error("count_mismatch.dae"),
            at + "count_mismatch.dae': <float_array id='tetra-positions-array'> (line 7): count "
                 "= '12' but it holds 11 numbers");
  EXPECT_EQ(error("nonfinite.dae"),
            at + "nonfinite.dae': <float_array id='tetra-positions-array'> (line 7): value 11 = "
                 "'inf' is not a finite number");
}

// A COLLADA text with one geometry 'g' of the given positions and the given visual scene.
std::string dae_text(const std::string& positions, int count, const std::string& scene) {
  return "<COLLADA><library_geometries><geometry id='g'><mesh><source id='s'><float_array "
         "id='a' count='" +
         std::to_string(3 * count) + "'>" + positions +
         "</float_array><technique_common><accessor source='#a' count='" + std::to_string(count) +
         "' stride='3'/></technique_common></source><vertices id='v'><input semantic='POSITION' "
         "source='#s'/></vertices></mesh></geometry></library_geometries>" +
         scene + "</COLLADA>";
}

// What the reader and the hull refuse beyond the malformed corpus: flat, too few and too distant
// points (MuJoCo's float32 copy), references out of the file, a node that instantiates itself.
TEST(ColladaMeshes, FlatSparseAndSelfReferencingFilesAreRefused) {
  const fs::path dir =
      fs::temp_directory_path() / ("featherdrive-dae-bad-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const std::string tetra = "0 0 0 1 0 0 0 1 0 0 0 1";
  auto scene = [](const std::string& nodes) {
    return "<library_visual_scenes><visual_scene id='vs'>" + nodes +
           "</visual_scene></library_visual_scenes>";
  };
  std::ofstream(dir / "flat.dae") << dae_text("0 0 0 1 0 0 0 1 0 1 1 1e-9", 4, "");
  std::ofstream(dir / "three.dae") << dae_text("0 0 0 1 0 0 0 1 0", 3, "");
  std::ofstream(dir / "far.dae") << dae_text("0 0 0 1 0 0 0 1 0 0 0 2e6", 4, "");
  std::ofstream(dir / "other_file.dae")
      << dae_text(tetra, 4, scene("<node><instance_geometry url='parts.dae#g'/></node>"));
  std::ofstream(dir / "cycle.dae")
      << dae_text(tetra, 4, scene("<node id='n'><instance_node url='#n'/></node>"));
  std::ofstream(dir / "tetra.dae") << dae_text(
      tetra, 4, scene("<node><scale>2 2 2</scale><instance_geometry url='#g'/></node>"));
  auto error = [&](const std::string& mesh) {
    try {
      const UrdfRobot r =
          parse_urdf(dae_box_urdf("<mesh filename='" + mesh + "'/>"), (dir / "r.urdf").string());
      return "hull of " + std::to_string(r.model->shapes[0].vertices.size());
    } catch (const InputError& e) {
      const std::string what = e.what();
      return what.substr(what.find(mesh) + mesh.size() + 3);  // after "mesh': "
    }
  };
  EXPECT_EQ(error("flat.dae"), "its vertices span no volume (all within 1e-06 m of a plane)");
  EXPECT_EQ(error("three.dae"), "3 vertices: a hull needs 4 that span a volume");
  EXPECT_EQ(error("far.dae"), "a vertex [0, 0, 2e+06] is not finite or beyond 1e+06 m");
  EXPECT_EQ(error("other_file.dae"),
            "<instance_geometry> (line 1): url = 'parts.dae#g': only references to this file's "
            "elements (#id) are read");
  EXPECT_EQ(error("cycle.dae"), "<node id='n'> (line 1): nodes instantiated deeper than 1000");
  EXPECT_EQ(error("tetra.dae"), "hull of 4");
  fs::remove_all(dir);
}

}  // namespace
}  // namespace featherdrive
