// URDF <collision> as contact shapes (issue 34): box, sphere and cylinder (half its length) become
// shapes on their model link with the pose composed through merged fixed joints (checked against
// the composition written out by hand), a PLY mesh is listed as unsupported, bad sizes are
// refused naming the file, link and value; DART's URDFs load with their STL meshes as hulls.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>

#include "featherdrive/io/urdf.hpp"
#include "featherdrive/sim/simulation.hpp"

namespace featherdrive {
namespace {

const std::string kShapesSource = FEATHERDRIVE_SOURCE_DIR;

Mat3 axis_rotation(const Vec3& axis, double angle) {
  return Eigen::AngleAxisd(angle, axis).toRotationMatrix();
}
// URDF's rpy: R = Rz(yaw) Ry(pitch) Rx(roll).
Mat3 rpy_rotation(double r, double p, double y) {
  return axis_rotation(Vec3::UnitZ(), y) * axis_rotation(Vec3::UnitY(), p) *
         axis_rotation(Vec3::UnitX(), r);
}

void expect_shape(const Model& m, size_t i, const std::string& name, const std::string& link,
                  ShapeType type, const Vec3& size, const Vec3& position, const Mat3& rotation) {
  ASSERT_LT(i, m.shapes.size());
  const CollisionShape& s = m.shapes[i];
  EXPECT_EQ(s.name, name) << i;
  EXPECT_EQ(m.links[static_cast<size_t>(s.link)].name, link) << name;
  EXPECT_EQ(s.type, type) << name;
  EXPECT_TRUE(s.size.isApprox(size, 1e-14)) << name << ": " << s.size.transpose();
  EXPECT_LT((s.position - position).norm(), 1e-14) << name << ": " << s.position.transpose();
  EXPECT_LT((s.rotation - rotation).cwiseAbs().maxCoeff(), 1e-14) << name;
  EXPECT_EQ(s.material.static_friction, Material{}.static_friction);
}

TEST(UrdfShapes, BoxesAndSpheresWithTheirPosesComposedThroughMergedLinks) {
  const UrdfRobot robot = load_urdf(kShapesSource + "/tests/data/collisions.urdf");
  const Model& m = *robot.model;
  ASSERT_EQ(m.num_links(), 2);  // base, arm: sensor, wrist and hand are merged
  ASSERT_EQ(m.shapes.size(), 6u);
  const double h = std::numbers::pi / 2;
  expect_shape(m, 0, "body", "base", ShapeType::box, Vec3(0.2, 0.1, 0.05), Vec3(0, 0, 0.05),
               rpy_rotation(0, 0, 0.3));
  expect_shape(m, 1, "", "base", ShapeType::sphere, Vec3(0.05, 0, 0), Vec3(0.1, 0, 0),
               Mat3::Identity());
  // <cylinder radius length>: the full length along z, the shape keeps half of it.
  expect_shape(m, 2, "wheel", "base", ShapeType::cylinder, Vec3(0.1, 0.025, 0), Vec3::Zero(),
               Mat3::Identity());
  // sensor at (0.2, 0, 0.1) turned 90 deg about z: its (0.01, 0.02, 0.03) is (-0.02, 0.01, 0.03).
  expect_shape(m, 3, "lens", "base", ShapeType::sphere, Vec3(0.02, 0, 0),
               Vec3(0.2 - 0.02, 0.01, 0.1 + 0.03), axis_rotation(Vec3::UnitZ(), h));
  expect_shape(m, 4, "arm_box", "arm", ShapeType::box, Vec3(0.025, 0.03, 0.25), Vec3(0, 0, -0.25),
               rpy_rotation(0.1, 0.2, 0.3));
  // hand in arm: wrist at (0, 0, -0.5) turned 90 deg about x, hand (0.01, 0, 0.02) from it turned
  // 0.5 about z: Rx(90) takes (x, y, z) to (x, -z, y), so the hand is at (0.01, -0.02, -0.5); the
  // palm's (0, 0.03, 0) turned by Rz(0.5) is (-0.03 sin 0.5, 0.03 cos 0.5, 0), then by Rx(90)
  // (-0.03 sin 0.5, 0, 0.03 cos 0.5).
  expect_shape(m, 5, "palm", "arm", ShapeType::box, Vec3(0.04, 0.01, 0.02),
               Vec3(0.01 - 0.03 * std::sin(0.5), -0.02, -0.5 + 0.03 * std::cos(0.5)),
               axis_rotation(Vec3::UnitX(), h) * axis_rotation(Vec3::UnitZ(), 0.5) *
                   axis_rotation(Vec3::UnitY(), 0.4));
  EXPECT_EQ(m.unsupported_shapes,
            (std::vector<std::string>{"link 'arm': mesh collision 'package://collisions/arm.ply' "
                                      "(meshes are read from STL, OBJ, MSH, DAE)"}));
  // rebuild() (armature from a scene) keeps them.
  UrdfRobot copy = robot;
  copy.links[1].joint.armature = {0.1};
  copy.rebuild();
  EXPECT_EQ(copy.model->shapes.size(), 6u);
  EXPECT_EQ(copy.model->unsupported_shapes.size(), 1u);
  // Its mesh keeps the ground off.
  Simulation sim(robot.model);
  Ground ground;
  ground.enabled = true;
  try {
    sim.set_ground(ground);
    ADD_FAILURE() << "no throw";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()).rfind("ground: link 'arm': mesh collision "
                                          "'package://collisions/arm.ply' (meshes are read "
                                          "from STL, OBJ, MSH, DAE): "
                                          "contacts do not support this shape yet", 0),
              0u) << e.what();
  }
}

