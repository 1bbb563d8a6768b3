// ModelBuilder::build(): every validation error with its message (naming the link or joint, the
// field and the value), and the layout of a valid model (depth-first link order, q and v indices,
// dof names, per-dof parameters, frames, inertia).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <numbers>
#include <string>
#include <tuple>
#include <type_traits>
#include <vector>

#include "featherdrive/algorithm/crba.hpp"
#include "featherdrive/algorithm/frame_kinematics.hpp"
#include "featherdrive/algorithm/kinematics.hpp"
#include "featherdrive/model/model_builder.hpp"
#include "featherdrive/sim/simulation.hpp"
#include "support/models.hpp"
#include "support/compare.hpp"

namespace featherdrive {
namespace {

using ::testing::AllOf;
using ::testing::ElementsAre;
using ::testing::HasSubstr;
using ::testing::StartsWith;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
using test::kInf;

static_assert(std::is_base_of_v<std::invalid_argument, ModelError>);

/// The message of the ModelError that build() throws (a test failure if it throws nothing).
std::string build_error(const ModelBuilder& builder) {
  try {
    builder.build();
  } catch (const ModelError& e) {
    return e.what();
  }
  ADD_FAILURE() << "build() did not throw ModelError";
  return {};
}

LinkSpec base_link() {
  return make_link("base", "", 1.0, Vec3::Zero(), test::box_inertia(1.0, Vec3(0.1, 0.1, 0.1)),
                   fixed_joint("world_joint"));
}

LinkSpec arm_link() {
  return make_link("arm", "base", 2.0, Vec3(0, 0, -0.5),
                   test::box_inertia(2.0, Vec3(0.1, 0.1, 1.0)),
                   revolute_joint("shoulder", Vec3::UnitY(), Vec3(0, 0, 0.25)));
}

/// A fixed base and one revolute arm below it, the arm edited by `edit`.
ModelBuilder base_and_arm(const std::function<void(LinkSpec&)>& edit) {
  LinkSpec arm = arm_link();
  edit(arm);
  ModelBuilder b;
  b.add_link(base_link());
  b.add_link(arm);
  return b;
}

TEST(ModelBuilderValidation, ErrorTypeIsInvalidArgument) {
  ModelBuilder b;
  EXPECT_THROW(b.build(), ModelError);
  EXPECT_THROW(b.build(), std::invalid_argument);
}

TEST(ModelBuilderValidation, BaseAndArmIsValid) {
  const Model model = base_and_arm([](LinkSpec&) {}).build();
  EXPECT_EQ(model.num_links(), 2);
  EXPECT_EQ(model.nq, 1);
  EXPECT_EQ(model.nv, 1);
}

// ---- Whole-model errors
// --------------------------------------------------------------------------

TEST(ModelBuilderValidation, NoLinks) {
  EXPECT_EQ(build_error(ModelBuilder()), "model: the model has no links");
}

TEST(ModelBuilderValidation, GravityNotFinite) {
  ModelBuilder b = base_and_arm([](LinkSpec&) {});
  b.set_gravity(Vec3(0, kNaN, -10));
  EXPECT_EQ(build_error(b), "model: gravity = [0, nan, -10] is not finite");
  b.set_gravity(Vec3(kInf, 0, -10));
  EXPECT_EQ(build_error(b), "model: gravity = [inf, 0, -10] is not finite");
}

// ---- Names and the tree
// ----------------------------------------------------------------------------

TEST(ModelBuilderValidation, EmptyLinkName) {
  EXPECT_EQ(build_error(base_and_arm([](LinkSpec& l) { l.name.clear(); })),
            "model: link #1: name is empty");
}

TEST(ModelBuilderValidation, EmptyJointName) {
  EXPECT_EQ(build_error(base_and_arm([](LinkSpec& l) { l.joint.name.clear(); })),
            "model: link 'arm': joint name is empty");
}

TEST(ModelBuilderValidation, DuplicateLinkName) {
  ModelBuilder b = base_and_arm([](LinkSpec&) {});
  LinkSpec again = arm_link();
  again.joint.name = "elbow";
  b.add_link(again);
  EXPECT_EQ(build_error(b), "model: link 'arm': duplicate link name");
}

TEST(ModelBuilderValidation, DuplicateJointName) {
  ModelBuilder b = base_and_arm([](LinkSpec&) {});
  LinkSpec other = arm_link();
  other.name = "forearm";
  other.parent = "arm";
  b.add_link(other);  // joint "shoulder" again
  EXPECT_EQ(build_error(b), "model: joint 'shoulder': duplicate joint name (links 'arm' and 'forearm')");
}

TEST(ModelBuilderValidation, UnknownParent) {
  EXPECT_EQ(build_error(base_and_arm([](LinkSpec& l) { l.parent = "nope"; })),
            "model: link 'arm': parent = 'nope' is not a link of the model");
}

TEST(ModelBuilderValidation, MoreThanOneRoot) {
  ModelBuilder b = base_and_arm([](LinkSpec&) {});
  LinkSpec other = base_link();
  other.name = "other_base";
  other.joint.name = "other_world_joint";
  b.add_link(other);
  EXPECT_EQ(build_error(b),
            "model: more than one root: links 'base' and 'other_base' have no parent");
}

TEST(ModelBuilderValidation, CycleBesideTheRoot) {
  // base is the root; a -> b -> a is a cycle that never reaches it.
  ModelBuilder b;
  b.add_link(base_link());
  LinkSpec a = arm_link();
  a.name = "a";
  a.parent = "b";
  a.joint.name = "ja";
  LinkSpec c = arm_link();
  c.name = "b";
  c.parent = "a";
  c.joint.name = "jb";
  b.add_link(a);
  b.add_link(c);
  EXPECT_EQ(build_error(b), "model: links 'b' -> 'a' -> 'b' form a cycle (each names the next as parent)");
}

TEST(ModelBuilderValidation, LinkIsItsOwnParent) {
  EXPECT_EQ(build_error(base_and_arm([](LinkSpec& l) { l.parent = "arm"; })),
            "model: link 'arm': parent = 'arm' is the link itself");
}

TEST(ModelBuilderValidation, CycleAndNoRoot) {
  // Every link names a parent: there is no root (checked before the cycle it implies).
  LinkSpec a = arm_link();
  a.name = "a";
  a.parent = "b";
  a.joint.name = "ja";
  LinkSpec c = arm_link();
  c.name = "b";
  c.parent = "a";
  c.joint.name = "jb";
  ModelBuilder b;
  b.add_link(a);
  b.add_link(c);
  EXPECT_EQ(build_error(b), "model: the model has no root link (every link names a parent)");
}

TEST(ModelBuilderValidation, FloatingJointNotAtTheRoot) {
  EXPECT_EQ(build_error(base_and_arm([](LinkSpec& l) { l.joint = floating_joint("shoulder"); })),
            "model: joint 'shoulder': type = floating is allowed only for the root link's joint");
}

// ---- Joint geometry
// --------------------------------------------------------------------------------

TEST(ModelBuilderValidation, OriginXyzNotFinite) {
  EXPECT_EQ(build_error(base_and_arm([](LinkSpec& l) { l.joint.origin_xyz.x() = kNaN; })),
            "model: joint 'shoulder': origin_xyz = [nan, 0, 0.25] is not finite");
}

TEST(ModelBuilderValidation, OriginRpyNotFinite) {
  EXPECT_EQ(build_error(base_and_arm([](LinkSpec& l) { l.joint.origin_rpy.z() = -kInf; })),
            "model: joint 'shoulder': origin_rpy = [0, 0, -inf] is not finite");
}

TEST(ModelBuilderValidation, AxisNotFinite) {
  EXPECT_EQ(build_error(base_and_arm([](LinkSpec& l) { l.joint.axis = Vec3(kNaN, 1, 0); })),
            "model: joint 'shoulder': axis = [nan, 1, 0] is not finite");
}

TEST(ModelBuilderValidation, ZeroAxis) {
  EXPECT_EQ(build_error(base_and_arm([](LinkSpec& l) { l.joint.axis = Vec3::Zero(); })),
            "model: joint 'shoulder': axis = [0, 0, 0] is zero");
  EXPECT_EQ(build_error(base_and_arm(
                [](LinkSpec& l) { l.joint = prismatic_joint("slide", Vec3::Zero()); })),
            "model: joint 'slide': axis = [0, 0, 0] is zero");
  // Below 1e-12 in length counts as zero.
  EXPECT_THAT(build_error(base_and_arm([](LinkSpec& l) { l.joint.axis = Vec3(0, 1e-13, 0); })),
              AllOf(StartsWith("model: joint 'shoulder': axis = [0, "), HasSubstr("is zero")));
}

TEST(ModelBuilderValidation, AxisOfAFixedJointIsNotUsed) {
  // A zero axis means nothing for a fixed or spherical joint and is accepted.
  EXPECT_NO_THROW(base_and_arm([](LinkSpec& l) {
                    l.joint = fixed_joint("shoulder");
                    l.joint.axis = Vec3::Zero();
                  }).build());
}

// ---- Inertial ----------------------------------------------------------------------------------

TEST(ModelBuilderValidation, MassNotFinite) {
  EXPECT_EQ(build_error(base_and_arm([](LinkSpec& l) { l.mass = kNaN; })),
            "model: link 'arm': mass = nan is not finite");
  EXPECT_EQ(build_error(base_and_arm([](LinkSpec& l) { l.mass = kInf; })),
            "model: link 'arm': mass = inf is not finite");
}

TEST(ModelBuilderValidation, ComNotFinite) {
  EXPECT_EQ(build_error(base_and_arm([](LinkSpec& l) { l.com.y() = kInf; })),
            "model: link 'arm': com = [0, inf, -0.5] is not finite");
}

TEST(ModelBuilderValidation, InertiaEntryNotFinite) {
  EXPECT_EQ(build_error(base_and_arm([](LinkSpec& l) { l.inertia(1, 2) = kNaN; })),
            "model: link 'arm': inertia(1,2) = nan is not finite");
  EXPECT_EQ(build_error(base_and_arm([](LinkSpec& l) { l.inertia(0, 0) = -kInf; })),
            "model: link 'arm': inertia(0,0) = -inf is not finite");
}

TEST(ModelBuilderValidation, MassNotPositiveOnAMovingLink) {
  EXPECT_EQ(build_error(base_and_arm([](LinkSpec& l) { l.mass = 0.0; })),
            "model: link 'arm': mass = 0 must be > 0 for a link that can move");
  EXPECT_EQ(build_error(base_and_arm([](LinkSpec& l) { l.mass = -2.0; })),
            "model: link 'arm': mass = -2 must be > 0 for a link that can move");
}

TEST(ModelBuilderValidation, MasslessMovingLinkAboveAMass) {
  // Two hinges at one point (an MJCF body with two joints): the first link is massless, its dof
  // moves the second link's mass. At q = 0 the mass matrix is the inertia about the joint point,
  // I_o = I_c + m (|c|^2 1 - c c^T), projected on the axes y and x.
  const double m = 2.0;
  const Vec3 c(0.1, 0.05, -0.5);
  const Mat3 I_c = test::box_inertia(m, Vec3(0.1, 0.2, 1.0));
  ModelBuilder b;
  b.add_link(base_link());
  b.add_link(make_link("arm", "base", 0.0, Vec3::Zero(), Mat3::Zero(),
                       revolute_joint("pitch", Vec3::UnitY(), Vec3(0, 0, 0.25))));
  b.add_link(make_link("fore", "arm", m, c, I_c, revolute_joint("roll", Vec3::UnitX())));
  const Model model = b.build();
  Data data(model);
  const MatX& M = crba(model, data, VecX::Zero(2));
  const Mat3 I_o = I_c + m * (c.squaredNorm() * Mat3::Identity() - c * c.transpose());
  EXPECT_NEAR(M(0, 0), I_o(1, 1), 1e-15);
  EXPECT_NEAR(M(0, 1), I_o(1, 0), 1e-15);
  EXPECT_NEAR(M(1, 1), I_o(0, 0), 1e-15);
}

TEST(ModelBuilderValidation, MasslessLinkFixedToAMovingLink) {
  // A link welded to a moving link moves with it, so it needs a mass too.
  ModelBuilder b = base_and_arm([](LinkSpec&) {});
  b.add_link(make_link("tool", "arm", 0.0, Vec3::Zero(), Mat3::Zero(), fixed_joint("tool_joint")));
  EXPECT_EQ(build_error(b), "model: link 'tool': mass = 0 must be > 0 for a link that can move");
}

TEST(ModelBuilderValidation, MasslessLinksWeldedToTheWorld) {
  // A massless root and a massless link welded to it are fine with zero inertia ...
  ModelBuilder ok;
  ok.add_link(make_link("world_frame", "", 0.0, Vec3::Zero(), Mat3::Zero(), fixed_joint("w")));
  ok.add_link(make_link("mount", "world_frame", 0.0, Vec3::Zero(), Mat3::Zero(),
                        fixed_joint("m", Vec3(0, 0, 1))));
  LinkSpec arm = arm_link();
  arm.parent = "mount";
  ok.add_link(arm);
  EXPECT_NO_THROW(ok.build());
  // ... but not with an inertia.
  ModelBuilder bad;
  bad.add_link(make_link("world_frame", "", 0.0, Vec3::Zero(), Mat3::Identity(), fixed_joint("w")));
  EXPECT_EQ(build_error(bad),
            "model: link 'world_frame': inertia must be zero for a massless link (mass = 0), got principal moments [1, 1, 1]");
  // A negative mass is rejected even where the link cannot move.
  ModelBuilder negative;
  negative.add_link(
      make_link("world_frame", "", -1.0, Vec3::Zero(), Mat3::Identity(), fixed_joint("w")));
  EXPECT_THAT(build_error(negative),
              AllOf(StartsWith("model: link 'world_frame': "), HasSubstr("mass = -1")));
}

TEST(ModelBuilderValidation, InertiaNotSymmetric) {
  EXPECT_EQ(
      build_error(base_and_arm([](LinkSpec& l) {
        l.inertia(0, 1) = 0.25;
        l.inertia(1, 0) = 0.5;
      })),
      "model: link 'arm': inertia is not symmetric: inertia(0,1) = 0.25 but inertia(1,0) = 0.5");
  // Asymmetry below 1e-9 of the largest entry is rounding and is symmetrised away.
  const Model model = base_and_arm([](LinkSpec& l) {
                        l.inertia(0, 2) = 1e-12;
                        l.inertia(2, 0) = 0.0;
                      }).build();
  EXPECT_EQ(model.links[1].inertia_com(0, 2), 0.5e-12);
  EXPECT_EQ(model.links[1].inertia_com(2, 0), 0.5e-12);
}

TEST(ModelBuilderValidation, InertiaNotPositiveDefinite) {
  EXPECT_EQ(build_error(base_and_arm([](LinkSpec& l) { l.inertia.setZero(); })),
            "model: link 'arm': inertia is not positive definite: principal moments [0, 0, 0]");
  EXPECT_EQ(build_error(base_and_arm([](LinkSpec& l) { l.inertia = Vec3(2, -1, 2).asDiagonal(); })),
            "model: link 'arm': inertia is not positive definite: principal moments [-1, 2, 2]");
}

TEST(ModelBuilderValidation, InertiaBreaksTheTriangleInequality) {
  EXPECT_EQ(build_error(base_and_arm([](LinkSpec& l) { l.inertia = Vec3(1, 3, 1).asDiagonal(); })),
            "model: link 'arm': inertia breaks the triangle inequality: principal moments "
            "[1, 1, 3] (1 + 1 < 3)");
  // A flat plate is the limit (Izz = Ixx + Iyy) and is accepted.
  EXPECT_NO_THROW(
      base_and_arm([](LinkSpec& l) { l.inertia = Vec3(1, 2, 3).asDiagonal(); }).build());
}

// ---- Per-dof parameters
// ---------------------------------------------------------------------------

TEST(ModelBuilderValidation, ArmatureSize) {
  EXPECT_EQ(build_error(base_and_arm([](LinkSpec& l) {
              l.joint = spherical_joint("shoulder");
              l.joint.armature = {0.1, 0.2};
            })),
            "model: joint 'shoulder': armature has 2 values, expected 1 or 3 (one per dof)");
  EXPECT_THAT(build_error(base_and_arm([](LinkSpec& l) {
                l.joint.armature = {0.1, 0.2};
              })),
              AllOf(StartsWith("model: joint 'shoulder': "), HasSubstr("armature has 2 values")));
}

TEST(ModelBuilderValidation, ArmatureNegativeOrNotFinite) {
  EXPECT_EQ(build_error(base_and_arm([](LinkSpec& l) { l.joint.armature = {-0.5}; })),
            "model: joint 'shoulder': armature = -0.5 must be finite and >= 0");
  EXPECT_EQ(build_error(base_and_arm([](LinkSpec& l) {
              l.joint = spherical_joint("shoulder");
              l.joint.armature = {0.5, kNaN, 0.5};
            })),
            "model: joint 'shoulder': armature = nan must be finite and >= 0");
}

TEST(ModelBuilderValidation, LowerLimitAboveUpperLimit) {
  EXPECT_EQ(build_error(base_and_arm([](LinkSpec& l) {
              l.joint.lower_limit = 1.0;
              l.joint.upper_limit = -1.5;
            })),
            "model: joint 'shoulder': lower_limit = 1 is above upper_limit = -1.5");
  // Equal limits (a locked joint) are allowed.
  EXPECT_NO_THROW(base_and_arm([](LinkSpec& l) {
                    l.joint.lower_limit = 0.5;
                    l.joint.upper_limit = 0.5;
                  }).build());
}

TEST(ModelBuilderValidation, LimitIsNaN) {
  EXPECT_EQ(build_error(base_and_arm([](LinkSpec& l) { l.joint.lower_limit = kNaN; })),
            "model: joint 'shoulder': lower_limit is NaN");
  EXPECT_EQ(build_error(base_and_arm([](LinkSpec& l) { l.joint.upper_limit = kNaN; })),
            "model: joint 'shoulder': upper_limit is NaN");
}

TEST(ModelBuilderValidation, LimitOfInfOnTheWrongSide) {
  EXPECT_EQ(build_error(base_and_arm([](LinkSpec& l) { l.joint.lower_limit = kInf; })),
            "model: joint 'shoulder': lower_limit = inf leaves no position");
  EXPECT_EQ(build_error(base_and_arm([](LinkSpec& l) {
              l.joint.lower_limit = kInf;
              l.joint.upper_limit = kInf;
            })),
            "model: joint 'shoulder': lower_limit = inf leaves no position");
  EXPECT_EQ(build_error(base_and_arm([](LinkSpec& l) {
              l.joint.lower_limit = -kInf;
              l.joint.upper_limit = -kInf;
            })),
            "model: joint 'shoulder': upper_limit = -inf leaves no position");
  const Model open = base_and_arm([](LinkSpec&) {}).build();  // -inf, inf: no limits
  EXPECT_EQ(open.lower_limit[0], -kInf);
  // The simulation's setter (Python's set_joint_limits and the scene reach it) says the same.
  Simulation sim(std::make_shared<const Model>(open));
  for (const auto& [lower, upper, error] :
       {std::tuple{kInf, kInf, "lower = inf"}, std::tuple{-kInf, -kInf, "upper = -inf"},
        std::tuple{kInf, 1.0, "lower = inf"}, std::tuple{-1.0, -kInf, "upper = -inf"}}) {
    try {
      sim.set_joint_limits(0, lower, upper);
      ADD_FAILURE() << lower << " " << upper;
    } catch (const std::invalid_argument& e) {
      EXPECT_EQ(std::string(e.what()),
                std::string("limits on joint 'shoulder': ") + error + " leaves no position");
    }
  }
  sim.set_joint_limits(0, -kInf, kInf);
  sim.set_joint_limits(0, -kInf, -1e308);
  EXPECT_EQ(sim.upper_limit(0), -1e308);
}

TEST(ModelBuilderValidation, NamesWithControlCharacters) {
  EXPECT_EQ(build_error(base_and_arm([](LinkSpec& l) { l.name = "arm\n2"; })),
            "model: link name 'arm\\x0a2' contains a control character (0x0a)");
  EXPECT_EQ(build_error(base_and_arm([](LinkSpec& l) { l.joint.name = std::string("a\0b", 3); })),
            "model: joint name 'a\\x00b' contains a control character (0x00)");
  EXPECT_EQ(build_error(base_and_arm([](LinkSpec& l) { l.joint.name = "\t\x7f"; })),
            "model: joint name '\\x09\\x7f' contains a control character (0x09)");
  EXPECT_EQ(name_problem("a, \"b\" \xc3\xa9"), "");
  EXPECT_EQ(name_problem("\r"), "name '\\x0d' contains a control character (0x0d)");
}

TEST(ModelBuilderValidation, InertiasWhoseProductsOrSumsOverflow) {
  EXPECT_EQ(build_error(base_and_arm([](LinkSpec& l) { l.com = Vec3(0, 1e160, 0); })),
            "model: link 'arm': mass = 2 at com = [0, 1e+160, 0]: the spatial inertia (m c, "
            "m c c^T) overflows");
  EXPECT_EQ(build_error(base_and_arm([](LinkSpec& l) {
              l.mass = 1e308;
              l.com = Vec3(0, 0, 10);
            })),
            "model: link 'arm': mass = 1e+308 at com = [0, 0, 10]: the spatial inertia (m c, "
            "m c c^T) overflows");
  // Each link finite, their sum not.
  ModelBuilder b;
  b.add_link(make_link("base", "", 5e307, Vec3::Zero(), Mat3::Identity(), fixed_joint("w")));
  b.add_link(make_link("arm", "base", 5e307, Vec3::Zero(), Mat3::Identity(),
                       revolute_joint("j", Vec3::UnitZ())));
  EXPECT_EQ(build_error(b),
            "model: link 'arm': mass = 5e+307, inertia [1, 1, 1]: the model's "
            "total mass or inertia overflows");
}

// Long chains and long cycles are checked in O(n), without recursion.
TEST(ModelBuilderValidation, HundredThousandLinkChainsAndCycles) {
  const int n = 100000;
  const Mat3 I = test::box_inertia(1.0, Vec3(0.1, 0.1, 0.1));
  ModelBuilder chain;
  chain.add_link(make_link("l0", "", 1.0, Vec3::Zero(), I, fixed_joint("j0")));
  for (int i = 1; i < n; ++i)
    chain.add_link(make_link("l" + std::to_string(i), "l" + std::to_string(i - 1), 1.0,
                             Vec3::Zero(), I,
                             revolute_joint("j" + std::to_string(i), Vec3::UnitZ())));
  const Model m = chain.build();
  EXPECT_EQ(m.nv, n - 1);
  EXPECT_EQ(m.links.back().parent, n - 2);
  EXPECT_EQ(m.links[0].subtree_end, n);

  // The same links in a ring beside a root: named once around from where the walk closes.
  ModelBuilder ring;
  ring.add_link(make_link("root", "", 1.0, Vec3::Zero(), I, fixed_joint("w")));
  for (int i = 0; i < n; ++i)
    ring.add_link(make_link("r" + std::to_string(i), "r" + std::to_string((i + 1) % n), 1.0,
                            Vec3::Zero(), I,
                            revolute_joint("k" + std::to_string(i), Vec3::UnitZ())));
  const std::string e = build_error(ring);
  EXPECT_THAT(e, StartsWith("model: links 'r"));
  EXPECT_THAT(e, HasSubstr("'r99999' -> 'r0' -> 'r1'"));
  EXPECT_THAT(e, HasSubstr("' form a cycle (each names the next as parent)"));
}

TEST(ModelBuilderValidation, EffortAndVelocityLimits) {
  EXPECT_EQ(build_error(base_and_arm([](LinkSpec& l) { l.joint.effort_limit = -1.0; })),
            "model: joint 'shoulder': effort_limit = -1 must be >= 0");
  EXPECT_EQ(build_error(base_and_arm([](LinkSpec& l) { l.joint.effort_limit = kNaN; })),
            "model: joint 'shoulder': effort_limit = nan must be >= 0");
  EXPECT_EQ(build_error(base_and_arm([](LinkSpec& l) { l.joint.velocity_limit = -2.0; })),
            "model: joint 'shoulder': velocity_limit = -2 must be >= 0");
}

TEST(ModelBuilderValidation, DampingAndFriction) {
  EXPECT_EQ(build_error(base_and_arm([](LinkSpec& l) { l.joint.damping = -0.25; })),
            "model: joint 'shoulder': damping = -0.25 must be finite and >= 0");
  EXPECT_EQ(build_error(base_and_arm([](LinkSpec& l) { l.joint.damping = kInf; })),
            "model: joint 'shoulder': damping = inf must be finite and >= 0");
  EXPECT_EQ(build_error(base_and_arm([](LinkSpec& l) { l.joint.friction = -3.0; })),
            "model: joint 'shoulder': friction = -3 must be finite and >= 0");
}

// ---- Layout of a valid model
// ---------------------------------------------------------------------

std::vector<std::string> link_names(const Model& model) {
  std::vector<std::string> names;
  for (const Link& link : model.links) names.push_back(link.name);
  return names;
}

TEST(ModelBuilderLayout, LinksInDepthFirstPreorderWithChildrenInInsertionOrder) {
  // Tree: r -> {c1 -> {h}, c2 -> {g, g2}}, given in an order that is not depth-first.
  auto link = [](const std::string& name, const std::string& parent) {
    return make_link(
        name, parent, 1.0, Vec3::Zero(), test::box_inertia(1.0, Vec3(0.1, 0.2, 0.3)),
        parent.empty() ? fixed_joint("j_" + name) : revolute_joint("j_" + name, Vec3::UnitZ()));
  };
  ModelBuilder b;
  b.add_link(link("c1", "r"));
  b.add_link(link("g", "c2"));
  b.add_link(link("r", ""));
  b.add_link(link("c2", "r"));
  b.add_link(link("h", "c1"));
  b.add_link(link("g2", "c2"));
  const Model model = b.build();

  EXPECT_THAT(link_names(model), ElementsAre("r", "c1", "h", "c2", "g", "g2"));
  const std::vector<int> parents{-1, 0, 1, 0, 3, 3};
  const std::vector<int> subtree_ends{6, 3, 3, 6, 5, 6};
  for (int i = 0; i < model.num_links(); ++i) {
    EXPECT_EQ(model.links[i].parent, parents[static_cast<size_t>(i)]) << i;
    EXPECT_EQ(model.links[i].subtree_end, subtree_ends[static_cast<size_t>(i)]) << i;
    EXPECT_LT(model.links[i].parent, i);  // parents come first
  }
  EXPECT_THAT(model.links[0].children, ElementsAre(1, 3));
  EXPECT_THAT(model.links[1].children, ElementsAre(2));
  EXPECT_TRUE(model.links[2].children.empty());
  EXPECT_THAT(model.links[3].children, ElementsAre(4, 5));

  // Dofs follow the link order.
  EXPECT_EQ(model.nq, 5);
  EXPECT_EQ(model.nv, 5);
  EXPECT_THAT(model.dof_names, ElementsAre("j_c1", "j_h", "j_c2", "j_g", "j_g2"));
  EXPECT_THAT(model.dof_link, ElementsAre(1, 2, 3, 4, 5));
  for (int i = 1; i < model.num_links(); ++i) {
    EXPECT_EQ(model.links[i].q_index, i - 1);
    EXPECT_EQ(model.links[i].v_index, i - 1);
  }
  EXPECT_EQ(model.link_index("g"), 4);
  EXPECT_EQ(model.joint_link_index("j_g"), 4);
  EXPECT_EQ(model.dof_index("j_g"), 3);
}

TEST(ModelBuilderLayout, SizesAndIndicesOfEveryJointType) {
  ModelBuilder b;
  const Mat3 I = test::box_inertia(1.0, Vec3(0.1, 0.2, 0.3));
  LinkSpec root = make_link("body", "", 5.0, Vec3::Zero(), I, floating_joint("free"));
  root.joint.armature = {1, 2, 3, 4, 5, 6};
  b.add_link(root);
  LinkSpec ball = make_link("ball_link", "body", 1.0, Vec3::Zero(), I, spherical_joint("ball"));
  ball.joint.armature = {0.5};
  ball.joint.lower_limit = -1.0;  // not used: limits apply to one-dof joints only
  ball.joint.upper_limit = 1.0;
  b.add_link(ball);
  LinkSpec hinge = make_link("hinge_link", "ball_link", 1.0, Vec3::Zero(), I,
                             revolute_joint("hinge", Vec3::UnitX()));
  hinge.joint.lower_limit = -0.5;
  hinge.joint.upper_limit = 0.75;
  hinge.joint.effort_limit = 10.0;
  hinge.joint.velocity_limit = 2.0;
  hinge.joint.damping = 0.1;
  hinge.joint.friction = 0.2;
  b.add_link(hinge);
  b.add_link(make_link("slide_link", "body", 1.0, Vec3::Zero(), I,
                       prismatic_joint("slide", Vec3::UnitY())));
  b.add_link(make_link("weld_link", "slide_link", 1.0, Vec3::Zero(), I, fixed_joint("weld")));
  const Model model = b.build();

  EXPECT_TRUE(model.floating_base());
  EXPECT_THAT(link_names(model),
              ElementsAre("body", "ball_link", "hinge_link", "slide_link", "weld_link"));
  struct Expected {
    int nq, nv, q_index, v_index;
  };
  const std::vector<Expected> expected{
      {7, 6, 0, 0}, {4, 3, 7, 6}, {1, 1, 11, 9}, {1, 1, 12, 10}, {0, 0, 13, 11}};
  for (int i = 0; i < model.num_links(); ++i) {
    const Expected& e = expected[static_cast<size_t>(i)];
    const Link& link = model.links[i];
    EXPECT_EQ(link.nq, e.nq) << link.name;
    EXPECT_EQ(link.nv, e.nv) << link.name;
    EXPECT_EQ(link.q_index, e.q_index) << link.name;
    EXPECT_EQ(link.v_index, e.v_index) << link.name;
    EXPECT_EQ(link.motion_subspace.cols(), e.nv) << link.name;
  }
  EXPECT_EQ(model.nq, 13);
  EXPECT_EQ(model.nv, 11);
  EXPECT_THAT(model.dof_names,
              ElementsAre("free:wx", "free:wy", "free:wz", "free:vx", "free:vy", "free:vz",
                          "ball:twist", "ball:swing1", "ball:swing2", "hinge", "slide"));
  EXPECT_THAT(model.dof_link, ElementsAre(0, 0, 0, 0, 0, 0, 1, 1, 1, 2, 3));
  EXPECT_EQ(model.dof_index("free"), 0);
  EXPECT_EQ(model.dof_index("ball"), 6);
  EXPECT_EQ(model.dof_index("hinge"), 9);
  EXPECT_EQ(model.dof_index("slide"), 10);
  EXPECT_THROW(model.dof_index("weld"), std::invalid_argument);
  EXPECT_THROW(model.dof_index("nope"), std::invalid_argument);

  // Neutral configuration: identity quaternions (w first), everything else zero.
  VecX neutral = VecX::Zero(13);
  neutral[3] = 1.0;
  neutral[7] = 1.0;
  EXPECT_EQ(model.neutral_configuration(), neutral);

  // Per-dof parameters: one armature value broadcasts over a joint's dofs; limits only for
  // one-dof joints; defaults are unbounded and zero.
  VecX armature(11);
  armature << 1, 2, 3, 4, 5, 6, 0.5, 0.5, 0.5, 0, 0;
  EXPECT_EQ(model.armature, armature);
  for (int d = 0; d < 9; ++d) {
    EXPECT_EQ(model.lower_limit[d], -kInf) << d;
    EXPECT_EQ(model.upper_limit[d], kInf) << d;
  }
  EXPECT_EQ(model.lower_limit[9], -0.5);
  EXPECT_EQ(model.upper_limit[9], 0.75);
  EXPECT_EQ(model.effort_limit[9], 10.0);
  EXPECT_EQ(model.velocity_limit[9], 2.0);
  EXPECT_EQ(model.damping[9], 0.1);
  EXPECT_EQ(model.friction[9], 0.2);
  EXPECT_EQ(model.lower_limit[10], -kInf);
  EXPECT_EQ(model.upper_limit[10], kInf);
  EXPECT_EQ(model.effort_limit[10], kInf);
  EXPECT_EQ(model.velocity_limit[10], kInf);
  EXPECT_EQ(model.damping[10], 0.0);
  EXPECT_EQ(model.friction[10], 0.0);
}

TEST(ModelBuilderLayout, MotionSubspaces) {
  const auto model = test::make_random_tree(3, 12, /*floating=*/true, /*spherical=*/true);
  for (const Link& link : model->links) {
    Mat6N S = Mat6N::Zero(6, link.nv);
    switch (link.joint_type) {
      case JointType::revolute:
        S.col(0).head<3>() = link.axis;
        break;
      case JointType::prismatic:
        S.col(0).tail<3>() = link.axis;
        break;
      case JointType::spherical:
        S.topRows<3>().setIdentity();
        break;
      case JointType::floating:
        S.setIdentity();
        break;
      case JointType::fixed:
        break;
    }
    EXPECT_EQ(link.motion_subspace, S) << link.name;
    if (link.nv == 1) {
      EXPECT_NEAR(link.axis.norm(), 1.0, 1e-15) << link.name;
    }
  }
}

TEST(ModelBuilderLayout, JointFrameAxisAndInertia) {
  const Vec3 xyz(0.1, -0.2, 0.3);
  const Vec3 rpy(0.4, -0.5, 0.6);
  const Vec3 com(0.05, 0.01, -0.3);
  Mat3 Ic;
  Ic << 0.3, 0.01, -0.02, 0.01, 0.4, 0.03, -0.02, 0.03, 0.5;
  ModelBuilder b;
  b.add_link(base_link());
  b.add_link(make_link("arm", "base", 2.0, com, Ic, revolute_joint("j", Vec3(0, 3, 4), xyz, rpy)));
  const Model model = b.build();
  const Link& arm = model.links[1];

  // The axis is normalised; the joint name and type are kept.
  EXPECT_TRUE(arm.axis.isApprox(Vec3(0, 0.6, 0.8), 1e-15));
  EXPECT_EQ(arm.joint_name, "j");
  EXPECT_EQ(arm.joint_type, JointType::revolute);

  // X_T: E = R^T with R = Rz(yaw) Ry(pitch) Rx(roll) the joint frame's orientation in the parent,
  // r = the joint frame's origin in the parent.
  const double cr = std::cos(rpy.x()), sr = std::sin(rpy.x());
  const double cp = std::cos(rpy.y()), sp = std::sin(rpy.y());
  const double cy = std::cos(rpy.z()), sy = std::sin(rpy.z());
  Mat3 Rx, Ry, Rz;
  Rx << 1, 0, 0, 0, cr, -sr, 0, sr, cr;
  Ry << cp, 0, sp, 0, 1, 0, -sp, 0, cp;
  Rz << cy, -sy, 0, sy, cy, 0, 0, 0, 1;
  const Mat3 R = Rz * Ry * Rx;
  EXPECT_TRUE(arm.tree_transform.E.isApprox(R.transpose(), 1e-14));
  EXPECT_EQ(arm.tree_transform.r, xyz);
  // Roll pi/2 turns the joint frame's y axis onto the parent's z axis.
  EXPECT_TRUE(
      rotation_from_rpy(Vec3(std::numbers::pi / 2, 0, 0)).col(1).isApprox(Vec3::UnitZ(), 1e-15));

  // Inertia: mass, com and the inertia about the com as given; the spatial inertia about the
  // link origin is [Ic + m c~ c~^T, m c~; m c~^T, m 1].
  EXPECT_EQ(arm.mass, 2.0);
  EXPECT_EQ(arm.com, com);
  EXPECT_EQ(arm.inertia_com, Ic);
  const Mat3 C = skew(com);
  Mat6 I;
  I << Ic + 2.0 * C * C.transpose(), 2.0 * C, 2.0 * C.transpose(), 2.0 * Mat3::Identity();
  EXPECT_TRUE(arm.inertia.isApprox(I, 1e-15));
}

TEST(ModelBuilderLayout, Gravity) {
  EXPECT_EQ(base_and_arm([](LinkSpec&) {}).build().gravity, Vec3(0, 0, -9.81));
  ModelBuilder b = base_and_arm([](LinkSpec&) {});
  b.set_gravity(Vec3(1, 2, 3));
  EXPECT_EQ(b.build().gravity, Vec3(1, 2, 3));
}

}  // namespace
}  // namespace featherdrive

