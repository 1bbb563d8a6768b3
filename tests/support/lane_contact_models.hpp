// Grounded robots for the lanes' contact tests (tests/sim/lane_contact_test.cpp, and the long
// cases in tests/peers/lane_contact_long_test.cpp): built here once for both executables.
#pragma once

#include <memory>
#include <random>
#include <string>
#include <utility>

#include "featherdrive/sim/batch.hpp"
#include "support/drives.hpp"
#include "support/lanes.hpp"
#include "support/models.hpp"

namespace featherdrive::test {

// A random floating tree (revolute and prismatic joints, optionally spherical ones) with a box
// on its root and a sphere, capsule or box on each other link, over the ground: damped drives
// on every joint, viscous friction that keeps it from chaos (lane_floating_test.cpp).
inline Simulation grounded_tree(unsigned seed, SolverType solver, bool spherical,
                         Compat compat = Compat::none) {
  Model model = *make_random_tree(seed, 9, /*floating=*/true, spherical, 0.01);
  for (int i = 0; i < model.num_links(); ++i) {
    CollisionShape shape;
    shape.link = i;
    shape.type = i == 0 ? ShapeType::box : i % 3 == 1 ? ShapeType::sphere
                                        : i % 3 == 2 ? ShapeType::capsule
                                                     : ShapeType::box;
    shape.size = shape.type == ShapeType::box      ? Vec3(0.08, 0.06, 0.05)
                 : shape.type == ShapeType::sphere ? Vec3(0.06, 0.0, 0.0)
                                                   : Vec3(0.03, 0.08, 0.0);
    shape.position = Vec3(0.02, -0.01, 0.03);
    shape.material.static_friction = 0.8;
    shape.material.dynamic_friction = 0.6;
    model.shapes.push_back(shape);
  }
  auto shared = std::make_shared<const Model>(std::move(model));
  SimulationOptions o = lane_test_options(solver);
  o.compat = compat;
  Simulation sim(shared, o);
  std::mt19937 rng(seed);
  drive_every_joint(sim, rng, 200.0, 20.0);
  for (int d = 6; d < shared->nv; ++d) sim.set_joint_friction(d, JointFriction{0.0, 0.0, 0.2});
  Ground ground;
  ground.enabled = true;
  ground.material.static_friction = 0.8;
  ground.material.dynamic_friction = 0.6;
  sim.set_ground(ground);
  return sim;
}

// Environments dropped from their own heights and turns: some land at once, some later, one
// stays airborne through the run (5 s fall 123 m), so the lanes differ in contact count.
inline void drop_from_own_heights(Batch& batch, std::mt19937& rng) {
  const double heights[] = {0.25, 0.5, 0.9, 1.6, 200.0, 0.35, 0.7};
  for (int e = 0; e < batch.size(); ++e) {
    Simulation& s = batch.sim(e);
    VecX q = s.q();
    q[2] = heights[e % 7];
    q[3] = 1.0, q[4] = 0.1 * e, q[5] = -0.05 * e, q[6] = 0.02;  // set_q normalises
    s.set_q(q);
    s.set_qd(random_vector(s.model().nv, rng, 0.3));
  }
}

/// A Simulation of `model` at lane_test_options(solver) with `compat`, on a ground of `material`.
inline Simulation on_ground(std::shared_ptr<const Model> model, SolverType solver, Compat compat,
                            const Material& material) {
  SimulationOptions o = lane_test_options(solver);
  o.compat = compat;
  Simulation sim(std::move(model), o);
  Ground ground;
  ground.enabled = true;
  ground.material = material;
  sim.set_ground(ground);
  return sim;
}

/// Six grounded_tree environments (lane groups, docs/simd_batch.md): 0, 1 and 3 with a shape on
/// every link, 2 and 4 without link 1's, 5 without link 3's either (three sets of shape links,
/// three groups), dropped from their own heights.
inline Batch shapes_on_three_link_sets(SolverType solver, Compat compat = Compat::none) {
  const Simulation proto = grounded_tree(5, solver, false, compat);
  Batch batch(proto, 6);
  Model fewer = proto.model();
  fewer.shapes.erase(fewer.shapes.begin() + 1);
  Model fewest = fewer;
  fewest.shapes.erase(fewest.shapes.begin() + 2);
  for (int e : {2, 4}) batch.sim(e).set_model(std::make_shared<const Model>(fewer));
  batch.sim(5).set_model(std::make_shared<const Model>(fewest));
  std::mt19937 rng(3);
  drop_from_own_heights(batch, rng);
  return batch;
}

}  // namespace featherdrive::test
