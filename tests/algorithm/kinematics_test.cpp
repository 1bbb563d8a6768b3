// forward_kinematics and world_poses into the caller's arrays against poses and velocities composed
// here with Eigen's AngleAxis, on a chain whose joints mix the coordinate-axis fast paths (axes
// +-e_k, joint frame parallel to the parent's) with general ones (tilted frames, oblique axes).
#include <gtest/gtest.h>

#include <random>

#include <Eigen/Geometry>

#include "featherdrive/algorithm/data.hpp"
#include "featherdrive/algorithm/kinematics.hpp"
#include "featherdrive/model/model_builder.hpp"

namespace featherdrive {
namespace {

struct JointCase {
  JointType type;
  Vec3 axis;
  Vec3 rpy;
};

Mat3 rpy_rotation(const Vec3& rpy) {  // URDF: R = Rz(yaw) Ry(pitch) Rx(roll)
  return (Eigen::AngleAxisd(rpy.z(), Vec3::UnitZ()) * Eigen::AngleAxisd(rpy.y(), Vec3::UnitY()) *
          Eigen::AngleAxisd(rpy.x(), Vec3::UnitX()))
      .toRotationMatrix();
}

TEST(ForwardKinematics, CoordinateAndGeneralJointsMatchComposedRotations) {
  const std::vector<JointCase> joints = {
      {JointType::revolute, Vec3::UnitX(), Vec3::Zero()},
      {JointType::revolute, -Vec3::UnitY(), Vec3::Zero()},
      {JointType::revolute, Vec3::UnitZ(), Vec3::Zero()},
      {JointType::revolute, -Vec3::UnitX(), Vec3::Zero()},
      {JointType::prismatic, -Vec3::UnitZ(), Vec3::Zero()},
      {JointType::revolute, Vec3::UnitY(), Vec3::Zero()},
      {JointType::revolute, -Vec3::UnitZ(), Vec3(0.3, -0.2, 0.7)},
      {JointType::prismatic, Vec3::UnitX(), Vec3::Zero()},
      {JointType::revolute, Vec3(0.6, 0.0, 0.8), Vec3::Zero()},
      {JointType::revolute, -Vec3::UnitY(), Vec3::Zero()},
      {JointType::prismatic, Vec3(0.0, 0.8, -0.6), Vec3(-0.4, 0.1, 0.2)},
      {JointType::revolute, Vec3::UnitX(), Vec3::Zero()},
  };
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  ModelBuilder b;
  b.add_link(make_link("base", "", 1.0, Vec3::Zero(), Mat3::Identity(), fixed_joint("base")));
  std::vector<Vec3> origins;
  for (size_t k = 0; k < joints.size(); ++k) {
    const Vec3 xyz(u(rng), u(rng), u(rng));
    origins.push_back(xyz);
    const std::string name = "l" + std::to_string(k);
    const std::string parent = k == 0 ? "base" : "l" + std::to_string(k - 1);
    const JointCase& j = joints[k];
    JointSpec spec = j.type == JointType::revolute ? revolute_joint("j" + name, j.axis, xyz, j.rpy)
                                                   : prismatic_joint("j" + name, j.axis, xyz, j.rpy);
    b.add_link(make_link(name, parent, 1.0, Vec3::Zero(), Mat3::Identity(), spec));
  }
  const Model model = b.build();
  ASSERT_EQ(model.nv, static_cast<int>(joints.size()));
  VecX q(model.nq), v(model.nv);
  for (int d = 0; d < model.nv; ++d) {
    q[d] = 2.5 * u(rng);
    v[d] = 3.0 * u(rng);
  }
  Data data(model);
  forward_kinematics(model, data, q, v);
  Data positions_only(model);
  forward_kinematics(model, positions_only, q);
  // world_poses into arrays of the caller's (compat physx's world_pose), from an unposed Data.
  const Data unposed(model);
  std::vector<Mat3> R_out(model.links.size());
  std::vector<Vec3> p_out(model.links.size());
  world_poses(unposed, q, R_out.data(), p_out.data());

  Mat3 R = Mat3::Identity();
  Vec3 p = Vec3::Zero(), w = Vec3::Zero(), vel = Vec3::Zero();  // world frame
  for (size_t k = 0; k < joints.size(); ++k) {
    const int i = static_cast<int>(k) + 1;
    const JointCase& j = joints[k];
    const Vec3 a = j.axis.normalized();
    const Vec3 p_next = p + R * origins[k] +
                        (j.type == JointType::prismatic ? Vec3(R * rpy_rotation(j.rpy) * a * q[k])
                                                        : Vec3::Zero());
    vel += w.cross(p_next - p);
    Mat3 R_next = R * rpy_rotation(j.rpy);
    if (j.type == JointType::revolute) {
      R_next = R_next * Eigen::AngleAxisd(q[k], a).toRotationMatrix();
      w += R_next * a * v[k];
    } else {
      vel += R_next * a * v[k];
    }
    R = R_next;
    p = p_next;
    SCOPED_TRACE("link " + std::to_string(i));
    EXPECT_LT((data.world_rotation[i] - R).norm(), 1e-12);
    EXPECT_LT((data.world_position[i] - p).norm(), 1e-12);
    EXPECT_LT((positions_only.world_rotation[i] - R).norm(), 1e-12);
    EXPECT_LT((positions_only.world_position[i] - p).norm(), 1e-12);
    EXPECT_LT((R_out[k + 1] - R).norm(), 1e-12);
    EXPECT_LT((p_out[k + 1] - p).norm(), 1e-12);
    EXPECT_LT((data.velocity[i].head<3>() - R.transpose() * w).norm(), 1e-11);
    EXPECT_LT((data.velocity[i].tail<3>() - R.transpose() * vel).norm(), 1e-11);
  }
}

// A floating root whose joint frame is off the world's, then spherical joints in tilted frames
// and a revolute joint about an oblique axis: poses and X_i against Eigen's quaternion rotations
// composed here (eq. JT-5, JT-6 with Q-5); quaternions of any norm.
TEST(ForwardKinematics, SphericalJointsAndFloatingRootMatchQuaternionRotations) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  ModelBuilder b;
  b.add_link(make_link("root", "", 1.0, Vec3::Zero(), Mat3::Identity(), floating_joint("root")));
  const std::vector<JointCase> joints = {
      {JointType::spherical, Vec3::Zero(), Vec3(0.3, -0.2, 0.7)},
      {JointType::spherical, Vec3::Zero(), Vec3::Zero()},
      {JointType::revolute, Vec3(0.0, 0.6, -0.8), Vec3(-0.5, 0.4, 0.1)},
      {JointType::spherical, Vec3::Zero(), Vec3(1.1, 0.2, -0.9)},
  };
  std::vector<Vec3> origins;
  for (size_t k = 0; k < joints.size(); ++k) {
    const Vec3 xyz(u(rng), u(rng), u(rng));
    origins.push_back(xyz);
    const std::string name = "l" + std::to_string(k);
    const std::string parent = k == 0 ? "root" : "l" + std::to_string(k - 1);
    const JointCase& j = joints[k];
    JointSpec spec = j.type == JointType::spherical
                         ? spherical_joint("j" + name, xyz, j.rpy)
                         : revolute_joint("j" + name, j.axis, xyz, j.rpy);
    b.add_link(make_link(name, parent, 1.0, Vec3::Zero(), Mat3::Identity(), spec));
  }
  Model model = b.build();
  const Vec3 root_rpy(0.2, 0.9, -0.4), root_xyz(0.5, -0.3, 1.2);
  model.links[0].tree_transform = Transform::from_pose(rpy_rotation(root_rpy), root_xyz);
  VecX q(model.nq);
  for (int e = 0; e < model.nq; ++e) q[e] = 2.0 * u(rng);
  Data data(model);
  forward_kinematics(model, data, q);
  const Data unposed(model);
  std::vector<Mat3> R_out(model.links.size());
  std::vector<Vec3> p_out(model.links.size());
  world_poses(unposed, q, R_out.data(), p_out.data());

