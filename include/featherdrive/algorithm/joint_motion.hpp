// What each joint type does to its link: the joint transform X_J(q) and how q moves with v.
#pragma once

#include "featherdrive/model/model.hpp"

namespace featherdrive {

/// The rotation matrix of the unit quaternion q / |q| (w x y z): quaternion_law::rotation
/// (docs/math/quaternion_update.md, eq. Q-5), the lanes' form.
Mat3 quaternion_rotation(const double* q);

/// X_J(q): joint frame -> link frame, from this joint's slice of q (quaternions are normalised).
Transform joint_transform(const Link& link, const double* q);

/// q_out = q (+) v * dt on every joint's manifold: angles and slides add, quaternions turn by the
/// body-frame angular velocity and are renormalised, a floating root moves by its world-frame
/// linear velocity R v_body. q_out may alias q.
void integrate_configuration(const Model& model, const VecX& q, const VecX& v, double dt,
                             VecX& q_out);

/// Renormalises every quaternion in q.
void normalize_configuration(const Model& model, VecX& q);

}  // namespace featherdrive
