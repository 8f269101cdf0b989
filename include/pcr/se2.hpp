#pragma once
// Planar rigid transforms (SE(2)), templated on the scalar so Ceres Jets flow through.

#include <Eigen/Core>
#include <cmath>

namespace pcr {

template <class T>
using Vector2 = Eigen::Matrix<T, 2, 1>;

/// Pose of a frame B in a frame A: ^A T_B. x, y in metres, theta in radians.
template <class T>
struct Pose2 {
  T x{0};
  T y{0};
  T theta{0};

  Vector2<T> translation() const { return Vector2<T>(x, y); }

  /// R(theta) * v.
  Vector2<T> rotate(const Vector2<T>& v) const {
    using std::cos;
    using std::sin;
    const T c = cos(theta), s = sin(theta);
    return Vector2<T>(c * v.x() - s * v.y(), s * v.x() + c * v.y());
  }

  /// Maps a point given in B to A: R p + t.
  Vector2<T> transform(const Vector2<T>& p) const { return rotate(p) + translation(); }

  /// ^A T_B * ^B T_C = ^A T_C.
  Pose2 operator*(const Pose2& other) const {
    const Vector2<T> t = transform(other.translation());
    return Pose2{t.x(), t.y(), theta + other.theta};
  }

  /// ^B T_A.
  Pose2 inverse() const {
    using std::cos;
    using std::sin;
    const T c = cos(theta), s = sin(theta);
    return Pose2{-(c * x + s * y), s * x - c * y, -theta};
  }

  template <class U>
  Pose2<U> cast() const {
    return Pose2<U>{U(x), U(y), U(theta)};
  }
};

/// Wraps an angle to (-pi, pi]; smooth, so it is safe inside differentiated residuals.
template <class T>
T wrap_angle(const T& angle) {
  using std::atan2;
  using std::cos;
  using std::sin;
  return atan2(sin(angle), cos(angle));
}

/// The distance between two poses of Eq. 6: |p_a - p_b| + w |theta_a - theta_b| (m; the angle
/// wrapped), with w the orientation weight (m/rad).
inline double pose_distance(const Pose2<double>& a, const Pose2<double>& b,
                            double orientation_weight) {
  return std::hypot(a.x - b.x, a.y - b.y) +
         orientation_weight * std::abs(wrap_angle(a.theta - b.theta));
}

}  // namespace pcr
