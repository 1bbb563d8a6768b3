// Bullet 3.24's btMultiBody (Debian's double-precision build) on the benchmark robots: one link
// per link of ours, frames at the centres of mass on the principal axes (as Bullet requires), no
// collision shapes, body damping off. The drives are explicit PD torques, kp (target - q) - kd qd,
// added with addJointTorque before each stepSimulation (Bullet has no implicit PD drive of the
// same law; its joint motors are velocity constraints with other gains).
#include <BulletDynamics/Featherstone/btMultiBody.h>
#include <BulletDynamics/Featherstone/btMultiBodyConstraintSolver.h>
#include <BulletDynamics/Featherstone/btMultiBodyDynamicsWorld.h>
#include <btBulletDynamicsCommon.h>

#include <Eigen/Eigenvalues>

#include <cmath>
#include <memory>
#include <stdexcept>
#include <vector>

#include "featherdrive/algorithm/kinematics.hpp"
#include "peers.hpp"

namespace featherdrive::bench {
namespace {

btVector3 bt_vec(const Vec3& v) { return btVector3(v.x(), v.y(), v.z()); }
btQuaternion bt_quat(const Mat3& R) {
  const Quat q(R);
  return btQuaternion(q.x(), q.y(), q.z(), q.w());
}

// A link's principal axes (columns, in link coordinates, right-handed) and moments.
struct Principal {
  Mat3 axes;
  Vec3 moments;
};
Principal principal(const Link& link) {
  Eigen::SelfAdjointEigenSolver<Mat3> eig(link.inertia_com);
  Principal p{eig.eigenvectors(), eig.eigenvalues()};
  if (p.axes.determinant() < 0.0) p.axes.col(2) = -p.axes.col(2);
  return p;
}

class BulletRobot {
 public:
  explicit BulletRobot(const BenchRobot& robot)
      : dispatcher_(&config_),
        world_(&dispatcher_, &broadphase_, &solver_, &config_) {
    const Model& model = *robot.model;
    world_.setGravity(bt_vec(model.gravity));
    const Link& root = model.links[0];
    if (root.joint_type != JointType::fixed && root.joint_type != JointType::floating)
      throw std::invalid_argument("bullet peer: the root must be fixed or floating");
    std::vector<Principal> axes;
    for (const Link& link : model.links) axes.push_back(principal(link));
    body_ = std::make_unique<btMultiBody>(model.num_links() - 1, root.mass, bt_vec(axes[0].moments),
                                          root.joint_type == JointType::fixed, false);
    for (int i = 1; i < model.num_links(); ++i) {
      const Link& link = model.links[i];
      const Link& parent = model.links[link.parent];
      const Mat3 R_tree = link.tree_transform.E.transpose();  // joint frame in the parent frame
      const Mat3& Rp = axes[link.parent].axes;
      const Mat3& Ri = axes[i].axes;
      const btQuaternion parent_to_this = bt_quat(Mat3(Ri.transpose() * R_tree.transpose() * Rp));
      const btVector3 pivot = bt_vec(Rp.transpose() * (link.tree_transform.r - parent.com));
      const btVector3 to_com = bt_vec(Ri.transpose() * link.com);
      const btVector3 moments = bt_vec(axes[i].moments);
      switch (link.joint_type) {
        case JointType::revolute:
          body_->setupRevolute(i - 1, link.mass, moments, link.parent - 1, parent_to_this,
                               bt_vec(Ri.transpose() * link.axis), pivot, to_com, true);
          driven_.push_back(i - 1);
          target_.push_back(robot.target[link.v_index]);
          break;
        case JointType::fixed:
          body_->setupFixed(i - 1, link.mass, moments, link.parent - 1, parent_to_this, pivot,
                            to_com, true);
          break;
        default: throw std::invalid_argument("bullet peer: revolute and fixed joints only");
      }
    }
    body_->finalizeMultiDof();
    body_->setLinearDamping(0.0);
    body_->setAngularDamping(0.0);
    body_->setMaxCoordinateVelocity(1e30);
    body_->setMaxAppliedImpulse(1e30);
    body_->setHasSelfCollision(false);
    body_->setCanSleep(false);
    world_.addMultiBody(body_.get());
    Data data(model);
    forward_kinematics(model, data, robot.q0);
    base_rotation_ = data.world_rotation[0] * axes[0].axes;
    base_position_ = data.world_position[0] + data.world_rotation[0] * root.com;
    reset();
  }
  ~BulletRobot() { world_.removeMultiBody(body_.get()); }

  void reset() {
    body_->setBasePos(bt_vec(base_position_));
    body_->setWorldToBaseRot(bt_quat(Mat3(base_rotation_.transpose())));
    body_->setBaseVel(btVector3(0, 0, 0));
    body_->setBaseOmega(btVector3(0, 0, 0));
    for (int j = 0; j < body_->getNumLinks(); ++j)
      if (body_->getLink(j).m_dofCount == 1) {
        body_->setJointPos(j, 0.0);
        body_->setJointVel(j, 0.0);
      }
  }

  void step() {
    body_->clearForcesAndTorques();
    for (size_t k = 0; k < driven_.size(); ++k) {
      const int j = driven_[k];
      body_->addJointTorque(j, kStiffness * (target_[k] - body_->getJointPos(j)) -
                                   kDamping * body_->getJointVel(j));
    }
    world_.stepSimulation(kDt, 0, kDt);
  }

  bool finite() const {
    for (int j = 0; j < body_->getNumLinks(); ++j)
      if (body_->getLink(j).m_dofCount == 1 && !std::isfinite(body_->getJointVel(j))) return false;
    return std::isfinite(body_->getBaseVel().x());
  }

 private:
  btDefaultCollisionConfiguration config_;
  btCollisionDispatcher dispatcher_;
  btDbvtBroadphase broadphase_;
  btMultiBodyConstraintSolver solver_;
  btMultiBodyDynamicsWorld world_;
  std::unique_ptr<btMultiBody> body_;
  std::vector<int> driven_;
  std::vector<double> target_;
  Mat3 base_rotation_;
  Vec3 base_position_;
};

}  // namespace

void bullet_step(benchmark::State& state, const BenchRobot& robot) {
  BulletRobot bullet(robot);
  int since_reset = 0;
  long diverged = 0;
  for (auto _ : state) {
    bullet.step();
    if (++since_reset == kResetInterval) {
      if (!bullet.finite()) ++diverged;
      bullet.reset();
      since_reset = 0;
    }
  }
  state.counters["dofs"] = robot.model->nv;
  state.counters["links"] = robot.model->num_links();
  state.counters["diverged"] = static_cast<double>(diverged);
}

}  // namespace featherdrive::bench
