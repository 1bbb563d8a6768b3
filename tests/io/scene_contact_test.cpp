// A scene's ground, contact and shapes keys (issue 34, CONTACT_SPEC's syntax): the values reach
// the Simulation's settings and the model; an MJCF file's floor is the scene's ground unless the
// scene says `ground:` itself; bad values are refused naming the file, key and value.
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "featherdrive/core/format.hpp"
#include "featherdrive/io/scene.hpp"
#include "featherdrive/io/trajectory.hpp"

namespace featherdrive {
namespace {

const std::string kContactSource = FEATHERDRIVE_SOURCE_DIR;
const std::string kChain =
    "model: " + kContactSource + "/examples/chain3.urdf\ndt: 0.01\nsteps: 5\n";
const std::string kHumanoidScene =
    "model: /usr/share/mujoco/model/humanoid/humanoid.xml\nfixed_base: false\ndt: 0.005\n"
    "steps: 2\n";

std::string contact_scene_error(const std::string& text) {
  try {
    (void)parse_scene(text, "s.yaml");
  } catch (const InputError& e) {
    return e.what();
  }
  return "no error";
}

// A scene's CSV with the ground's columns (and `feet`'s): its header, its initial row and the row
// after `steps` steps of sim.
std::array<std::string, 3> csv_after(const Scene& scene, Simulation& sim, int steps,
                                     const std::vector<Foot>& feet) {
  std::ostringstream out;
  TrajectoryWriter writer(out, scene.robot, {}, false, sim.ground().enabled, feet);
  writer.write(0, sim, true);
  sim.step(steps);
  writer.write(steps, sim);
  std::istringstream in(out.str());
  std::array<std::string, 3> lines;
  for (std::string& line : lines) std::getline(in, line);
  return lines;
}

TEST(SceneContact, GroundContactAndShapesReachTheSimulation) {
  const Scene scene = parse_scene(kChain + R"(
ground:
  height: 0.5
  normal: [0, 3, 4]
  static_friction: 0.9
  dynamic_friction: 0.8
  restitution: 0.25
contact: {contact_offset: 0.04, rest_offset: 0.005, bounce_threshold: 0.5}
shapes:
  - link: link3
    type: capsule
    radius: 0.025
    half_length: 0.1
    xyz: [0, 0, -0.1]
    rpy: [0, 1.5707963267948966, 0]
    name: tip
    static_friction: 1.0
    dynamic_friction: 0.75
  - {link: link1, type: box, half_extents: [0.1, 0.2, 0.3]}
  - {link: link2, type: sphere, radius: 0.05, restitution: 0.5}
  - {link: link3, type: ellipsoid, radii: [0.1, 0.2, 0.3]}
  - {link: link3, type: cylinder, radius: 0.04, half_length: 0.15}
)",
                                  "s.yaml");
  const Model& m = *scene.model();
  ASSERT_EQ(m.shapes.size(), 5u);
  EXPECT_EQ(m.links[static_cast<size_t>(m.shapes[0].link)].name, "link1");  // by link order
  EXPECT_EQ(m.links[static_cast<size_t>(m.shapes[2].link)].name, "link3");
  EXPECT_EQ(m.shapes[3].type, ShapeType::ellipsoid);
  EXPECT_EQ(m.shapes[3].size, Vec3(0.1, 0.2, 0.3));
  EXPECT_EQ(m.shapes[4].type, ShapeType::cylinder);
  EXPECT_EQ(m.shapes[4].size, Vec3(0.04, 0.15, 0.0));
  const CollisionShape& tip = m.shapes[2];
  EXPECT_EQ(tip.name, "tip");
  EXPECT_EQ(tip.type, ShapeType::capsule);
  EXPECT_EQ(tip.size, Vec3(0.025, 0.1, 0.0));
  EXPECT_EQ(tip.position, Vec3(0, 0, -0.1));
  // Ry(pi/2) takes the capsule's z to the link's x.
  EXPECT_LT((tip.rotation.col(2) - Vec3::UnitX()).norm(), 1e-15);
  EXPECT_EQ(tip.material.static_friction, 1.0);
  EXPECT_EQ(tip.material.dynamic_friction, 0.75);
  EXPECT_EQ(tip.material.restitution, 0.0);
  EXPECT_EQ(m.shapes[1].material.restitution, 0.5);
  EXPECT_EQ(m.shapes[0].size, Vec3(0.1, 0.2, 0.3));
  EXPECT_EQ(scene.robot.shapes.size(), 5u);  // a later rebuild keeps them

