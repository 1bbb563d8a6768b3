// MJCF geoms as contact shapes (issue 34): OpenAI's ant (Debian's dart-doc, gzip'd) and MuJoCo's
// humanoid: shape counts, the floor plane as the robot's ground, and capsules' world endpoints at
// MuJoCo's qpos0 against the fromto the XML writes (summed body offsets worked out by hand);
// visual geoms (contype = conaffinity = 0) skipped, other kinds listed as unsupported.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>

#include "featherdrive/algorithm/data.hpp"
#include "featherdrive/algorithm/frame_kinematics.hpp"
#include "featherdrive/algorithm/kinematics.hpp"
#include "featherdrive/io/mjcf.hpp"

namespace featherdrive {
namespace {

const std::string kAnt = "/usr/share/doc/dart/data/mjcf/openai/ant.xml.gz";
const std::string kHumanoid = "/usr/share/mujoco/model/humanoid/humanoid.xml";

// A gzip'd file's text, through Debian's gzip (no zlib in the project).
std::string gunzip(const std::string& path) {
  const std::unique_ptr<FILE, int (*)(FILE*)> pipe(popen(("gzip -dc '" + path + "'").c_str(), "r"),
                                                   pclose);
  std::string text;
  if (!pipe) return text;
  char buffer[4096];
  for (size_t n; (n = fread(buffer, 1, sizeof(buffer), pipe.get())) > 0;) text.append(buffer, n);
  return text;
}

const CollisionShape& shape_named(const Model& m, const std::string& name) {
  for (const CollisionShape& s : m.shapes)
    if (s.name == name) return s;
  ADD_FAILURE() << "no shape " << name;
  return m.shapes.front();
}

// The world endpoints of a capsule's segment at q: the shape's origin -+ half_length along its z.
std::pair<Vec3, Vec3> capsule_ends(const Model& m, const VecX& q, const CollisionShape& s) {
  Data data(m);
  forward_kinematics(m, data, q);
  const Mat3 R = data.world_rotation[static_cast<size_t>(s.link)] * s.rotation;
  const Vec3 c = frame_position(m, data, s.link, s.position);
  return {c - s.size.y() * R.col(2), c + s.size.y() * R.col(2)};
}

// The capsule's ends are a and b in some order.
void expect_ends(const std::pair<Vec3, Vec3>& ends, const Vec3& a, const Vec3& b,
                 const std::string& what) {
  const double same = std::max((ends.first - a).norm(), (ends.second - b).norm());
  const double swapped = std::max((ends.first - b).norm(), (ends.second - a).norm());
  EXPECT_LT(std::min(same, swapped), 1e-12)
      << what << ": " << ends.first.transpose() << " / " << ends.second.transpose();
}

TEST(MjcfShapes, TheAntsSphereAndTwelveCapsulesOnTheFloor) {
  const std::string xml = gunzip(kAnt);
  ASSERT_FALSE(xml.empty()) << kAnt;
  const MjcfRobot robot = parse_mjcf(xml, "ant.xml", UrdfOptions{.fixed_base = false});
  const Model& m = *robot.model;
  ASSERT_EQ(m.shapes.size(), 13u);
  EXPECT_TRUE(m.unsupported_shapes.empty());
  int capsules = 0;
  for (const CollisionShape& s : m.shapes) {
    capsules += s.type == ShapeType::capsule;
    // friction="1 0.5 0.5": the sliding coefficient for both.
    EXPECT_EQ(s.material.static_friction, 1.0) << s.name;
    EXPECT_EQ(s.material.dynamic_friction, 1.0) << s.name;
    EXPECT_EQ(s.material.restitution, 0.0) << s.name;
    EXPECT_EQ(s.size.x(), s.type == ShapeType::sphere ? 0.25 : 0.08) << s.name;
  }
  EXPECT_EQ(capsules, 12);
  const CollisionShape& torso = shape_named(m, "torso_geom");
  EXPECT_EQ(torso.type, ShapeType::sphere);
  EXPECT_EQ(m.links[static_cast<size_t>(torso.link)].name, "torso");
  // The floor: the plane z = 0, friction 1.
  ASSERT_TRUE(robot.ground.has_value());
  EXPECT_TRUE(robot.ground->enabled);
  EXPECT_EQ(robot.ground->height, 0.0);
  EXPECT_TRUE(robot.ground->normal.isApprox(Vec3::UnitZ()));
  EXPECT_EQ(robot.ground->material.static_friction, 1.0);
  // At qpos0 the torso stands at (0, 0, 0.75) and the hinges at 0: each leg's bodies sit at the
  // sums of their pos, and a capsule's ends are its body's position plus its fromto.
  const Vec3 torso_at(0, 0, 0.75);
  struct Leg {
    const char* aux;
    const char* leg;
    const char* ankle;
    double x, y;
  };
  for (const Leg& l : {Leg{"aux_1_geom", "left_leg_geom", "left_ankle_geom", 1, 1},
                       Leg{"aux_2_geom", "right_leg_geom", "right_ankle_geom", -1, 1},
                       Leg{"aux_3_geom", "back_leg_geom", "third_ankle_geom", -1, -1},
                       Leg{"aux_4_geom", "rightback_leg_geom", "fourth_ankle_geom", 1, -1}}) {
    const Vec3 d(0.2 * l.x, 0.2 * l.y, 0.0);
    expect_ends(capsule_ends(m, robot.q0, shape_named(m, l.aux)), torso_at, torso_at + d, l.aux);
    expect_ends(capsule_ends(m, robot.q0, shape_named(m, l.leg)), torso_at + d, torso_at + 2 * d,
                l.leg);
    expect_ends(capsule_ends(m, robot.q0, shape_named(m, l.ankle)), torso_at + 2 * d,
                torso_at + 4 * d, l.ankle);
    EXPECT_NEAR(shape_named(m, l.ankle).size.y(), 0.2 * std::sqrt(2.0), 1e-12);
  }
}

TEST(MjcfShapes, TheHumanoidsCapsulesAndSpheresAtQpos0) {
  const MjcfRobot robot = load_mjcf(kHumanoid, UrdfOptions{.fixed_base = false});
  const Model& m = *robot.model;
  EXPECT_EQ(m.shapes.size(), 19u);  // 20 colliding geoms, the floor among them
  EXPECT_TRUE(m.unsupported_shapes.empty());
  ASSERT_TRUE(robot.ground.has_value());
  EXPECT_EQ(robot.ground->height, 0.0);
  EXPECT_EQ(robot.ground->material.static_friction, 1.0);  // MuJoCo's default for the floor
  EXPECT_EQ(shape_named(m, "butt").material.static_friction, 0.7);  // class body
  // Body origins at qpos0: torso (0, 0, 1.5); lower_waist + (-.01, 0, -.26); pelvis + (0, 0,
  // -.165); right_thigh + (0, -.1, -.04); right_shin + (0, .01, -.403); right_foot + (0, 0, -.39).
  const Vec3 thigh(-0.01, -0.1, 1.5 - 0.26 - 0.165 - 0.04);
  const Vec3 foot = thigh + Vec3(0, 0.01, -0.403 - 0.39);
  expect_ends(capsule_ends(m, robot.q0, shape_named(m, "right_thigh")), thigh,
              thigh + Vec3(0, 0.01, -0.34), "right_thigh");
  // The foot's body has two joints with anchors (its links' origins at .08 and .04 above it).
  expect_ends(capsule_ends(m, robot.q0, shape_named(m, "right_right_foot")),
              foot + Vec3(-0.07, -0.02, 0), foot + Vec3(0.14, -0.04, 0), "right_right_foot");
  expect_ends(capsule_ends(m, robot.q0, shape_named(m, "torso")), Vec3(0, -0.07, 1.5),
              Vec3(0, 0.07, 1.5), "torso");
  // size=".04 .16" with fromto: the length is fromto's, the radius .04.
  const CollisionShape& arm = shape_named(m, "right_upper_arm");
  EXPECT_EQ(arm.size.x(), 0.04);
  EXPECT_NEAR(arm.size.y(), 0.5 * std::sqrt(3 * 0.16 * 0.16), 1e-12);
  const CollisionShape& hand = shape_named(m, "right_hand");
  EXPECT_EQ(hand.type, ShapeType::sphere);
  EXPECT_EQ(hand.size.x(), 0.04);
}

TEST(MjcfShapes, VisualGeomsAreSkippedAndOtherKindsListed) {
  const std::string xml = R"(<mujoco><worldbody>
      <geom name="sky" type="plane" size="1 1 1" pos="0 0 0.3" zaxis="0 1 1" friction="0.6"/>
      <geom name="rock" type="box" size="1 1 1" pos="3 0 0"/>
      <body name="b" pos="0 0 1"><freejoint/>
        <geom name="shell" type="box" size="0.1 0.2 0.3" pos="0.1 0 0"/>
        <geom name="look" type="sphere" size="0.5" contype="0" conaffinity="0"/>
        <geom name="egg" type="ellipsoid" size="0.1 0.2 0.3"/>
        <geom type="cylinder" size="0.1 0.2"/>
      </body></worldbody></mujoco>)";
  const MjcfRobot robot = parse_mjcf(xml, "m.xml", UrdfOptions{.fixed_base = false});
  const Model& m = *robot.model;
  ASSERT_EQ(m.shapes.size(), 3u);
  EXPECT_EQ(m.shapes[0].name, "shell");
  EXPECT_TRUE(m.shapes[0].size.isApprox(Vec3(0.1, 0.2, 0.3)));
  EXPECT_TRUE(m.shapes[0].position.isApprox(Vec3(0.1, 0, 0)));
  EXPECT_EQ(m.shapes[1].type, ShapeType::ellipsoid);
  EXPECT_EQ(m.shapes[1].size, Vec3(0.1, 0.2, 0.3));  // the semi-axes, as MuJoCo's size
  EXPECT_EQ(m.shapes[2].type, ShapeType::cylinder);
  EXPECT_EQ(m.shapes[2].size, Vec3(0.1, 0.2, 0));  // radius, half length, as MuJoCo's size
  EXPECT_TRUE(m.unsupported_shapes.empty());
  // The tilted plane: normal (0, 1, 1)/sqrt 2 through (0, 0, 0.3): height 0.3/sqrt 2.
  ASSERT_TRUE(robot.ground.has_value());
  EXPECT_TRUE(robot.ground->normal.isApprox(Vec3(0, 1, 1).normalized(), 1e-12));
  EXPECT_NEAR(robot.ground->height, 0.3 / std::sqrt(2.0), 1e-12);
  EXPECT_EQ(robot.ground->material.dynamic_friction, 0.6);
  bool warned = false;
  for (const std::string& w : robot.warnings)
    warned = warned || w == "geoms of the world body other than its first plane (the ground) are "
                            "not simulated: box 'rock'";
  EXPECT_TRUE(warned);
}

// A cylinder's fromto is its axis, as a capsule's: MuJoCo's compiler turns it into size and pose.
TEST(MjcfShapes, ACylinderFromtoIsItsAxis) {
  const std::string xml = R"(<mujoco><worldbody><body name="b"><freejoint/>
      <geom name="can" type="cylinder" fromto="0.1 0 0 0.1 0.3 0.4" size="0.05"/>
      </body></worldbody></mujoco>)";
  const MjcfRobot robot = parse_mjcf(xml, "m.xml", UrdfOptions{.fixed_base = false});
  ASSERT_EQ(robot.model->shapes.size(), 1u);
  const CollisionShape& can = robot.model->shapes[0];
  EXPECT_EQ(can.type, ShapeType::cylinder);
  EXPECT_NEAR(can.size.x(), 0.05, 1e-15);
  EXPECT_NEAR(can.size.y(), 0.25, 1e-12);  // half of |(0, 0.3, 0.4)|
  // The shape's z is the segment's direction (up to its sign).
  const Vec3 axis = can.rotation.col(2);
  EXPECT_LT((axis.cwiseAbs() - Vec3(0, 0.6, 0.8)).norm(), 1e-12);
}

