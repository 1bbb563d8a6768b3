// Models shared by the tests: closed-form cases and random trees.
#pragma once

#include <memory>
#include <random>

#include "featherdrive/model/model_builder.hpp"

namespace featherdrive::test {

/// Inertia tensor of a solid box about its centre.
Mat3 box_inertia(double mass, const Vec3& size);

/// A fixed root (mass 1) and one link of the given mass sliding along `axis` of the root frame.
/// The sliding link is a 0.1 m cube with its centre of mass on its frame origin.
std::shared_ptr<const Model> make_slider(double mass, const Vec3& axis, const Vec3& gravity);

/// A point-like bob of mass m (small isotropic inertia `inertia` about its centre) at distance l
/// below a revolute joint about y; gravity -z.
std::shared_ptr<const Model> make_pendulum(double mass, double length, double inertia = 1e-3);

/// A planar chain of n revolute joints about y, links of mass m and length l along -z, centre of
/// mass at the middle, rod inertia about the centre.
std::shared_ptr<const Model> make_planar_chain(int n, double mass, double length,
                                               const Vec3& gravity = Vec3(0, 0, -9.81));

/// Issue 35's benchmark chain (bench/bench_models.cpp, make_chain): n links of 1 kg and 0.5 m,
/// solid cylinders of radius 0.05 along -z, revolute axes cycling y, z, x, from a fixed base.
std::shared_ptr<const Model> make_benchmark_chain(int n, const Vec3& gravity);

/// A random tree of n links with every joint type (revolute, prismatic, spherical, fixed),
/// random frames, axes, inertias and armature; root fixed or floating.
std::shared_ptr<const Model> make_random_tree(unsigned seed, int n, bool floating,
                                              bool spherical = true, double armature = 0.0);

/// A random configuration (unit quaternions) and velocity for a model.
VecX random_configuration(const Model& model, std::mt19937& rng);
VecX random_vector(int n, std::mt19937& rng, double scale = 1.0);

}  // namespace featherdrive::test