  const Simulation sim = make_simulation(scene);
  const Ground& g = sim.ground();
  EXPECT_TRUE(g.enabled);
  EXPECT_EQ(g.height, 0.5);
  EXPECT_LT((g.normal - Vec3(0, 0.6, 0.8)).norm(), 1e-15);
  EXPECT_EQ(g.material.static_friction, 0.9);
  EXPECT_EQ(g.material.dynamic_friction, 0.8);
  EXPECT_EQ(g.material.restitution, 0.25);
  EXPECT_EQ(sim.contact_options().contact_offset, 0.04);
  EXPECT_EQ(sim.contact_options().rest_offset, 0.005);
  EXPECT_EQ(sim.contact_options().bounce_threshold, 0.5);

  // Without the keys: no ground, PhysX's default options, the URDF's shapes (none).
  const Scene plain = parse_scene(kChain, "s.yaml");
  const Simulation bare = make_simulation(plain);
  EXPECT_FALSE(bare.ground().enabled);
  EXPECT_EQ(bare.contact_options().contact_offset, 0.02);
  EXPECT_TRUE(plain.model()->shapes.empty());
  // ground: true is the default plane; ground: {} too.
  EXPECT_TRUE(make_simulation(parse_scene(kChain + "ground: true\n", "s.yaml")).ground().enabled);
  EXPECT_TRUE(make_simulation(parse_scene(kChain + "ground: {}\n", "s.yaml")).ground().enabled);
}

TEST(SceneContact, AnMjcfFloorIsTheGroundUnlessTheSceneSaysOtherwise) {
  const Simulation floor = make_simulation(parse_scene(kHumanoidScene, "s.yaml"));
  EXPECT_TRUE(floor.ground().enabled);
  EXPECT_EQ(floor.ground().height, 0.0);
  EXPECT_EQ(floor.ground().material.static_friction, 1.0);
  EXPECT_EQ(floor.model().shapes.size(), 19u);
  const Simulation own =
      make_simulation(parse_scene(kHumanoidScene + "ground: {height: -0.5}\n", "s.yaml"));
  EXPECT_EQ(own.ground().height, -0.5);
  EXPECT_EQ(own.ground().material.static_friction, 0.5);  // the scene's defaults, not the file's
  const Simulation none =
      make_simulation(parse_scene(kHumanoidScene + "ground: false\n", "s.yaml"));
  EXPECT_FALSE(none.ground().enabled);
  // A floor beside geometry contacts cannot use (the scene would load without a ground and say
  // why) no longer comes from an MJCF file: every geom kind on a moving body is a shape, and
  // MuJoCo 2.2.2 refuses a plane or height field on a static body beside the world's plane
  // ("Broadphase buffer full").
}

TEST(SceneContact, BadValuesAreRefusedNamingFileKeyAndValue) {
  const std::pair<std::string, std::string> cases[] = {
      {"ground: {normal: [0, 0, 0]}\n",
       "s.yaml: ground.normal = [0, 0, 0]: must be of finite non-zero length"},
      {"ground: {height: .nan}\n",
       "s.yaml: ground.height = .nan: must be finite"},
      {"ground: {dynamic_friction: -0.5}\n",
       "s.yaml: ground.dynamic_friction = -0.5: must be finite and >= 0"},
      {"ground: [1, 2]\n",
       "s.yaml: ground = [1, 2]: must be a map (key: value, ...)"},
      {"ground: maybe\n",
       "s.yaml: ground = maybe: must be true or false"},
      {"contact: {rest_offset: 0.02}\n",
       "s.yaml: contact = {rest_offset: 0.02}: the contact offset must be above the rest offset "
       "(0.02)"},
      {"contact: {contact_offset: .inf}\n",
       "s.yaml: contact.contact_offset = .inf: must be finite"},
      {"shapes:\n  - {link: link3, type: sphere}\n",
       "s.yaml: shapes[0].radius: missing (a sphere needs it)"},
      {"shapes:\n  - {type: sphere, radius: 1}\n",
       "s.yaml: shapes[0].link: missing"},
      {"shapes:\n  - {link: link3, type: sphere, radius: 1, half_length: 2}\n",
       "s.yaml: shapes[0].half_length = 2: is not a size of a sphere"},
      {"shapes:\n  - {link: link3, type: capsule, radius: 1, half_length: .inf}\n",
       "s.yaml: shapes[0].half_length = .inf: must be finite and > 0"},
      {"shapes:\n  - {link: link3, type: box, half_extents: [1, 2]}\n",
       "s.yaml: shapes[0].half_extents = [1, 2]: must be a list of 3 numbers"},
      {"shapes:\n  - {link: link3, type: ellipsoid, radii: 0.1}\n",
       "s.yaml: shapes[0].radii = 0.1: must be a list of 3 numbers"},
      {"shapes:\n  - {link: link3, type: ellipsoid, radii: [0.1, 0, 0.1]}\n",
       "s.yaml: shapes[0].radii[1] = 0: must be finite and > 0"},
      {"shapes:\n  - {link: link3, type: cylinder, radius: 0.1}\n",
       "s.yaml: shapes[0].half_length: missing (a cylinder needs it)"},
      {"shapes:\n  - {link: link3, type: cylinder, radius: 0.1, half_length: 1, "
       "radii: [1, 1, 1]}\n",
       "s.yaml: shapes[0].radii = [1, 1, 1]: is not a size of a cylinder"},
      {"shapes:\n  - {link: link3, type: box, half_extents: [1, 1, 1], xyz: [0, .nan, 0]}\n",
       "s.yaml: shapes[0].xyz[1] = .nan: must be finite"},
      {"shapes:\n  - {link: link3, type: sphere, radius: 1, static_friction: -1}\n",
       "s.yaml: shapes[0].static_friction = -1: must be finite and >= 0"},
  };
  for (const auto& [text, message] : cases)
    EXPECT_EQ(contact_scene_error(kChain + text), message);
  EXPECT_EQ(contact_scene_error(kChain + "shapes:\n  - {link: link3, type: sphere, radius: 1, "
                                         "colour: red}\n")
                .rfind("s.yaml: shapes[0].colour: unknown key", 0),
            0u);

  // A robot whose geometry contacts cannot use yet: the ground is refused in one line.
  const std::string collisions =
      "model: " + kContactSource + "/tests/data/collisions.urdf\ndt: 0.01\nsteps: 1\n";
  EXPECT_EQ(contact_scene_error(collisions + "ground: {}\n"),
            "s.yaml: ground: link 'arm': mesh collision 'package://collisions/arm.ply' (meshes "
            "are read from STL, OBJ, MSH, DAE): contacts do not support this shape yet (sphere, capsule, "
            "box, ellipsoid, cylinder, convex mesh); leave the ground off or replace the geometry");
  EXPECT_EQ(contact_scene_error(collisions + "ground: false\n"), "no error");
}

TEST(SceneContact, TheCsvHasContactColumnsForLinksWithShapesWithTheGroundOn) {
  const Scene scene = parse_scene(kChain + R"(
ground: {height: -5}
shapes:
  - {link: link3, type: sphere, radius: 0.05}
  - {link: link1, type: sphere, radius: 0.05}
  - {link: link3, type: box, half_extents: [0.1, 0.1, 0.1]}
)",
                                  "s.yaml");
  EXPECT_EQ(shape_links(*scene.model()),
            (std::vector<int>{scene.model()->link_index("link1"),
                              scene.model()->link_index("link3")}));
  Simulation sim = make_simulation(scene);
  const auto [header, initial, row] = csv_after(scene, sim, 1, {});
  const std::string columns =
      ",contact:link1:fx,contact:link1:fy,contact:link1:fz,contact:link3:fx,contact:link3:fy,"
      "contact:link3:fz";
  ASSERT_GE(header.size(), columns.size());
  EXPECT_EQ(header.substr(header.size() - columns.size()), columns);
  EXPECT_EQ(initial.substr(initial.size() - 12), ",0,0,0,0,0,0");
  std::string values;
  for (const char* link : {"link1", "link3"}) {
    const Vec3 f = sim.link_contact_force()[static_cast<size_t>(scene.model()->link_index(link))];
    for (int k = 0; k < 3; ++k) values += "," + format_double(f[k]);
  }
  EXPECT_EQ(row.substr(row.size() - values.size()), values);
  // Without the ground, no contact columns.
  std::ostringstream plain;
  TrajectoryWriter(plain, scene.robot).write(0, sim, true);
  EXPECT_EQ(plain.str().find("contact:"), std::string::npos);
}