  auto quaternion = [&](int at) {
    return Quat(q[at], q[at + 1], q[at + 2], q[at + 3]).normalized().toRotationMatrix();
  };
  // The root: R = E_T^T R_q, p = r_T + E_T^T q_xyz.
  Mat3 R = rpy_rotation(root_rpy) * quaternion(3);
  Vec3 p = root_xyz + rpy_rotation(root_rpy) * q.head<3>();
  EXPECT_LT((data.world_rotation[0] - R).norm(), 1e-14);
  EXPECT_LT((data.world_position[0] - p).norm(), 1e-14);
  EXPECT_LT((R_out[0] - R).norm(), 1e-14);
  EXPECT_LT((p_out[0] - p).norm(), 1e-14);
  int at = 7;
  for (size_t k = 0; k < joints.size(); ++k) {
    const int i = static_cast<int>(k) + 1;
    const JointCase& j = joints[k];
    SCOPED_TRACE("link " + std::to_string(i));
    const Mat3 J = j.type == JointType::spherical
                       ? quaternion(at)
                       : Mat3(Eigen::AngleAxisd(q[at], j.axis.normalized()).toRotationMatrix());
    at += j.type == JointType::spherical ? 4 : 1;
    const Mat3 E_T = rpy_rotation(j.rpy).transpose();
    p = p + R * origins[k];
    R = R * E_T.transpose() * J;
    EXPECT_LT((data.world_rotation[i] - R).norm(), 1e-14);
    EXPECT_LT((data.world_position[i] - p).norm(), 1e-14);
    EXPECT_LT((R_out[k + 1] - R).norm(), 1e-14);
    EXPECT_LT((p_out[k + 1] - p).norm(), 1e-14);
    // X_i = X_J X_T: E = J^T E_T, r = r_T.
    EXPECT_LT((data.parent_transform[i].E - J.transpose() * E_T).norm(), 1e-14);
    EXPECT_LT((data.parent_transform[i].r - origins[k]).norm(), 1e-15);
  }
}

}  // namespace
}  // namespace featherdrive
