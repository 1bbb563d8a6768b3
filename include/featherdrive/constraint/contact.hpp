// Contacts between a robot's shapes and the ground, solved as PhysX 5.6.1 solves an articulation's
// contacts with a static plane (docs/math/contact.md).
#pragma once

#include "featherdrive/model/shape.hpp"

namespace featherdrive {

/// The ground: the plane n . x = height (n normalised when set), with its material. Off unless
/// enabled.
struct Ground {
  bool enabled = false;
  double height = 0.0;
  Vec3 normal{0.0, 0.0, 1.0};
  Material material;
};

/// PhysX 5.6.1's contact parameters (docs/math/contact.md, section 8), each the same for every
/// shape and for the ground. A pair's contact distance is 2 contact_offset, its rest distance
/// 2 rest_offset (C1).
struct ContactOptions {
  double contact_offset = 0.02;    ///< m, > rest_offset
  double rest_offset = 0.0;        ///< m
  double bounce_threshold = 2.0;   ///< m/s: slower impacts do not bounce (C8)
};

/// One contact point of the last step (docs/math/contact.md, section 1): a point of a shape
/// within the contact distance of the ground, and the impulses its rows applied over the step.
struct ContactReport {
  int link = 0;
  int shape = 0;                      ///< index into Model::shapes
  Vec3 position = Vec3::Zero();       ///< on the shape's surface, world frame, at the step's start
  Vec3 normal = Vec3::UnitZ();        ///< the ground's normal, into the body
  double separation = 0.0;            ///< at the step's start; < 0 penetrating
  double normal_impulse = 0.0;        ///< N s, along the normal
  Vec3 friction_impulse = Vec3::Zero();  ///< N s, world frame, tangential (the point's share)
};

}  // namespace featherdrive
