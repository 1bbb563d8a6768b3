// Collision shapes in the Model (issue 34): ModelBuilder::add_shape and with_shapes keep them
// grouped by link in link order, place a merged link's shapes on its link with the composed pose,
// and refuse every bad size, pose and material in one line naming shape, link, field and value;
// an enabled ground is refused while the model has geometry contacts cannot use.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "featherdrive/model/model_builder.hpp"
#include "featherdrive/model/model_variant.hpp"
#include "featherdrive/sim/simulation.hpp"
#include "support/models.hpp"

namespace featherdrive {
namespace {

using ::testing::HasSubstr;

// base (fixed) -> upper (revolute y) -> lower (revolute y); "tool" a frame on lower.
ModelBuilder shapes_chain() {
  const Mat3 I = test::box_inertia(1.0, Vec3(0.1, 0.1, 0.5));
  ModelBuilder b;
  b.add_link(make_link("base", "", 1.0, Vec3::Zero(), I, fixed_joint("world_joint")));
  b.add_link(make_link("upper", "base", 1.0, Vec3(0, 0, -0.25), I,
                       revolute_joint("hip", Vec3::UnitY(), Vec3(0, 0, -0.1))));
  b.add_link(make_link("lower", "upper", 1.0, Vec3(0, 0, -0.25), I,
                       revolute_joint("knee", Vec3::UnitY(), Vec3(0, 0, -0.5))));
  b.add_frame("tool", "lower", Vec3(0.1, 0.0, -0.5),
              Eigen::AngleAxisd(0.5, Vec3::UnitX()).toRotationMatrix());
  return b;
}

CollisionShape make_shape(const std::string& name, ShapeType type, const Vec3& size) {
  CollisionShape s;
  s.name = name;
  s.type = type;
  s.size = size;
  return s;
}

std::string shape_error(const std::function<void()>& f) {
  try {
    f();
  } catch (const ModelError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no ModelError";
  return {};
}

TEST(ModelShapes, KeptGroupedByLinkInLinkOrderAndInInsertionOrderWithinALink) {
  ModelBuilder b = shapes_chain();
  b.add_shape("lower", make_shape("foot", ShapeType::sphere, Vec3(0.05, 0, 0)));
  b.add_shape("base", make_shape("body", ShapeType::box, Vec3(0.2, 0.1, 0.05)));
  b.add_shape("upper", make_shape("thigh", ShapeType::capsule, Vec3(0.03, 0.2, 0)));
  b.add_shape("lower", make_shape("shin", ShapeType::capsule, Vec3(0.02, 0.2, 0)));
  const Model m = b.build();
  ASSERT_EQ(m.shapes.size(), 4u);
  const std::vector<std::string> names = {m.shapes[0].name, m.shapes[1].name, m.shapes[2].name,
                                          m.shapes[3].name};
  EXPECT_EQ(names, (std::vector<std::string>{"body", "thigh", "foot", "shin"}));
  EXPECT_EQ(m.shapes[0].link, m.link_index("base"));
  EXPECT_EQ(m.shapes[1].link, m.link_index("upper"));
  EXPECT_EQ(m.shapes[2].link, m.link_index("lower"));
  EXPECT_TRUE(m.unsupported_shapes.empty());

  // with_shapes adds after the model's own within a link, and keeps the order by link.
  const Model more = with_shapes(
      m, {{"base", make_shape("nose", ShapeType::sphere, Vec3(0.01, 0, 0))},
          {"upper", make_shape("knee_pad", ShapeType::sphere, Vec3(0.02, 0, 0))}});
  ASSERT_EQ(more.shapes.size(), 6u);
  EXPECT_EQ(more.shapes[0].name, "body");
  EXPECT_EQ(more.shapes[1].name, "nose");
  EXPECT_EQ(more.shapes[2].name, "thigh");
  EXPECT_EQ(more.shapes[3].name, "knee_pad");
  EXPECT_EQ(more.shapes[4].name, "foot");
  for (size_t i = 1; i < more.shapes.size(); ++i)
    EXPECT_LE(more.shapes[i - 1].link, more.shapes[i].link);
}

TEST(ModelShapes, AShapeOnAFrameGoesToItsLinkWithThePoseComposed) {
  // x_link = p_f + R_f x_frame, so the shape's pose in the link is (p_f + R_f p, R_f R).
  const Vec3 p_f(0.1, 0.0, -0.5);
  const Mat3 R_f = Eigen::AngleAxisd(0.5, Vec3::UnitX()).toRotationMatrix();
  CollisionShape s = make_shape("toe", ShapeType::box, Vec3(0.01, 0.02, 0.03));
  s.position = Vec3(0.0, 0.2, 0.0);
  s.rotation = Eigen::AngleAxisd(0.3, Vec3::UnitZ()).toRotationMatrix();
  const Vec3 expected_p = p_f + R_f * s.position;
  const Mat3 expected_R = R_f * s.rotation;
  // 0.2 along the frame's y, turned 0.5 rad about x: (0.1, 0.2 cos 0.5, -0.5 + 0.2 sin 0.5).
  EXPECT_NEAR(expected_p.y(), 0.2 * std::cos(0.5), 1e-15);
  EXPECT_NEAR(expected_p.z(), -0.5 + 0.2 * std::sin(0.5), 1e-15);
  for (int path = 0; path < 2; ++path) {
    Model m;
    if (path == 0) {
      ModelBuilder b = shapes_chain();
      b.add_shape("tool", s);
      m = b.build();
    } else {
      m = with_shapes(shapes_chain().build(), {{"tool", s}});
    }
    ASSERT_EQ(m.shapes.size(), 1u);
    EXPECT_EQ(m.shapes[0].link, m.link_index("lower"));
    EXPECT_TRUE(m.shapes[0].position.isApprox(expected_p, 1e-15)) << path;
    EXPECT_TRUE(m.shapes[0].rotation.isApprox(expected_R, 1e-15)) << path;
  }
}

TEST(ModelShapes, EveryBadSizePoseAndMaterialIsRefusedNamingShapeLinkFieldAndValue) {
  constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  constexpr double kInf = std::numeric_limits<double>::infinity();
  struct Case {
    ShapeType type;
    std::function<void(CollisionShape&)> edit;
    std::string message;
  };
  const std::vector<Case> cases = {
      {ShapeType::sphere, [](CollisionShape& s) { s.size.x() = 0.0; }, "radius = 0 must be"},
      {ShapeType::sphere, [](CollisionShape& s) { s.size.x() = -1.0; }, "radius = -1 must be"},
      {ShapeType::sphere, [](CollisionShape& s) { s.size.x() = kNaN; }, "radius = nan must be"},
      {ShapeType::capsule, [](CollisionShape& s) { s.size.y() = 0.0; }, "half_length = 0 must"},
      {ShapeType::capsule, [](CollisionShape& s) { s.size.x() = kInf; }, "radius = inf must"},
      {ShapeType::box, [](CollisionShape& s) { s.size.x() = -2.0; }, "half_extent.x = -2 must"},
      {ShapeType::box, [](CollisionShape& s) { s.size.y() = 0.0; }, "half_extent.y = 0 must"},
      {ShapeType::box, [](CollisionShape& s) { s.size.z() = kNaN; }, "half_extent.z = nan must"},
      {ShapeType::ellipsoid, [](CollisionShape& s) { s.size.y() = -1.0; }, "semi_axis.y = -1 must"},
      {ShapeType::cylinder, [](CollisionShape& s) { s.size.y() = 0.0; }, "half_length = 0 must"},
      {ShapeType::cylinder, [](CollisionShape& s) { s.size.x() = kNaN; }, "radius = nan must"},
      {ShapeType::convex, [](CollisionShape& s) { s.vertices.clear(); },
       "vertices: a convex shape needs at least one"},
      {ShapeType::convex, [](CollisionShape& s) { s.vertices[1].z() = kInf; },
       "vertices[1] = [0, 0, inf] is not finite"},
      {ShapeType::box, [](CollisionShape& s) { s.position.y() = kInf; },
       "position = [0, inf, 0] is not finite"},
      {ShapeType::box, [](CollisionShape& s) { s.rotation(0, 0) = 2.0; },
       "rotation is not a rotation matrix (max |R^T R - I| = 3"},
      {ShapeType::box, [](CollisionShape& s) { s.rotation(2, 2) = -1.0; },
       "rotation is not a rotation matrix (max |R^T R - I| = 0, det R = -1)"},
      {ShapeType::box, [](CollisionShape& s) { s.rotation(1, 0) = kNaN; },
       "rotation has an entry that is not finite"},
      {ShapeType::box, [](CollisionShape& s) { s.material.static_friction = -0.1; },
       "static_friction = -0.1 must be finite and >= 0"},
      {ShapeType::box, [](CollisionShape& s) { s.material.dynamic_friction = kInf; },
       "dynamic_friction = inf must be finite and >= 0"},
      {ShapeType::box, [](CollisionShape& s) { s.material.restitution = 1.5; },
       "restitution = 1.5 must be in [0, 1]"},
      {ShapeType::box, [](CollisionShape& s) { s.material.restitution = kNaN; },
       "restitution = nan must be in [0, 1]"},
  };
  for (const Case& c : cases) {
    CollisionShape s = make_shape("pad", c.type, Vec3(0.1, 0.2, 0.3));
    if (c.type == ShapeType::convex) s.vertices = {Vec3(0.1, 0, 0), Vec3(0, 0, 0.1)};
    c.edit(s);
    const std::string expected =
        std::string("model: shape 'pad' (") + to_string(c.type) + ") of link 'lower': " + c.message;
    ModelBuilder b = shapes_chain();
    b.add_shape("lower", s);
    const std::string built = shape_error([&] { (void)b.build(); });
    EXPECT_THAT(built, HasSubstr(expected));
    EXPECT_EQ(built.find('\n'), std::string::npos);
    const Model m = shapes_chain().build();
    EXPECT_THAT(shape_error([&] { (void)with_shapes(m, {{"lower", s}}); }), HasSubstr(expected));
  }
  // An unnamed shape is named by its place; an unknown link is named with the nearest names.
  CollisionShape s = make_shape("", ShapeType::sphere, Vec3(0.1, 0, 0));
  ModelBuilder b = shapes_chain();
  b.add_shape("lowr", s);
  EXPECT_EQ(shape_error([&] { (void)b.build(); }),
            "model: shape #0 (sphere) of link 'lowr': the link is not a link or frame of the "
            "model");
  EXPECT_THAT(shape_error([&] { (void)with_shapes(shapes_chain().build(), {{"lowr", s}}); }),
              HasSubstr("model: shape #0 (sphere) of link 'lowr': no link or frame named 'lowr'"));
}

TEST(ModelShapes, AGroundIsRefusedWhileTheModelHasGeometryContactsCannotUse) {
  ModelBuilder b = shapes_chain();
  b.add_shape("lower", make_shape("foot", ShapeType::sphere, Vec3(0.05, 0, 0)));
  b.add_unsupported_shape("link 'lower': mesh collision 'foot.dae'");
  b.add_unsupported_shape("link 'upper': cylinder collision #0");
  const auto model = std::make_shared<const Model>(b.build());
  ASSERT_EQ(model->unsupported_shapes.size(), 2u);
  Simulation sim(model);
  Ground ground;
  ground.enabled = true;
  const std::string expected =
      "ground: link 'lower': mesh collision 'foot.dae': contacts do not support this shape yet "
      "(sphere, capsule, box, ellipsoid, cylinder, convex mesh) (2 such shapes in all)";
  try {
    sim.set_ground(ground);
    ADD_FAILURE() << "set_ground did not throw";
  } catch (const std::invalid_argument& e) {
    EXPECT_THAT(e.what(), HasSubstr(expected));
  }
  Settings settings = sim.settings();
  settings.ground = ground;
  try {
    sim.set_settings(settings);
    ADD_FAILURE() << "set_settings did not throw";
  } catch (const std::invalid_argument& e) {
    EXPECT_THAT(e.what(), HasSubstr(expected));
  }
  EXPECT_FALSE(sim.ground().enabled);
  // Off, the ground may be set; a model without such geometry takes it on.
  ground.enabled = false;
  EXPECT_NO_THROW(sim.set_ground(ground));
  ground.enabled = true;
  Simulation plain(std::make_shared<const Model>(shapes_chain().build()));
  EXPECT_NO_THROW(plain.set_ground(ground));
  EXPECT_TRUE(plain.ground().enabled);
}

}  // namespace
}  // namespace featherdrive
