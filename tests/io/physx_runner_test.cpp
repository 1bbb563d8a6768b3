// The comparison logic of `featherdrive compare-physx` on trajectories whose differences are known
// by construction, the CSV reader's errors, and find_physx's messages (no node or PhysX needed).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "featherdrive/core/format.hpp"
#include "featherdrive/io/physx_runner.hpp"

namespace featherdrive {
namespace {

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

// Sets an environment variable for one scope.
class ScopedEnv {
 public:
  ScopedEnv(const char* name, const std::string& value) : name_(name) {
    if (const char* old = std::getenv(name)) old_ = old;
    had_ = std::getenv(name) != nullptr;
    ::setenv(name, value.c_str(), 1);
  }
  ~ScopedEnv() {
    if (had_)
      ::setenv(name_, old_.c_str(), 1);
    else
      ::unsetenv(name_);
  }

 private:
  const char* name_;
  std::string old_;
  bool had_ = false;
};

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
