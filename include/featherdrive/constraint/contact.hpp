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
  /// Contacts between the robot's own shapes (docs/math/contact.md, section 14): every pair of
  /// shapes on two links that are not parent and child. Off by default, as in Isaac Lab.
  bool self_collision = false;
};

/// One contact point of the last step (docs/math/contact.md, sections 1 and 14): a point of a
/// shape within the contact distance of the ground or of another link's shape, and the impulses
/// its rows applied over the step (on `link`; the other link takes the opposite).
struct ContactReport {
  int link = 0;
  int shape = 0;                      ///< index into Model::shapes
  int other_link = -1;                ///< -1: the ground; else the link of the other shape
  int other_shape = -1;               ///< -1: the ground; else its index into Model::shapes
  Vec3 position = Vec3::Zero();       ///< world frame, at the step's start (ground: on the shape)
  Vec3 normal = Vec3::UnitZ();        ///< into `link`: the ground's normal, or from the other shape
  double separation = 0.0;            ///< at the step's start; < 0 penetrating
  double normal_impulse = 0.0;        ///< N s, along the normal
  Vec3 friction_impulse = Vec3::Zero();  ///< N s, world frame, tangential (the point's share)
};

}  // namespace featherdrive
