// rtp math vocabulary: Eigen types in double precision under short physics names.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace rtp {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;
using Quat = Eigen::Quaterniond;

// dq/dt = ½ ω ⊗ q for an angular velocity ω in the world frame, as a quaternion's 4 coefficients.
inline Quat quaternion_rate(const Vec3& angular_velocity, const Quat& orientation) {
  Quat spin(0.0, angular_velocity.x(), angular_velocity.y(), angular_velocity.z());
  Quat rate = spin * orientation;
  rate.coeffs() *= 0.5;
  return rate;
}

// the world-frame inverse inertia R I⁻¹ Rᵀ of a body whose principal axes are its body axes
inline Mat3 world_inverse_inertia(const Quat& orientation, const Vec3& inverse_inertia_body) {
  const Mat3 rotation = orientation.toRotationMatrix();
  return rotation * inverse_inertia_body.asDiagonal() * rotation.transpose();
}

}  // namespace rtp