TEST(UrdfShapes, BadSizesAreRefusedNamingTheFileLinkAndValue) {
  auto urdf = [](const std::string& geometry) {
    return "<robot name='r'><link name='base'><collision name='c'><geometry>" + geometry +
           "</geometry></collision></link></robot>";
  };
  auto error = [&](const std::string& geometry) {
    try {
      (void)parse_urdf(urdf(geometry), "r.urdf");
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(error("<box size='0.1 0 0.1'/>"),
            "r.urdf: link 'base': <collision name='c'> <box size> = [0.1, 0, 0.1]: must be finite "
            "and > 0");
  EXPECT_EQ(error("<box size='0.1 -1 0.1'/>"),
            "r.urdf: link 'base': <collision name='c'> <box size> = [0.1, -1, 0.1]: must be finite "
            "and > 0");
  EXPECT_EQ(error("<sphere radius='0'/>"),
            "r.urdf: link 'base': <collision name='c'> <sphere radius> = 0: must be finite and "
            "> 0");
  EXPECT_EQ(error("<sphere radius='-0.5'/>"),
            "r.urdf: link 'base': <collision name='c'> <sphere radius> = -0.5: must be finite and "
            "> 0");
  EXPECT_EQ(error("<cylinder radius='0.1' length='0'/>"),
            "r.urdf: link 'base': <collision name='c'> <cylinder length> = 0: must be finite and "
            "> 0");
  EXPECT_EQ(error("<cylinder radius='-0.1' length='1'/>"),
            "r.urdf: link 'base': <collision name='c'> <cylinder radius> = -0.1: must be finite "
            "and > 0");
  EXPECT_EQ(parse_urdf(urdf("<sphere radius='0.5'/>"), "r.urdf").model->shapes.size(), 1u);
}

TEST(UrdfShapes, DartsUrdfsLoadWithTheirMeshesAsConvexHulls) {
  struct Case {
    std::string path;
    size_t shapes;
  };
  const std::string dart = "/usr/share/doc/dart/data/";
  for (const Case& c : {Case{dart + "urdf/KR5/KR5 sixx R650.urdf", 7},
                        Case{dart + "urdf/wam/wam.urdf", 8},
                        Case{dart + "sdf/atlas/atlas_v3_no_head.urdf", 29},
                        Case{dart + "urdf/KR5/ground.urdf", 1}}) {
    const UrdfRobot robot = load_urdf(c.path);
    EXPECT_EQ(robot.model->shapes.size(), c.shapes) << c.path;
    EXPECT_TRUE(robot.model->unsupported_shapes.empty()) << c.path;
    for (const CollisionShape& s : robot.model->shapes)
      EXPECT_TRUE(s.type == ShapeType::box || !s.vertices.empty()) << c.path;
  }
  // ground.urdf's 2 x 0.05 x 2 box, 0.525 m below its link.
  const Model ground = *load_urdf(dart + "urdf/KR5/ground.urdf").model;
  EXPECT_TRUE(ground.shapes[0].size.isApprox(Vec3(1.0, 0.025, 1.0)));
  EXPECT_TRUE(ground.shapes[0].position.isApprox(Vec3(0, -0.525, 0)));
}

}  // namespace
}  // namespace featherdrive
