// MJCF documents as a hostile user writes them: NaN and infinite numbers (MuJoCo would put its
// defaults in their place), nesting and include chains deeper than MuJoCo's compiler stack, FIFOs
// and folders named by <include> and asset files (MuJoCo would wait on them), <size> counts MuJoCo
// handles badly, names that collide, and the files a load reads (no output may replace them).
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <fstream>
#include <set>

#include "featherdrive/io/mjcf.hpp"

namespace featherdrive {
namespace {

namespace fs = std::filesystem;

fs::path fresh_dir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() /
                       ("featherdrive-mjcf-" + name + "-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

fs::path write(const fs::path& path, const std::string& text) {
  std::ofstream(path) << text;
  return path;
}

// The message of parse_mjcf's InputError ("" when it loads).
std::string parse_error(const std::string& xml, const std::string& name = "m.xml") {
  try {
    (void)parse_mjcf(xml, name);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

std::string load_error(const fs::path& path) {
  try {
    (void)load_mjcf(path);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

// One moving body around `inside`, with `extra` after the worldbody.
std::string model(const std::string& inside, const std::string& extra = "",
                  const std::string& before = "") {
  return "<mujoco>" + before + "<worldbody><body name=\"b\">" + inside +
         "</body></worldbody>" + extra + "</mujoco>";
}

TEST(MjcfInput, EmptyOrRootlessTextIsRefusedNotFatal) {
  // MuJoCo's VFS calls its fatal error (print, wait for Enter, exit) on an empty file.
  EXPECT_EQ(parse_error("", "x.xml"), "x.xml: empty text (an MJCF file is <mujoco>...</mujoco>)");
  EXPECT_EQ(parse_error("  \n", "y.xml"),
            "y.xml: no root element (an MJCF file is <mujoco>...</mujoco>)");
  EXPECT_EQ(parse_error("<robot name=\"r\"/>", "z.xml"),
            "z.xml: line 1: the root element is <robot>, not <mujoco> (an MJCF file)");
}

TEST(MjcfInput, NonFiniteNumbersAreRefusedNamingElementAndAttribute) {
  const std::string joint = "<joint name=\"h\"/>", geom = "<geom size=\"0.1\"/>";
  struct Case {
    std::string xml, element, attribute, value;
  };
  const std::vector<Case> cases = {
      {model(joint + geom).replace(24, 0, " pos=\"nan 0 0\""), "body", "pos", "nan 0 0"},
      {model(joint + geom).replace(24, 0, " euler=\"0 -NaN 0\""), "body", "euler", "0 -NaN 0"},
      {model(joint + geom).replace(24, 0, " quat=\"1 0 0 inf\""), "body", "quat", "1 0 0 inf"},
      {model(joint + "<geom size=\"0.1\" mass=\"nan\"/>"), "geom", "mass", "nan"},
      {model(joint + "<geom size=\"0.1\" pos=\"0 0 1e999\"/>"), "geom", "pos", "0 0 1e999"},
      {model(joint + "<geom size=\"infinity\"/>"), "geom", "size", "infinity"},
      {model(joint + "<inertial pos=\"nan 0 0\" mass=\"1\" diaginertia=\"1 1 1\"/>"), "inertial",
       "pos", "nan 0 0"},
      {model(joint + "<inertial pos=\"0 0 0\" mass=\"nan\" diaginertia=\"1 1 1\"/>"), "inertial",
       "mass", "nan"},
      {model(joint + "<inertial pos=\"0 0 0\" mass=\"1\" diaginertia=\"1 nan 1\"/>"), "inertial",
       "diaginertia", "1 nan 1"},
      {model("<joint name=\"h\" stiffness=\"nan\"/>" + geom), "joint", "stiffness", "nan"},
      {model("<joint name=\"h\" damping=\"inf\"/>" + geom), "joint", "damping", "inf"},
      {model("<joint name=\"h\" limited=\"true\" range=\"-1 nan\"/>" + geom), "joint", "range",
       "-1 nan"},
      {model(joint + geom, "", "<option timestep=\"nan\"/>"), "option", "timestep", "nan"},
      {model(joint + geom, "<actuator><position joint=\"h\" kp=\"1\" gear=\"nan\"/></actuator>"),
       "position", "gear", "nan"},
      // A character reference spells the same number.
      {model(joint + "<geom size=\"0.1\" mass=\"&#110;an\"/>"), "geom", "mass", "nan"},
  };
  for (const Case& c : cases) {
    const std::string expected = "<" + c.element + "> " + c.attribute + " = \"" + c.value + "\"";
    const std::string error = parse_error(c.xml);
    EXPECT_EQ(error.rfind("m.xml: line 1: " + expected, 0), 0u) << c.xml << "\n" << error;
  }
  // Names are not numbers: a joint may be called "nan" and a body "inf".
  EXPECT_EQ(parse_error("<mujoco><worldbody><body name=\"inf\"><joint name=\"nan\"/><geom "
                        "size=\"0.1\"/></body></worldbody><actuator><motor joint=\"nan\"/>"
                        "</actuator></mujoco>"),
            "");
}

TEST(MjcfInput, SizeCountsAndKeyframesAreBounded) {
  const std::string body = "<joint/><geom size=\"0.1\"/>";
  EXPECT_EQ(parse_error(model(body, "", "<size nkey=\"300000\"/>")),
            "m.xml: line 1: <size> nkey = \"300000\": above the bound 1000 (MuJoCo's compiler "
            "takes time quadratic in keyframes)");
  EXPECT_EQ(parse_error(model(body, "", "<size nkey=\"1000\"/>")), "");
  std::string keys;
  for (long k = 0; k <= kMaxMjcfKeyframes; ++k) keys += "<key/>";
  EXPECT_EQ(parse_error(model(body, "<keyframe>" + keys + "</keyframe>")),
            "m.xml: line 1: 1001 <key> elements: above the bound 1000 (MuJoCo's compiler takes "
            "time quadratic in keyframes)");
  EXPECT_NE(parse_error(model(body, "", "<size nuser_body=\"1001\"/>"))
                .find("<size> nuser_body = \"1001\": above the bound 1000"),
            std::string::npos);
  EXPECT_NE(parse_error(model(body, "", "<size nuserdata=\"1e9\"/>"))
                .find("<size> nuserdata = \"1e9\": above the bound 1000000"),
            std::string::npos);
  EXPECT_NE(parse_error(model(body, "", "<size nstack=\"2000000000\"/>"))
                .find("<size> nstack = \"2000000000\": above the bound 10000000"),
            std::string::npos);
}

TEST(MjcfInput, NestingIsBoundedWithIncludesFollowed) {
  // 12 files of 90 nested bodies: each within TinyXML2's per-file depth, 1 080 deep in all.
  const fs::path dir = fresh_dir("deep");
  for (int k = 0; k < 12; ++k) {
    std::string text;
    for (int i = 0; i < 90; ++i) text += "<body><joint/><geom size=\"0.1\"/>";
    if (k < 11) text += "<include file=\"deep" + std::to_string(k + 1) + ".xml\"/>";
    for (int i = 0; i < 90; ++i) text += "</body>";
    write(dir / ("deep" + std::to_string(k) + ".xml"),
          k == 0 ? "<mujoco><worldbody>" + text + "</worldbody></mujoco>"
                 : "<mujocoinclude>" + text + "</mujocoinclude>");
  }
  // <mujoco> is level 1, <worldbody> 2, file k's bodies 3 + 90 k ... 92 + 90 k: level 1001 is in
  // file 11.
  EXPECT_EQ(load_error(dir / "deep0.xml"),
            (dir / "deep0.xml").string() + ": " + (dir / "deep11.xml").string() +
                ", line 1: elements nested deeper than 1000 with includes followed (the bound)");

  // MuJoCo refuses a repeated name, so the count of includes is the count of files: bounded.
  std::string includes;
  for (int k = 0; k <= kMaxMjcfIncludes; ++k) {
    const std::string name = "part" + std::to_string(k) + ".xml";
    write(dir / name, "<mujocoinclude><body><joint/><geom size=\"0.1\"/></body></mujocoinclude>");
    includes += "<include file=\"" + name + "\"/>";
  }
  const fs::path many = write(dir / "many.xml", "<mujoco><worldbody>" + includes + "</worldbody></mujoco>");
  EXPECT_NE(load_error(many).find("more than 1000 included files (the bound)"), std::string::npos)
      << load_error(many);
}

TEST(MjcfInput, NonRegularFilesAreRefusedWhereverNamed) {
  const fs::path dir = fresh_dir("fifo");
  ASSERT_EQ(::mkfifo((dir / "fifo.xml").c_str(), 0600), 0);
  ASSERT_EQ(::mkfifo((dir / "fifo.stl").c_str(), 0600), 0);
  fs::create_directories(dir / "folder.stl");
  const fs::path top = write(dir / "inc.xml", model("<joint/><include file=\"fifo.xml\"/>"));
  EXPECT_EQ(load_error(top), top.string() + ": line 1: <include> " + (dir / "fifo.xml").string() +
                                 ": is not a regular file (a FIFO)");
  for (const std::string& file : {"fifo.stl", "folder.stl"}) {
    const fs::path mesh =
        write(dir / "mesh.xml", "<mujoco><asset>\n<mesh name=\"m\" file=\"" + file +
                                    "\"/></asset><worldbody><body><joint/><geom type=\"mesh\" "
                                    "mesh=\"m\"/></body></worldbody></mujoco>");
    EXPECT_EQ(load_error(mesh), mesh.string() + ": line 2: <mesh> file '" +
                                    (dir / file).string() + "' " +
                                    (file == "fifo.stl" ? "is not a regular file"
                                                        : "is a directory"));
  }
  // meshdir and texturedir place the files (a folder name with or without its '/').
  fs::create_directories(dir / "assets");
  ASSERT_EQ(::mkfifo((dir / "assets" / "t.png").c_str(), 0600), 0);
  const fs::path texture = write(
      dir / "texture.xml",
      "<mujoco><compiler texturedir=\"assets\"/><asset><texture name=\"t\" type=\"cube\" "
      "fileup=\"t.png\"/></asset><worldbody><body><joint/><geom size=\"0.1\"/></body>"
      "</worldbody></mujoco>");
  EXPECT_EQ(load_error(texture), texture.string() + ": line 1: <texture> fileup '" +
                                     (dir / "assets" / "t.png").string() +
                                     "' is not a regular file");
}

TEST(MjcfInput, FileNamesMujocosVfsCannotHoldAreRefusedNotFatal) {
  // MuJoCo's VFS lookup calls its fatal error for a name with nothing after its last '/' or a
  // last part of 1000 characters or more (fuzz_mjcf: <mesh file="../collada/">, MujocoError then).
  const std::string body = "<joint/><geom size=\"0.1\"/>";
  EXPECT_EQ(
      parse_error(model(body, "", "<asset>\n<mesh name=\"m\" file=\"../collada/\"/></asset>")),
      "m.xml: line 2: <mesh> file = '../collada/': names no file");
  EXPECT_EQ(parse_error(model(body, "", "<compiler strippath=\"true\"/><asset><texture "
                                        "name=\"t\" type=\"cube\" fileup=\"a/\"/></asset>")),
            "m.xml: line 1: <texture> fileup = '': names no file");
  EXPECT_EQ(parse_error(model(body + "<include file=\"x\\\"/>")),
            "m.xml: line 1: <include> file = 'x\\': names no file");
  const std::string long_name = "dir/" + std::string(999, 'a') + ".stl";
  EXPECT_EQ(parse_error(model(body, "", "<asset><hfield name=\"h\" file=\"" + long_name +
                                        "\"/></asset>")),
            "m.xml: line 1: <hfield> file = '" + long_name +
                "': the file name is longer than 999 characters (MuJoCo's bound)");
}

TEST(MjcfInput, InputFilesListEveryFileTheLoadReads) {
  const fs::path dir = fresh_dir("inputs");
  fs::create_directories(dir / "meshes");
  // A tetrahedron with outward faces.
  write(dir / "meshes" / "tetra.obj",
        "v 0 0 0\nv 0.1 0 0\nv 0 0.1 0\nv 0 0 0.1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n");
  write(dir / "arm.xml",
        "<mujocoinclude><body name=\"arm\"><joint name=\"h\"/><geom size=\"0.1\"/><geom "
        "type=\"mesh\" mesh=\"tetra\"/></body></mujocoinclude>");
  const fs::path top = write(dir / "top.xml",
                             "<mujoco><compiler meshdir=\"meshes/\"/><asset><mesh name=\"tetra\" "
                             "file=\"tetra.obj\"/></asset><worldbody><include file=\"arm.xml\"/>"
                             "</worldbody></mujoco>");
  const MjcfRobot robot = load_mjcf(top);
  const std::set<fs::path> expected = {top, dir / "arm.xml", dir / "meshes" / "tetra.obj"};
  EXPECT_EQ(std::set<fs::path>(robot.input_files.begin(), robot.input_files.end()), expected);
  const std::vector<fs::path> listed = mjcf_input_files(top);
  EXPECT_EQ(std::set<fs::path>(listed.begin(), listed.end()), expected);
  // load_robot keeps the list (scenes read it).
  EXPECT_EQ(load_robot(top).input_files.size(), 3u);
}

TEST(MjcfInput, UnnamedJointsNeverTakeAnotherJointsName) {
  // MuJoCo's index names an unnamed joint: joint 1 would be "joint1", the name of joint 0.
  const MjcfRobot robot = parse_mjcf(
      "<mujoco><worldbody><body name=\"a\"><joint name=\"joint1\"/><geom size=\"0.1\"/>"
      "<body name=\"b\" pos=\"0 0 1\"><joint/><geom size=\"0.1\"/></body></body></worldbody>"
      "</mujoco>",
      "unnamed.xml");
  ASSERT_EQ(robot.joint_order.size(), 2u);
  EXPECT_EQ(robot.joint_order[0], "joint1");
  EXPECT_NE(robot.joint_order[1], "joint1");
}

TEST(MjcfInput, GearZeroNamesTheActuatorAndGear) {
  EXPECT_EQ(parse_error(model("<joint name=\"h\"/><geom size=\"0.1\"/>",
                              "<actuator><position name=\"servo\" joint=\"h\" kp=\"10\" "
                              "gear=\"0\"/></actuator>")),
            "m.xml: actuator 'servo' on joint 'h': gear = 0: the joint force is gear times the "
            "actuator's, and its target ctrl / gear");
}

// The singularity check is ABA's pivots: exact on these small cases, O(n) on large ones.
TEST(MjcfInput, SingularMassMatrixIsFoundPerJoint) {
  // Two hinges of one body on one axis: M = I [1 1; 1 1] has no inertia along (1, -1); the first
  // joint's link moves nothing the second does not.
  EXPECT_EQ(parse_error(model("<joint name=\"j1\" axis=\"0 0 1\"/><joint name=\"j2\" axis=\"0 0 "
                              "1\"/><geom size=\"0.1\"/>"))
                .rfind("m.xml: joint 'j1' (link 'b/j1') moves no inertia at qpos0", 0),
            0u);
  // Two slides of one body along one axis: M = m [1 1; 1 1].
  EXPECT_EQ(parse_error(model("<joint name=\"s1\" type=\"slide\" axis=\"1 0 0\"/><joint "
                              "name=\"s2\" type=\"slide\" axis=\"1 0 0\"/><geom size=\"0.1\"/>"))
                .rfind("m.xml: joint 's1' (link 'b/s1') moves no inertia", 0),
            0u);
  // Armature gives the first joint inertia of its own: M = I [1 1; 1 1] + diag(a, 0) is regular.
  EXPECT_EQ(parse_error(model("<joint name=\"j1\" axis=\"0 0 1\" armature=\"0.1\"/><joint "
                              "name=\"j2\" axis=\"0 0 1\"/><geom size=\"0.1\"/>")),
            "");
  // Parallel hinges on different lines move the body differently (a turn about one is a turn
  // about the other plus a translation): regular.
  EXPECT_EQ(parse_error(model("<joint name=\"j1\" axis=\"0 0 1\"/><joint name=\"j2\" axis=\"0 0 "
                              "1\" pos=\"1 0 0\"/><geom size=\"0.1\"/>")),
            "");
}

TEST(MjcfInput, WideRangesOfMassAreNotSingular) {
  // 10 t on the first hinge, 1 mg on the second: M's eigenvalues are 1e-14 apart (a dense
  // check against the largest called it singular), yet each joint moves inertia of its own.
  const std::string xml =
      "<mujoco><worldbody><body name=\"heavy\"><joint name=\"j1\" axis=\"0 1 0\"/><inertial "
      "pos=\"0 0 0\" mass=\"1e4\" diaginertia=\"1e4 1e4 1e4\"/><body name=\"light\" pos=\"0 0 "
      "1\"><joint name=\"j2\" axis=\"0 1 0\"/><inertial pos=\"0 0 0\" mass=\"1e-6\" "
      "diaginertia=\"1e-10 1e-10 1e-10\"/></body></body></worldbody></mujoco>";
  EXPECT_EQ(parse_error(xml), "");
}

TEST(MjcfInput, LargeModelsPassTheSingularityCheck) {
  // 2 000 bodies of 1 kg, each on a hinge of its own under the world (contacts off): the
  // check is linear (a dense eigen-solve of M took 2.5 s here; at 10 000 bodies it would not
  // finish, and MuJoCo's own compiler takes 4 s of them).
  std::string bodies;
  for (int i = 0; i < 2000; ++i)
    bodies += "<body pos=\"" + std::to_string(i) + " 0 0\"><joint/><geom size=\"0.1\" "
              "mass=\"1\" contype=\"0\" conaffinity=\"0\"/></body>";
  const MjcfRobot robot = parse_mjcf("<mujoco><worldbody>" + bodies + "</worldbody></mujoco>",
                                     "flat.xml");
  EXPECT_EQ(robot.model->nv, 2000);
}

}  // namespace
}  // namespace featherdrive