// The quadruped standing (tests/data/quadruped_ground.yaml, its feet the four legs): at rest the
// four feet's normal forces carry its weight m g (linear momentum of a steady state), and each
// foot's columns are the sums of its links' contact columns.
TEST(SceneContact, FeetColumnsSumTheirLinksAndCarryTheWeightAtRest) {
  const Scene scene = load_scene(kContactSource + "/tests/data/quadruped_ground.yaml");
  ASSERT_EQ(scene.feet.size(), 4u);
  EXPECT_EQ(scene.feet[1].name, "fr");
  EXPECT_EQ(scene.feet[1].link_names, (std::vector<std::string>{"fr_thigh", "fr_shin"}));
  Simulation sim = make_simulation(scene);
  const auto [header, initial, row] = csv_after(scene, sim, 1000, scene.feet);  // 10 s: settled
  auto split = [](const std::string& line) {
    std::vector<std::string> fields;
    std::istringstream s(line);
    for (std::string f; std::getline(s, f, ',');) fields.push_back(f);
    return fields;
  };
  const std::vector<std::string> names = split(header), values = split(row);
  ASSERT_EQ(names.size(), values.size());
  auto column = [&](const std::string& name) {
    const auto it = std::find(names.begin(), names.end(), name);
    if (it == names.end()) ADD_FAILURE() << "no column " << name;
    return it == names.end() ? 0.0 : std::stod(values[static_cast<size_t>(it - names.begin())]);
  };
  // The foot columns follow the contact columns.
  EXPECT_EQ(names.back(), "foot:hr:fz");
  EXPECT_EQ(names[names.size() - 12], "foot:fl:fx");
  EXPECT_EQ(names[names.size() - 13], "contact:hr_shin:fz");
  double mass = 0.0;
  for (const Link& link : scene.model()->links) mass += link.mass;
  double normal = 0.0;
  for (const char* leg : {"fl", "fr", "hl", "hr"}) {
    for (const char* axis : {":fx", ":fy", ":fz"}) {
      const double thigh = column(std::string("contact:") + leg + "_thigh" + axis);
      const double shin = column(std::string("contact:") + leg + "_shin" + axis);
      EXPECT_EQ(column(std::string("foot:") + leg + axis), thigh + shin) << leg << axis;
    }
    normal += column(std::string("foot:") + leg + ":fz");
  }
  EXPECT_NEAR(normal, mass * 9.81, 1e-6);
  EXPECT_NE(initial.find(",0,0,0,0,0,0,0,0,0,0,0,0"), std::string::npos);
}

