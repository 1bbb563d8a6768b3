#include "support/models.hpp"

namespace featherdrive::test {

Mat3 box_inertia(double m, const Vec3& s) {
  return Vec3(m / 12 * (s.y() * s.y() + s.z() * s.z()), m / 12 * (s.x() * s.x() + s.z() * s.z()),
              m / 12 * (s.x() * s.x() + s.y() * s.y()))
      .asDiagonal();
}

std::shared_ptr<const Model> make_slider(double mass, const Vec3& axis, const Vec3& gravity) {
  ModelBuilder b;
  b.set_gravity(gravity);
  b.add_link(make_link("base", "", 1.0, Vec3::Zero(), box_inertia(1.0, Vec3(0.1, 0.1, 0.1)),
                       fixed_joint("world_joint")));
  b.add_link(make_link("slider", "base", mass, Vec3::Zero(), box_inertia(mass, Vec3(0.1, 0.1, 0.1)),
                       prismatic_joint("slide", axis)));
  return std::make_shared<const Model>(b.build());
}

std::shared_ptr<const Model> make_pendulum(double mass, double length, double inertia) {
  ModelBuilder b;
  b.set_gravity(Vec3(0, 0, -9.81));
  b.add_link(make_link("base", "", 1.0, Vec3::Zero(), box_inertia(1.0, Vec3(0.1, 0.1, 0.1)),
                       fixed_joint("world_joint")));
  b.add_link(make_link("bob", "base", mass, Vec3(0, 0, -length), Mat3::Identity() * inertia,
                       revolute_joint("hinge", Vec3::UnitY())));
  return std::make_shared<const Model>(b.build());
}

std::shared_ptr<const Model> make_benchmark_chain(int n, const Vec3& gravity) {
  const Vec3 axes[3] = {Vec3::UnitY(), Vec3::UnitZ(), Vec3::UnitX()};
  const double r = 0.05, l = 0.5;
  const Mat3 inertia =
      Vec3((3 * r * r + l * l) / 12, (3 * r * r + l * l) / 12, r * r / 2).asDiagonal();
  ModelBuilder b;
  b.set_gravity(gravity);
  b.add_link(
      make_link("base", "", 1.0, Vec3::Zero(), Mat3::Identity() * (0.02 / 12), fixed_joint("fix")));
  std::string parent = "base";
  for (int i = 0; i < n; ++i) {
    const std::string name = "link" + std::to_string(i + 1);
    b.add_link(make_link(name, parent, 1.0, Vec3(0, 0, -l / 2), inertia,
                         revolute_joint("joint" + std::to_string(i + 1), axes[i % 3],
                                        i == 0 ? Vec3::Zero() : Vec3(0, 0, -l))));
    parent = name;
  }
  return std::make_shared<const Model>(b.build());
}

std::shared_ptr<const Model> make_planar_chain(int n, double mass, double length,
                                               const Vec3& gravity) {
  ModelBuilder b;
  b.set_gravity(gravity);
  b.add_link(make_link("base", "", 1.0, Vec3::Zero(), box_inertia(1.0, Vec3(0.1, 0.1, 0.1)),
                       fixed_joint("world_joint")));
  std::string parent = "base";
  for (int i = 0; i < n; ++i) {
    const std::string name = "link" + std::to_string(i + 1);
    const double rod = mass * length * length / 12.0;
    b.add_link(make_link(name, parent, mass, Vec3(0, 0, -length / 2),
                         Vec3(rod, rod, 1e-4).asDiagonal(),
                         revolute_joint("joint" + std::to_string(i + 1), Vec3::UnitY(),
                                        i == 0 ? Vec3::Zero() : Vec3(0, 0, -length))));
    parent = name;
  }
  return std::make_shared<const Model>(b.build());
}

VecX random_vector(int n, std::mt19937& rng, double scale) {
  std::uniform_real_distribution<double> u(-scale, scale);
  VecX v(n);
  for (int i = 0; i < n; ++i) v[i] = u(rng);
  return v;
}

std::shared_ptr<const Model> make_random_tree(unsigned seed, int n, bool floating, bool spherical,
                                              double armature) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::uniform_real_distribution<double> pos(0.2, 2.0);
  ModelBuilder b;
  b.set_gravity(Vec3(0.3, -0.2, -9.81));
  for (int i = 0; i < n; ++i) {
    LinkSpec l;
    l.name = "link" + std::to_string(i);
    l.mass = pos(rng);
    l.com = Vec3(u(rng), u(rng), u(rng)) * 0.3;
    // A random rotation of a box inertia is symmetric, positive definite and physical.
    const Mat3 R = Quat(Eigen::Vector4d(u(rng), u(rng), u(rng), u(rng)).normalized()).toRotationMatrix();
    l.inertia = R * box_inertia(l.mass, Vec3(pos(rng), pos(rng), pos(rng)) * 0.5) * R.transpose();
    l.joint.name = "joint" + std::to_string(i);
    if (i == 0) {
      l.joint.type = floating ? JointType::floating : JointType::fixed;
    } else {
      std::uniform_int_distribution<int> pick(0, i - 1);
      l.parent = "link" + std::to_string(pick(rng));
      const int kinds = spherical ? 10 : 9;
      const int k = std::uniform_int_distribution<int>(0, kinds - 1)(rng);
      l.joint.type = k < 5   ? JointType::revolute
                     : k < 8 ? JointType::prismatic
                     : k < 9 ? JointType::fixed
                             : JointType::spherical;
      l.joint.origin_xyz = Vec3(u(rng), u(rng), u(rng));
      l.joint.origin_rpy = Vec3(u(rng), u(rng), u(rng)) * 3.0;
      l.joint.axis = Vec3(u(rng), u(rng), u(rng));
    }
    if (armature > 0.0 && l.joint.type != JointType::fixed) l.joint.armature = {armature * pos(rng)};
    b.add_link(l);
  }
  return std::make_shared<const Model>(b.build());
}

VecX random_configuration(const Model& model, std::mt19937& rng) {
  VecX q = random_vector(model.nq, rng, 1.0);
  for (const Link& link : model.links) {
    if (link.joint_type == JointType::spherical) q.segment<4>(link.q_index).normalize();
    if (link.joint_type == JointType::floating) q.segment<4>(link.q_index + 3).normalize();
  }
  return q;
}

}  // namespace featherdrive::test
