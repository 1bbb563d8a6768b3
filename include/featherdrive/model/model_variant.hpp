// Variants of a Model with other inertial parameters and the same topology: what a batch of
// randomised environments shares (sim/batch.hpp). Each returns a new validated Model.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "featherdrive/model/model.hpp"

namespace featherdrive {

/// "" when a and b have one topology (link and joint names, parents, joint types, axes and tree
/// transforms bit for bit, q and v indices, nq, nv), else the first difference in one line, e.g.
/// "link 2 ('forearm'): joint type revolute vs prismatic".
std::string topology_difference(const Model& a, const Model& b);

/// model with link `link` given this mass, centre of mass (link frame) and rotational inertia
/// about it (link axes), validated as ModelBuilder validates a LinkSpec; throws ModelError
/// naming the link, field and value, std::invalid_argument for a link index out of range.
Model with_link_inertial(const Model& model, int link, double mass, const Vec3& com,
                         const Mat3& inertia_com);

/// model with these collision shapes added (link name, shape), checked as ModelBuilder::add_shape
/// checks them: a name may be a link's or a frame's (a merged link: the shape goes to its link,
/// its pose composed). Model::shapes stays grouped by link in link order, the model's own shapes
/// first within a link. Throws ModelError naming the shape, link, field and value.
Model with_shapes(const Model& model,
                  const std::vector<std::pair<std::string, CollisionShape>>& shapes);

/// model with this armature (nv values, each finite and >= 0); throws ModelError naming the
/// joint and value, or the size.
Model with_armature(const Model& model, const VecX& armature);

}  // namespace featherdrive