TEST(SceneContact, FeetAreChecked) {
  const std::string scene =
      "model: " + kContactSource + "/tests/data/quadruped.urdf\nfixed_base: false\ndt: 0.01\n"
      "steps: 1\nshapes:\n  - {link: fl_shin, type: sphere, radius: 0.05}\n";
  EXPECT_EQ(contact_scene_error(scene + "feet: {fl: [fl_shin]}\n"), "no error");
  EXPECT_EQ(contact_scene_error(scene + "feet: {fl: [fl_shn]}\n"),
            "s.yaml: feet.fl[0] = fl_shn: no link or frame named 'fl_shn'; nearest: 'fl_shin', "
            "'fr_shin', 'hl_shin'");
  EXPECT_EQ(contact_scene_error(scene + "feet: {fl: []}\n"),
            "s.yaml: feet.fl = []: must be a non-empty list of link names");
  EXPECT_EQ(contact_scene_error(scene + "feet: {fl: [fl_shin], fl: [fl_shin]}\n"),
            "s.yaml: feet.fl: the key appears twice");
  EXPECT_EQ(contact_scene_error(scene + "feet: {fl: [fl_shin, fl_shin]}\n"),
            "s.yaml: feet.fl[1] = fl_shin: appears twice in the foot");
  EXPECT_EQ(contact_scene_error(scene + "feet: {fl: [fl_thigh]}\n"),
            "s.yaml: feet.fl[0] = fl_thigh: link 'fl_thigh' has no collision shapes, so its "
            "contact force is always 0");
  EXPECT_EQ(contact_scene_error(scene + "feet: [fl_shin]\n"),
            "s.yaml: feet = [fl_shin]: must be a map {name: [link, ...], ...}");
}

}  // namespace
}  // namespace featherdrive
