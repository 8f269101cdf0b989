#pragma once
// The shooting problem of FK or IK (pcr/shooting.hpp's residual with some of the unknowns as
// inputs), in the form the Newton solver takes: size(), evaluate(z, r, J*).

#include <algorithm>
#include <cmath>

#include "pcr/internal/rod_step_ladder.hpp"
#include "pcr/robot.hpp"
#include "pcr/shooting.hpp"
#include "pcr/solver.hpp"

namespace pcr::internal {

/// One shooting problem (FK or IK) along a straight input path u(t) = u0 + t (u1 - u0).
class ShootingProblem {
 public:
  enum class Kind { kForward, kInverse };

  ShootingProblem(Kind kind, const RobotParams<double>& robot, const PlatformLoad<double>& load,
                  const SolverOptions& options)
      : kind_(kind),
        robot_(robot),
        load_(load),
        options_(options),
        scale_(shooting_scale(robot)),
        n_(robot.num_limbs) {
    steps_ = options.rod_steps > 0 ? options.rod_steps : options.min_rod_steps;
  }

  int rod_steps() const { return steps_; }
  void set_rod_steps(int steps) { steps_ = steps; }
  const RobotParams<double>& robot() const { return robot_; }
  const PlatformLoad<double>& load() const { return load_; }

  /// The physical size of a step dz of the scaled unknowns on the solved outputs: the largest
  /// length (m: FK's x, y; IK's joints) and the largest angle (rad: FK's theta; IK's theta, n = 2).
  void output_change(const ShootingVector& dz, double& position, double& angle) const {
    position = 0.0;
    angle = 0.0;
    const auto take = [](double& to, double v) { to = std::isfinite(v) ? std::max(to, v) : v; };
    if (kind_ == Kind::kForward) {
      take(position, std::abs(dz(3 * n_)) * scale_.length);
      take(position, std::abs(dz(3 * n_ + 1)) * scale_.length);
      take(angle, std::abs(dz(3 * n_ + 2)));
    } else {
      for (int i = 0; i < n_; ++i) take(position, std::abs(dz(3 * n_ + i)) * scale_.length);
      if (n_ == 2) take(angle, std::abs(dz(4 * n_)));
    }
  }

  /// Whether a step dz of the unknowns moves the solved outputs by at most `share` of the
  /// accuracy targets (SolverOptions::position_accuracy, angle_accuracy).
  bool output_change_within(const ShootingVector& dz, double share) const {
    double position, angle;
    output_change(dz, position, angle);
    return position <= share * options_.position_accuracy &&
           angle <= share * options_.angle_accuracy;
  }

  int size() const { return kind_ == Kind::kForward ? 3 * n_ + 3 : 4 * n_ + (n_ == 2 ? 1 : 0); }
  int num_inputs() const { return kind_ == Kind::kForward ? n_ : 3; }
  const ShootingScale& scale() const { return scale_; }

  void set_input(const ShootingVector& u) { input_ = u; }

  /// Newton homotopy: solve r(z) = offset instead of r(z) = 0 (empty offset: none).
  void set_residual_offset(const ShootingVector& offset) { offset_ = offset; }

  /// Unknowns in scaled units from physical values.
  ShootingVector pack(const ShootingPoint<double>& p) const {
    ShootingVector z(size());
    for (int i = 0; i < n_; ++i) {
      z(3 * i + 0) = p.wrenches[i].nx / scale_.force;
      z(3 * i + 1) = p.wrenches[i].ny / scale_.force;
      z(3 * i + 2) = p.wrenches[i].m / scale_.moment();
    }
    if (kind_ == Kind::kForward) {
      z(3 * n_ + 0) = p.pose.x / scale_.length;
      z(3 * n_ + 1) = p.pose.y / scale_.length;
      z(3 * n_ + 2) = p.pose.theta;
    } else {
      for (int i = 0; i < n_; ++i) z(3 * n_ + i) = p.q[i] / scale_.length;
      if (n_ == 2) z(4 * n_) = p.pose.theta;
    }
    return z;
  }

  ShootingPoint<double> unpack(const ShootingVector& z) const {
    ShootingPoint<double> p;
    for (int i = 0; i < n_; ++i) {
      p.wrenches[i] = Wrench<double>{z(3 * i) * scale_.force, z(3 * i + 1) * scale_.force,
                                     z(3 * i + 2) * scale_.moment()};
    }
    if (kind_ == Kind::kForward) {
      for (int i = 0; i < n_; ++i) p.q[i] = input_(i);
      p.pose =
          Pose2<double>{z(3 * n_) * scale_.length, z(3 * n_ + 1) * scale_.length, z(3 * n_ + 2)};
    } else {
      for (int i = 0; i < n_; ++i) p.q[i] = z(3 * n_ + i) * scale_.length;
      p.pose = Pose2<double>{input_(0), input_(1), n_ == 2 ? z(4 * n_) : input_(2)};
    }
    return p;
  }

  /// Residual and, on request, the Jacobian w.r.t. the scaled unknowns and the rods' tips (see
  /// shooting_residual). Returns max strain.
  double evaluate(const ShootingVector& z, ShootingVector& r, JacobianMatrix* jacobian,
                  RodTip<double>* tips = nullptr) const {
    const ShootingPoint<double> p = unpack(z);

    ResidualVector<double> res;
    const double strain = shooting_residual(robot_, p, load_, scale_, steps_, res,
                                            jacobian ? &partials_ : nullptr, tips);
    r = res;
    if (offset_.size() == r.size()) r -= offset_;
    if (jacobian) {
      const int m = 3 * n_ + 3;
      if (kind_ == Kind::kForward) {
        *jacobian = partials_.leftCols(m);
      } else {
        jacobian->resize(m, size());
        jacobian->leftCols(3 * n_) = partials_.leftCols(3 * n_);
        jacobian->middleCols(3 * n_, n_) = partials_.middleCols(3 * n_ + 3, n_);
        if (n_ == 2) jacobian->col(4 * n_) = partials_.col(3 * n_ + 2);
      }
    }
    return strain;
  }

  /// d residual / d input times du at z: the first-order change of the residual when the input
  /// moves by du (for the tangent predictor of a warm start).
  ShootingVector input_derivative(const ShootingVector& z, const ShootingVector& du) const {
    const ShootingPoint<double> p = unpack(z);
    ShootingMatrix partials = ShootingMatrix::Zero(3 * n_ + 3, 4 * n_ + 3);
    input_partials(robot_, p, scale_, partials);
    if (kind_ == Kind::kForward) return partials.middleCols(3 * n_ + 3, n_) * (du / scale_.length);
    ShootingVector d = partials.col(3 * n_) * (du(0) / scale_.length) +
                       partials.col(3 * n_ + 1) * (du(1) / scale_.length);
    if (n_ != 2) d += partials.col(3 * n_ + 2) * du(2);
    return d;
  }

 private:
  Kind kind_;
  const RobotParams<double>& robot_;
  const PlatformLoad<double>& load_;
  const SolverOptions& options_;
  ShootingScale scale_;
  int n_;
  int steps_;
  ShootingVector input_;
  ShootingVector offset_;
  mutable ShootingMatrix partials_;
};

}  // namespace pcr::internal
