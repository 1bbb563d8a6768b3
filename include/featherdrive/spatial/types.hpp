// Scalar and small fixed-size types used everywhere. Spatial vectors are [angular; linear]
// (docs/conventions.md).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace featherdrive {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;
using Vec6 = Eigen::Matrix<double, 6, 1>;
using Mat6 = Eigen::Matrix<double, 6, 6>;
using Quat = Eigen::Quaterniond;
using VecX = Eigen::VectorXd;
using MatX = Eigen::MatrixXd;

/// Up to six columns of spatial vectors (a joint's motion subspace, its U = IA S); never allocates.
using Mat6N = Eigen::Matrix<double, 6, Eigen::Dynamic, 0, 6, 6>;
/// Up to 6x6 joint-space block (a joint's D, D^-1); never allocates.
using MatNN = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 6, 6>;
using VecN = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 6, 1>;

}  // namespace featherdrive