// A plane on a link (MuJoCo allows planes and height fields on bodies welded to the world) is
// geometry contacts cannot use: listed.
TEST(MjcfShapes, APlaneOnALinkIsListed) {
  const std::string xml = R"(<mujoco><worldbody>
      <body name="base" pos="0 0 1"><geom name="pad" type="plane" size="1 1 1"/>
        <body name="arm"><joint type="hinge"/><geom type="sphere" size="0.1"/></body>
      </body></worldbody></mujoco>)";
  const MjcfRobot robot = parse_mjcf(xml, "m.xml");
  EXPECT_EQ(robot.model->shapes.size(), 1u);
  EXPECT_EQ(robot.model->unsupported_shapes,
            (std::vector<std::string>{"link 'base': plane geom 'pad'"}));
}

TEST(MjcfShapes, AFileWithContactsDisabledHasNoFloor) {
  const std::string xml = R"(<mujoco><option><flag contact="disable"/></option><worldbody>
      <geom type="plane" size="1 1 1"/><geom name="rock" type="box" size="1 1 1" pos="3 0 0"/>
      <body name="b" pos="0 0 1"><freejoint/><geom type="sphere" size="0.1"/></body>
      </worldbody></mujoco>)";
  const MjcfRobot robot = parse_mjcf(xml, "m.xml", UrdfOptions{.fixed_base = false});
  EXPECT_FALSE(robot.ground.has_value());
  EXPECT_EQ(robot.model->shapes.size(), 1u);  // the shapes stay: a scene's ground: may use them
  for (const std::string& w : robot.warnings) EXPECT_EQ(w.find("world body"), std::string::npos);
}

}  // namespace
}  // namespace featherdrive
