// The comparison logic of `featherdrive compare-physx` on trajectories whose differences are known
// by construction, the CSV reader's errors, and find_physx's messages (no node or PhysX needed).
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "featherdrive/core/format.hpp"
#include "featherdrive/io/physx_runner.hpp"
#include "featherdrive/io/trajectory.hpp"
#include "featherdrive/io/urdf.hpp"
#include "featherdrive/model/model_builder.hpp"
#include "support/scoped_env.hpp"

namespace featherdrive {
namespace {

using test::ScopedEnv;

// A harness-style CSV of `rows` rows for joints b and a (not in name order), with a root column
// the reader must skip.
std::string synthetic_csv(int rows) {
  std::string s = "step,t,q:b,q:a,qd:b,qd:a,f:b,f:a,root:px\n";
  for (int k = 0; k < rows; ++k) {
    const double t = 0.01 * k;
    s += std::to_string(k);
    for (double v : {t, -2.0 * std::sin(t), 0.5 * t, -2.0 * std::cos(t), 0.5,
                     k == 0 ? 0.0 : 30.0 * std::cos(3 * t), k == 0 ? 0.0 : -4.0}) {
      s += ",";
      s += format_double(v);
    }
    s += ",7\n";
  }
  return s;
}

TEST(PhysxRunner, ParsesHarnessCsvByColumnName) {
  const JointTrajectory t = parse_joint_csv(synthetic_csv(5), "px.csv");
  ASSERT_EQ(t.joints, (std::vector<std::string>{"b", "a"}));
  ASSERT_EQ(t.rows(), 5u);
  EXPECT_DOUBLE_EQ(t.t[3], 0.03);
  EXPECT_DOUBLE_EQ(t.q[3][1], 0.015);
  EXPECT_DOUBLE_EQ(t.qd[2][0], -2.0 * std::cos(0.02));
  EXPECT_DOUBLE_EQ(t.f[4][1], -4.0);
}

TEST(PhysxRunner, ComparisonFindsTheKnownLargestDifferences) {
  const JointTrajectory reference = parse_joint_csv(synthetic_csv(50), "px.csv");
  // Differences put in by hand: the largest of each quantity and joint, with a smaller one
  // elsewhere that must not win.
  JointTrajectory a = parse_joint_csv(synthetic_csv(50), "fd.csv");
  a.q[17][1] += 3e-6;   // a: q, row 17
  a.q[40][1] -= 1e-6;   //   smaller
  a.qd[33][0] -= 2e-5;  // b: qd, row 33 (a negative difference counts by its magnitude)
  a.qd[5][0] += 1e-5;
  a.f[49][0] += 0.25;  // b: f, the last row
  a.f[1][1] += 1e-3;   // a: f, row 1
  const TrajectoryComparison c = compare_trajectories(a, reference);
  ASSERT_EQ(c.joints.size(), 2u);
  const JointDifference& b = c.joints[0];
  const JointDifference& ja = c.joints[1];
  EXPECT_EQ(b.joint, "b");
  EXPECT_EQ(ja.joint, "a");
  EXPECT_NEAR(ja.q.value, 3e-6, 1e-15);
  EXPECT_EQ(ja.q.row, 17u);
  EXPECT_EQ(b.q.value, 0.0);
  EXPECT_EQ(b.q.row, 0u);
  EXPECT_NEAR(b.qd.value, 2e-5, 1e-15);
  EXPECT_EQ(b.qd.row, 33u);
  EXPECT_NEAR(b.f.value, 0.25, 1e-12);
  EXPECT_EQ(b.f.row, 49u);
  EXPECT_NEAR(ja.f.value, 1e-3, 1e-12);
  EXPECT_EQ(ja.f.row, 1u);
  // Scale: the reference's largest |q|, |qd|, |f| over joints and rows.
  double sq = 0, sqd = 0, sf = 0;
  for (int k = 0; k < 50; ++k) {
    const double t = 0.01 * k;
    sq = std::max({sq, 2.0 * std::abs(std::sin(t)), 0.5 * t});
    sqd = std::max({sqd, 2.0 * std::abs(std::cos(t)), 0.5});
    sf = std::max({sf, k ? 30.0 * std::abs(std::cos(3 * t)) : 0.0, k ? 4.0 : 0.0});
  }
  EXPECT_DOUBLE_EQ(c.scale_q, sq);
  EXPECT_DOUBLE_EQ(c.scale_qd, sqd);
  EXPECT_DOUBLE_EQ(c.scale_f, sf);
  EXPECT_NEAR(c.relative_q(), 3e-6 / sq, 1e-15);
  EXPECT_NEAR(c.relative_qd(), 2e-5 / sqd, 1e-15);
  EXPECT_NEAR(c.relative_f(), 0.25 / sf, 1e-12);
}

TEST(PhysxRunner, FirstRowOfATieAndNanAsWorst) {
  const JointTrajectory reference = parse_joint_csv(synthetic_csv(10), "px.csv");
  JointTrajectory a = reference;
  a.q[2][0] += 0.5;
  a.q[6][0] += 0.5;  // the same difference later: the first row is reported
  a.qd[8][1] = std::nan("");
  const TrajectoryComparison c = compare_trajectories(a, reference);
  EXPECT_EQ(c.joints[0].q.row, 2u);
  EXPECT_TRUE(std::isinf(c.joints[1].qd.value));
  EXPECT_EQ(c.joints[1].qd.row, 8u);
}

TEST(PhysxRunner, IdenticalTrajectoriesDifferByNothing) {
  const JointTrajectory t = parse_joint_csv(synthetic_csv(20), "px.csv");
  const TrajectoryComparison c = compare_trajectories(t, t);
  for (const JointDifference& j : c.joints) EXPECT_EQ(j.q.value + j.qd.value + j.f.value, 0.0);
  EXPECT_EQ(c.relative_q() + c.relative_qd() + c.relative_f(), 0.0);
}

TEST(PhysxRunner, MismatchedTrajectoriesAreRefused) {
  const JointTrajectory t = parse_joint_csv(synthetic_csv(20), "px.csv");
  const JointTrajectory shorter = parse_joint_csv(synthetic_csv(19), "px.csv");
  EXPECT_THROW(compare_trajectories(shorter, t), PhysxError);
  JointTrajectory renamed = t;
  renamed.joints[1] = "c";
  try {
    compare_trajectories(renamed, t);
    FAIL() << "a joint missing on one side must throw";
  } catch (const PhysxError& e) {
    EXPECT_NE(std::string(e.what()).find("joint 'a'"), std::string::npos) << e.what();
  }
}

TEST(PhysxRunner, CsvErrorsNameFileLineColumnAndValue) {
  auto message = [](const std::string& text) {
    try {
      parse_joint_csv(text, "px.csv");
    } catch (const PhysxError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(message("step,t,q:a,qd:a,f:a\n0,0,1,2,x\n"),
            "px.csv: line 2, column 'f:a': 'x' is not a number");
  EXPECT_EQ(message("step,t,q:a,qd:a,f:a\n0,0,1,2\n"),
            "px.csv: line 2: 4 values, the header has 5");
  EXPECT_EQ(message("step,t,q:a,f:a\n"), "px.csv: header: column 'qd:a' is missing for joint 'a'");
  EXPECT_EQ(message(""), "px.csv: empty file, expected a CSV header");
  EXPECT_THROW(read_joint_csv("/nonexistent/px.csv"), PhysxError);
}

TEST(PhysxRunner, QuotedHeaderFieldsAreRead) {
  // RFC 4180: commas, doubled quotes and line breaks inside quotes; CRLF line ends.
  const std::string text =
      "step,t,\"q:a,b\",\"qd:a,b\",\"f:a,b\",\"q:say \"\"hi\"\"\",\"qd:say \"\"hi\"\"\","
      "\"f:say \"\"hi\"\"\",\"q:x\ny\",\"qd:x\ny\",\"f:x\ny\"\r\n"
      "0,0,1,2,3,4,5,6,7,8,9\r\n\r\n1,0.5,10,20,30,40,50,60,70,80,x\r\n";
  try {
    parse_joint_csv(text, "q.csv");
    FAIL() << "the bad number must be found";
  } catch (const PhysxError& e) {
    // The header spans lines 1-4 (three names hold a line break), row 0 is line 5, a blank
    // line 6: the bad row starts on line 7.
    EXPECT_EQ(std::string(e.what()), "q.csv: line 7, column 'f:x\ny': 'x' is not a number");
  }
  const std::string good = text.substr(0, text.rfind(",x")) + ",90\r\n";
  const JointTrajectory t = parse_joint_csv(good, "q.csv");
  ASSERT_EQ(t.joints, (std::vector<std::string>{"a,b", "say \"hi\"", "x\ny"}));
  ASSERT_EQ(t.rows(), 2u);
  EXPECT_EQ(t.q[1], (std::vector<double>{10, 40, 70}));
  EXPECT_EQ(t.f[1], (std::vector<double>{30, 60, 90}));
  try {
    parse_joint_csv("step,t,\"q:a\n0,1\n", "open.csv");
    FAIL() << "an unclosed quote must be refused";
  } catch (const PhysxError& e) {
    EXPECT_EQ(std::string(e.what()), "open.csv: line 1: a quoted field is not closed");
  }
}

TEST(PhysxRunner, CsvFieldQuotesOnlyWhatNeedsIt) {
  EXPECT_EQ(csv_field("q:joint1"), "q:joint1");
  EXPECT_EQ(csv_field("q:a,b"), "\"q:a,b\"");
  EXPECT_EQ(csv_field("say \"hi\""), "\"say \"\"hi\"\"\"");
  EXPECT_EQ(csv_field("x\ny"), "\"x\ny\"");
  EXPECT_EQ(csv_field("x\ry"), "\"x\ry\"");
  EXPECT_EQ(csv_field(""), "");
}

TEST(PhysxRunner, TrajectoryCsvWithOddJointNamesReadsBack) {
  // Joint names with a comma and quotes (legal in URDF) keep the columns aligned.
  const std::string urdf = R"(<robot name="odd">
    <link name="base"/>
    <link name="l1"><inertial><mass value="1"/>
      <inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link>
    <link name="l2"><inertial><mass value="1"/>
      <inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link>
    <joint name="a,b" type="prismatic"><parent link="base"/><child link="l1"/><axis xyz="1 0 0"/>
      <limit effort="1" velocity="1" lower="-1" upper="1"/></joint>
    <joint name="say &quot;hi&quot;" type="continuous"><parent link="l1"/><child link="l2"/></joint>
  </robot>)";
  const UrdfRobot robot = parse_urdf(urdf, "odd.urdf");
  Simulation sim(robot.model);
  std::ostringstream out;
  TrajectoryWriter writer(out, robot);
  writer.write(0, sim, true);
  sim.step();
  writer.write(1, sim);
  const JointTrajectory t = parse_joint_csv(out.str(), "odd.csv");
  EXPECT_EQ(t.joints, (std::vector<std::string>{"a,b", "say \"hi\""}));
  ASSERT_EQ(t.rows(), 2u);
  EXPECT_EQ(t.q[1][0], sim.q()[0]);
  EXPECT_EQ(t.q[1][1], sim.q()[1]);
}

TEST(PhysxRunner, RelativeDifferenceAgainstAScaleOfZeroIsInfinite) {
  // PhysX's joint stays at 0 in every quantity; featherdrive's moves by 0.9.
  const JointTrajectory reference =
      parse_joint_csv("step,t,q:a,qd:a,f:a\n0,0,0,0,0\n1,0.1,0,0,0\n", "px.csv");
  JointTrajectory a = reference;
  a.q[1][0] = 0.9;
  const TrajectoryComparison c = compare_trajectories(a, reference);
  EXPECT_EQ(c.scale_q, 0.0);
  EXPECT_DOUBLE_EQ(c.joints[0].q.value, 0.9);
  EXPECT_TRUE(std::isinf(c.relative_q()) && c.relative_q() > 0) << c.relative_q();
  // No difference against a scale of 0 is no difference.
  EXPECT_EQ(c.relative_qd(), 0.0);
  EXPECT_EQ(c.relative_f(), 0.0);
}

TEST(PhysxRunner, SceneJsonEscapesNamesAsPythonsJsonReadsThem) {
  if (!std::filesystem::exists("/usr/bin/python3")) GTEST_SKIP() << "no /usr/bin/python3";
  // A name that would close the string and set gravity, backslashes, JSON's own punctuation and
  // UTF-8 (control characters never reach a model: ModelBuilder refuses them in names).
  const std::vector<std::string> names = {"base\", \"gravity\": [0, 0, 0], \"x\": \"",
                                          "root (not exported)",
                                          "comma, [brackets] {braces}: \xc3\xbc", "solidus/",
                                          "back\\slash\\", "slide\""};
  ModelBuilder b;
  b.set_gravity(Vec3(0, 0, -9.81));
  const Mat3 I = Mat3::Identity() * 0.01;
  b.add_link(make_link(names[0], "", 1.0, Vec3::Zero(), I, fixed_joint(names[1])));
  b.add_link(make_link(names[2], names[0], 1.0, Vec3::Zero(), I,
                       prismatic_joint(names[3], Vec3::UnitX())));
  b.add_link(make_link(names[4], names[2], 1.0, Vec3::Zero(), I,
                       prismatic_joint(names[5], Vec3::UnitY())));
  Simulation sim(std::make_shared<const Model>(b.build()));
  const auto dir = std::filesystem::temp_directory_path() /
                   ("featherdrive-json-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "scene.json") << physx_scene_json(sim, 2, {{{names[3], {0.5, 0.0}}}});
  // Exit 0 when every name reads back exactly and gravity is the model's.
  const std::string script =
      "import json, sys\n"
      "d = json.load(open(sys.argv[1], encoding='utf-8'))\n"
      "got = [l['name'] for l in d['links']] + [l['joint']['name'] for l in d['links'][1:]]\n"
      "got += list(d['initial']['q']) + list(d['targets'][0])\n"
      "want = sys.argv[2:]\n"
      "want = [want[0], want[2], want[4], want[3], want[5], want[3], want[5], want[3]]\n"
      "sys.exit(0 if got == want and d['gravity'] == [0, 0, -9.81] else 3)\n";
  std::vector<std::string> argv = {"/usr/bin/python3", "-c", script, (dir / "scene.json").string()};
  argv.insert(argv.end(), names.begin(), names.end());
  EXPECT_EQ(run_program(argv), 0) << "python's json module read other names or gravity";
  std::filesystem::remove_all(dir);
}

std::string find_physx_message(const std::vector<std::filesystem::path>& dirs) {
  try {
    find_physx(dirs);
  } catch (const PhysxError& e) {
    return e.what();
  }
  return "no error";
}

TEST(PhysxRunner, NoNodeSaysHowToInstallIt) {
  const auto empty = std::filesystem::temp_directory_path() / "featherdrive-physx-runner-empty";
  std::filesystem::create_directories(empty);
  ScopedEnv path("PATH", empty.string());
  const std::string m = find_physx_message({});
  EXPECT_NE(m.find("node"), std::string::npos) << m;
  EXPECT_NE(m.find("apt-get install -y nodejs npm"), std::string::npos) << m;
  EXPECT_NE(m.find("make physx"), std::string::npos) << m;
  EXPECT_EQ(m.find('\n'), std::string::npos) << m;
}

TEST(PhysxRunner, MissingPackageNamesTheFolder) {
  const auto dir = std::filesystem::temp_directory_path() / "featherdrive-physx-runner-fake";
  std::filesystem::create_directories(dir / "bin");
  {  // a "node" on PATH that is never run
    std::ofstream(dir / "bin" / "node") << "#!/bin/sh\nexit 1\n";
    std::filesystem::permissions(dir / "bin" / "node", std::filesystem::perms::owner_all);
  }
  ScopedEnv path("PATH", (dir / "bin").string());
  {
    ScopedEnv env("FEATHERDRIVE_PHYSX_DIR", dir.string());
    const std::string m = find_physx_message({});
    EXPECT_NE(m.find("FEATHERDRIVE_PHYSX_DIR = " + dir.string() + ": no harness.js"),
              std::string::npos)
        << m;
    EXPECT_NE(m.find("tests/physx/install.sh " + dir.string()), std::string::npos) << m;
  }
  {
    ScopedEnv env("FEATHERDRIVE_PHYSX_DIR", "");
    std::ofstream(dir / "harness.js") << "";
    const std::string m = find_physx_message({dir, dir / "other"});
    EXPECT_NE(m.find("looked in " + dir.string() + ", " + (dir / "other").string()),
              std::string::npos)
        << m;
    EXPECT_NE(m.find("make physx"), std::string::npos) << m;
    // With the package's two files the folder is found.
    std::filesystem::create_directories(dir / "node_modules" / "physx-js-webidl");
    std::ofstream(dir / "node_modules" / "physx-js-webidl" / "physx-js-webidl.mjs") << "";
    std::ofstream(dir / "node_modules" / "physx-js-webidl" / "physx-js-webidl.wasm") << "";
    const PhysxInstall found = find_physx({dir / "other", dir});
    EXPECT_EQ(found.dir, dir);
    EXPECT_EQ(found.node, (dir / "bin" / "node").string());
  }
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace featherdrive
