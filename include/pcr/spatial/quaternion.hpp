#pragma once
// Rotations in 3-D as quaternions h = (w, x, y, z), templated on the scalar so Ceres Jets flow
// through. A quaternion is stored as a plain 4-vector in that order (Eigen::Quaternion stores
// (x, y, z, w) and normalises in places; the rod's state needs a vector it can step as is).
//
// rotation_of(h) is the rotation body -> world of h / |h|: the formula divides by |h|^2, so R is
// a rotation whatever |h|, and a quaternion that drifted off the unit sphere (RK4 on
// h' = h (x) (0, u) / 2 keeps |h| only to its order) still gives an orthogonal R.

#include <Eigen/Core>
#include <cmath>

#include "pcr/scalar_traits.hpp"

namespace pcr {

template <class T>
using Vector3 = Eigen::Matrix<T, 3, 1>;
template <class T>
using Vector4 = Eigen::Matrix<T, 4, 1>;
template <class T>
using Matrix3 = Eigen::Matrix<T, 3, 3>;

/// The identity rotation (1, 0, 0, 0).
template <class T>
Vector4<T> identity_quaternion() {
  return Vector4<T>(T(1), T(0), T(0), T(0));
}

/// The Hamilton product a (x) b of quaternions (w, x, y, z).
template <class T>
Vector4<T> quaternion_product(const Vector4<T>& a, const Vector4<T>& b) {
  return Vector4<T>(a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3],
                    a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
                    a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1],
                    a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0]);
}

/// h (x) (0, u) for a vector u: the product the rod's h' = h (x) (0, u) / 2 needs, without the
/// products by the zero scalar part.
template <class T>
Vector4<T> quaternion_times_vector(const Vector4<T>& h, const Vector3<T>& u) {
  return Vector4<T>(
      -h[1] * u[0] - h[2] * u[1] - h[3] * u[2], h[0] * u[0] + h[2] * u[2] - h[3] * u[1],
      h[0] * u[1] + h[3] * u[0] - h[1] * u[2], h[0] * u[2] + h[1] * u[1] - h[2] * u[0]);
}

/// The rotation matrix of h / |h| (body -> world): R = I + 2 / |h|^2 (w [v]x + [v]x^2), v = (x,
/// y, z). Exactly orthogonal up to rounding for any h != 0. A quaternion with zero components
/// gives exact zeros where the rotation has them (a rotation about a coordinate axis keeps the
/// other axis' entries exactly 0 and 1).
template <class T>
Matrix3<T> rotation_of(const Vector4<T>& h) {
  const T &w = h[0], &x = h[1], &y = h[2], &z = h[3];
  const T k = T(2) / (w * w + x * x + y * y + z * z);
  const T xx = x * x, yy = y * y, zz = z * z;
  const T xy = x * y, xz = x * z, yz = y * z, wx = w * x, wy = w * y, wz = w * z;
  Matrix3<T> R;
  R << T(1) - k * (yy + zz), k * (xy - wz), k * (xz + wy),  //
      k * (xy + wz), T(1) - k * (xx + zz), k * (yz - wx),   //
      k * (xz - wy), k * (yz + wx), T(1) - k * (xx + yy);
  return R;
}

/// A unit quaternion of the rotation R (Shepperd's method: the square root of the largest of
/// 1 + trace and 1 + 2 R_ii - trace, which never cancels). Of the two quaternions of R, the one
/// whose largest component is positive. R must be a rotation.
template <class T>
Vector4<T> quaternion_of(const Matrix3<T>& R) {
  using std::sqrt;
  const T trace = R(0, 0) + R(1, 1) + R(2, 2);
  Vector4<T> h;
  if (trace > R(0, 0) && trace > R(1, 1) && trace > R(2, 2)) {
    const T s = T(2) * sqrt(T(1) + trace);  // 4 w
    h << T(0.25) * s, (R(2, 1) - R(1, 2)) / s, (R(0, 2) - R(2, 0)) / s, (R(1, 0) - R(0, 1)) / s;
  } else if (R(0, 0) >= R(1, 1) && R(0, 0) >= R(2, 2)) {
    const T s = T(2) * sqrt(T(1) + R(0, 0) - R(1, 1) - R(2, 2));  // 4 x
    h << (R(2, 1) - R(1, 2)) / s, T(0.25) * s, (R(0, 1) + R(1, 0)) / s, (R(0, 2) + R(2, 0)) / s;
  } else if (R(1, 1) >= R(2, 2)) {
    const T s = T(2) * sqrt(T(1) + R(1, 1) - R(0, 0) - R(2, 2));  // 4 y
    h << (R(0, 2) - R(2, 0)) / s, (R(0, 1) + R(1, 0)) / s, T(0.25) * s, (R(1, 2) + R(2, 1)) / s;
  } else {
    const T s = T(2) * sqrt(T(1) + R(2, 2) - R(0, 0) - R(1, 1));  // 4 z
    h << (R(1, 0) - R(0, 1)) / s, (R(0, 2) + R(2, 0)) / s, (R(1, 2) + R(2, 1)) / s, T(0.25) * s;
  }
  return h;
}

/// The rotation vector (rad) of h / |h|: angle times axis, the angle in [0, pi] (of h and -h, the
/// one with w >= 0). The inverse of quaternion_exp (pcr/spatial/shooting.hpp). atan2 keeps
/// full precision at small and at large angles; below 1e-6 rad the series 2 v / w (1 - |v|^2 /
/// (3 w^2)), exact to rounding there, keeps the derivatives a Jet carries through the identity.
template <class T>
Vector3<T> quaternion_log(const Vector4<T>& h) {
  using std::atan2;
  using std::sqrt;
  const T sign = h[0] < T(0) ? T(-1) : T(1);
  const Vector3<T> v = sign * h.template tail<3>();
  const T w = sign * h[0];
  const T n2 = v.squaredNorm();
  if (scalar_value(n2) < 1e-12 * scalar_value(w * w)) {
    return (T(2) / w * (T(1) - n2 / (T(3) * w * w))) * v;
  }
  const T n = sqrt(n2);
  return (T(2) * atan2(n, w) / n) * v;
}

}  // namespace pcr
