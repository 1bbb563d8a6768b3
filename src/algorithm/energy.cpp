#include "featherdrive/algorithm/energy.hpp"

namespace featherdrive {

double kinetic_energy(const Model& model, const Data& data, const VecX& qd) {
  double e = 0.0;
  for (int i = 0; i < model.num_links(); ++i)
    e += 0.5 * data.velocity[i].dot(model.links[i].inertia * data.velocity[i]);
  return e + 0.5 * qd.dot(model.armature.cwiseProduct(qd));
}

double potential_energy(const Model& model, const Data& data) {
  double e = 0.0;
  for (int i = 0; i < model.num_links(); ++i) {
    const Link& l = model.links[i];
    e -= l.mass * model.gravity.dot(data.world_position[i] + data.world_rotation[i] * l.com);
  }
  return e;
}

Vec6 momentum(const Model& model, const Data& data) {
  Vec6 h = Vec6::Zero();
  for (int i = 0; i < model.num_links(); ++i) {
    const Vec6 local = model.links[i].inertia * data.velocity[i];
    // Link frame -> world: X^T of the world->link transform applied to a force.
    const Transform world_to_link =
        Transform::from_pose(data.world_rotation[i], data.world_position[i]);
    h += world_to_link.transpose_apply_force(local);
  }
  return h;
}

Vec3 center_of_mass(const Model& model, const Data& data) {
  Vec3 c = Vec3::Zero();
  double m = 0.0;
  for (int i = 0; i < model.num_links(); ++i) {
    const Link& l = model.links[i];
    c += l.mass * (data.world_position[i] + data.world_rotation[i] * l.com);
    m += l.mass;
  }
  return m > 0.0 ? Vec3(c / m) : Vec3::Zero();
}

}  // namespace featherdrive
