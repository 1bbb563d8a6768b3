// Model variants: a variant equals, bit for bit, the model ModelBuilder builds from the same
// parameters; bad parameters are refused as the builder refuses them; topology differences are
// named.
#include <gtest/gtest.h>

#include <cstring>
#include <limits>

#include "featherdrive/model/model_variant.hpp"
#include "support/models.hpp"
#include "support/compare.hpp"

namespace featherdrive {
namespace {

ModelBuilder two_links(double mass, const Vec3& com, const Mat3& inertia, double armature) {
  ModelBuilder b;
  b.add_link(make_link("base", "", 1.0, Vec3::Zero(), test::box_inertia(1, Vec3(.1, .2, .3)),
                       fixed_joint("weld")));
  JointSpec hinge = revolute_joint("hinge", Vec3(0, 1, 1), Vec3(0.1, 0, 0));
  hinge.armature = {armature};
  b.add_link(make_link("arm", "base", mass, com, inertia, hinge));
  return b;
}

using test::same_bits;

TEST(ModelVariant, EqualsTheModelBuiltWithTheSameParameters) {
  const Mat3 inertia = test::box_inertia(2.0, Vec3(0.1, 0.5, 0.2));
  const Model nominal = two_links(2.0, Vec3(0, 0.2, 0), inertia, 0.01).build();
  const Mat3 heavier = test::box_inertia(3.5, Vec3(0.1, 0.5, 0.2));
  const Model built = two_links(3.5, Vec3(0.01, 0.3, -0.02), heavier, 0.04).build();
  const Model varied =
      with_armature(with_link_inertial(nominal, 1, 3.5, Vec3(0.01, 0.3, -0.02), heavier),
                    VecX::Constant(1, 0.04));
  const Link& a = varied.links[1];
  const Link& b = built.links[1];
  EXPECT_EQ(a.mass, b.mass);
  EXPECT_TRUE(same_bits(a.com, b.com));
  EXPECT_TRUE(same_bits(a.inertia_com, b.inertia_com));
  EXPECT_TRUE(same_bits(a.inertia, b.inertia));
  EXPECT_TRUE(same_bits(varied.armature, built.armature));
  EXPECT_EQ(topology_difference(varied, nominal), "");
  EXPECT_FALSE(same_bits(nominal.links[1].inertia, b.inertia));
}

TEST(ModelVariant, BadParametersAreRefusedAsTheBuilderRefusesThem) {
  const Mat3 inertia = test::box_inertia(2.0, Vec3(0.1, 0.5, 0.2));
  const Model m = two_links(2.0, Vec3::Zero(), inertia, 0.0).build();
  auto message = [](auto f) {
    try {
      f();
    } catch (const ModelError& e) {
      return std::string(e.what());
    } catch (const std::invalid_argument& e) {
      return "invalid_argument: " + std::string(e.what());
    }
    return std::string("no throw");
  };
  EXPECT_EQ(message([&] { with_link_inertial(m, 1, -1.0, Vec3::Zero(), inertia); }),
            "model: link 'arm': mass = -1 must be > 0 for a link that can move");
  EXPECT_EQ(message([&] {
              with_link_inertial(m, 1, 1.0, Vec3(0, std::numeric_limits<double>::infinity(), 0),
                                 inertia);
            }),
            "model: link 'arm': com = [0, inf, 0] is not finite");
  EXPECT_NE(message([&] { with_link_inertial(m, 1, 1.0, Vec3::Zero(), -inertia); })
                .find("model: link 'arm': inertia is not positive definite"),
            std::string::npos);
  EXPECT_EQ(message([&] { with_link_inertial(m, 2, 1.0, Vec3::Zero(), inertia); }),
            "invalid_argument: link index 2 is out of range [0, 2)");
  EXPECT_EQ(message([&] { with_armature(m, VecX::Constant(1, -0.5)); }),
            "model: joint 'hinge': armature = -0.5 must be finite and >= 0 (dof 0)");
  EXPECT_EQ(message([&] { with_armature(m, VecX::Zero(2)); }),
            "model: armature has 2 values, expected nv = 1");
  // The welded base may be massless, as in the builder.
  EXPECT_EQ(with_link_inertial(m, 0, 0.0, Vec3::Zero(), Mat3::Zero()).links[0].mass, 0.0);
}

TEST(ModelVariant, TopologyDifferencesAreNamed) {
  const Mat3 inertia = test::box_inertia(2.0, Vec3(0.1, 0.5, 0.2));
  const Model a = two_links(2.0, Vec3::Zero(), inertia, 0.0).build();
  ModelBuilder other;
  other.add_link(make_link("base", "", 1.0, Vec3::Zero(), inertia, fixed_joint("weld")));
  other.add_link(make_link("arm", "base", 2.0, Vec3::Zero(), inertia,
                           prismatic_joint("hinge", Vec3(0, 1, 1), Vec3(0.1, 0, 0))));
  EXPECT_EQ(topology_difference(a, other.build()),
            "link 1 ('arm'): joint type revolute vs prismatic");
  EXPECT_EQ(topology_difference(a, *test::make_planar_chain(2, 1.0, 0.5)),
            "nq 1, nv 1, 2 links vs nq 2, nv 2, 3 links");
}

}  // namespace
}  // namespace featherdrive