namespace featherdrive {
namespace {

// A named frame (a merged link's) against the same link kept as a massless fixed-joint link of
// an unmerged model: the same world pose for every configuration and point.
TEST(ModelBuilderFrames, FrameEqualsTheUnmergedFixedLink) {
  const Mat3 eye = Mat3::Identity();
  const Vec3 xyz(0.05, -0.02, 0.1), rpy(0.3, -0.2, 0.7);
  auto chain = [&](ModelBuilder& b) {
    b.add_link(make_link("base", "", 0.0, Vec3::Zero(), Mat3::Zero(), fixed_joint("root")));
    b.add_link(make_link("a", "base", 1.0, Vec3(0, 0, 0.1), 0.01 * eye,
                         revolute_joint("j1", Vec3::UnitZ(), Vec3(0, 0, 0.2))));
    b.add_link(make_link("b", "a", 2.0, Vec3(0.1, 0, 0), 0.02 * eye,
                         revolute_joint("j2", Vec3(0, 1, 1), Vec3(0.3, 0, 0), Vec3(0.1, 0, 0))));
  };
  ModelBuilder unmerged, merged;
  chain(unmerged);
  chain(merged);
  // (a link below a moving one needs mass; the kinematics compared do not depend on it)
  unmerged.add_link(make_link("tcp", "b", 0.1, Vec3::Zero(), 1e-3 * eye,
                              fixed_joint("tcp_joint", xyz, rpy)));
  merged.add_frame("tcp", "b", xyz, rotation_from_rpy(rpy));
  const Model u = unmerged.build(), m = merged.build();
  ASSERT_EQ(m.frames.size(), 1u);
  const NamedFrame f = m.frame("tcp");
  EXPECT_EQ(f.link, m.link_index("b"));
  const NamedFrame itself = m.frame("a");  // a link is its own frame
  EXPECT_EQ(itself.link, m.link_index("a"));
  EXPECT_EQ(itself.position, Vec3::Zero());
  Data du(u), dm(m);
  const Vec3 point(0.01, 0.02, -0.03);
  const std::vector<std::pair<double, double>> configurations{
      {0.0, 0.0}, {0.7, -1.2}, {-2.0, 0.4}};
  for (const auto& [q0, q1] : configurations) {
    VecX q(2), qd(2);
    q << q0, q1;
    qd << 0.5, -0.3;
    forward_kinematics(u, du, q, qd);
    forward_kinematics(m, dm, q, qd);
    const int t = u.link_index("tcp");
    EXPECT_LT((frame_rotation(m, dm, f) - du.world_rotation[t]).norm(), 1e-14);
    EXPECT_LT((frame_position(m, dm, f, point) - frame_position(u, du, t, point)).norm(), 1e-14);
    for (ReferenceFrame r : {ReferenceFrame::local, ReferenceFrame::world_aligned})
      EXPECT_LT((frame_velocity(m, dm, f, point, r) - frame_velocity(u, du, t, point, r)).norm(),
                1e-13);
  }
}

TEST(ModelBuilderFrames, BadFramesAndUnknownNames) {
  auto model_with = [](const std::string& name, const std::string& link, const Vec3& xyz) {
    ModelBuilder b;
    b.add_link(make_link("base", "", 0.0, Vec3::Zero(), Mat3::Zero(), fixed_joint("root")));
    b.add_link(make_link("tool", "base", 1.0, Vec3::Zero(), 0.01 * Mat3::Identity(),
                         revolute_joint("j", Vec3::UnitZ())));
    b.add_frame(name, link, xyz, Mat3::Identity());
    return b.build();
  };
  auto message = [](const std::function<void()>& f) -> std::string {
    try {
      f();
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "(no exception)";
  };
  EXPECT_EQ(message([&] { model_with("tool", "base", Vec3::Zero()); }),
            "model: frame 'tool': a link has this name");
  EXPECT_EQ(message([&] { model_with("tcp", "hand", Vec3::Zero()); }),
            "model: frame 'tcp': link = 'hand' is not a link of the model");
  EXPECT_THAT(message([&] { model_with("tcp", "tool", Vec3(kNaN, 0, 0)); }),
              StartsWith("model: frame 'tcp': xyz = "));
  const Model m = model_with("tcp", "tool", Vec3(0, 0, 0.1));
  EXPECT_THAT(message([&] { m.frame("tpc"); }),
              StartsWith("no link or frame named 'tpc'; nearest: 'tcp', "));
  EXPECT_THAT(message([&] { m.link_index("tol"); }),
              StartsWith("no link named 'tol' in the model; nearest: 'tool', "));
}

}  // namespace
}  // namespace featherdrive
