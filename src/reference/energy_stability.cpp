// Elastic stability by the energy: the rods' angles discretised, the equilibrium found by Newton on
// the first-order (KKT) conditions, and the Hessian of the Lagrangian projected on the null space
// of the constraints. Independent of the shooting solver: no rod ODE, no sensitivities.
#include <Eigen/Dense>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "pcr/reference.hpp"

namespace pcr {
namespace {

/// The discrete model's layout: rod i's N angles at u[i N + k], then the free pose components;
/// the multipliers (two per rod) follow in the KKT system.
struct Layout {
  int rods = 0, segments = 0;
  std::array<int, 3> pose_index{-1, -1, -1};  ///< position in u of x, y, theta; -1: held
  int size = 0;                               ///< of u
};

/// The platform's pose at u (held components from `held`).
Pose2<double> pose_at(const Layout& layout, const Eigen::VectorXd& u, const Pose2<double>& held) {
  const auto component = [&](int j, double fixed) {
    return layout.pose_index[j] < 0 ? fixed : u(layout.pose_index[j]);
  };
  return {component(0, held.x), component(1, held.y), component(2, held.theta)};
}

/// Gradient of the Lagrangian, constraints, Hessian of the Lagrangian and constraint Jacobian at
/// (u, lambda). Energy: sum of the rods' bending energies minus the load's work; constraints: each
/// rod's tip at its distal clamp, A + h sum (cos, sin)(theta_k) - (P + R(phi) B) = 0; the
/// Lagrangian is the energy minus lambda . constraints.
struct Kkt {
  Eigen::VectorXd gradient, constraints;
  Eigen::MatrixXd hessian, jacobian;
};

Kkt evaluate(const EnergyProblem& problem, const Layout& layout, const Eigen::VectorXd& u,
             const Eigen::VectorXd& lambda, const Pose2<double>& held) {
  const int N = layout.segments, n = layout.rods;
  Kkt kkt;
  kkt.gradient = Eigen::VectorXd::Zero(layout.size);
  kkt.hessian = Eigen::MatrixXd::Zero(layout.size, layout.size);
  kkt.constraints = Eigen::VectorXd::Zero(2 * n);
  kkt.jacobian = Eigen::MatrixXd::Zero(2 * n, layout.size);
  const Pose2<double> pose = pose_at(layout, u, held);
  const int ix = layout.pose_index[0], iy = layout.pose_index[1], ith = layout.pose_index[2];
  const double c = std::cos(pose.theta), s = std::sin(pose.theta);
  // The load's work: f . P + m phi.
  if (ix >= 0) kkt.gradient(ix) -= problem.load.force.x();
  if (iy >= 0) kkt.gradient(iy) -= problem.load.force.y();
  if (ith >= 0) kkt.gradient(ith) -= problem.load.moment;
  for (int i = 0; i < n; ++i) {
    const EnergyRod& rod = problem.rods[static_cast<std::size_t>(i)];
    const double h = rod.length / N;
    const int first = i * N;
    // Bending: sum_j w_j (theta_{j+1} - theta_j - int u*)^2 / 2 over theta_0 = alpha (clamp),
    // the N midpoint angles, theta_{N+1} = phi + beta (platform); the half spacing at each end
    // doubles its weight. The energy density EI (theta' - u*)^2 / 2, u* the intrinsic curvature.
    const auto angle = [&](int j) {  // j = 0 ... N + 1
      if (j == 0) return rod.alpha;
      if (j == N + 1) return pose.theta + rod.beta;
      return u(first + j - 1);
    };
    const auto index = [&](int j) {  // position in u, -1 when held
      if (j == 0) return -1;
      if (j == N + 1) return ith;
      return first + j - 1;
    };
    // The intervals between the angles' arc lengths, 0, (k + 1/2) h, l: node j sits at
    // arc_length(j), and the stress-free rod turns by int u* over each interval.
    const auto arc_length = [&](int j) {
      return j == 0 ? 0.0 : j == N + 1 ? rod.length : (j - 0.5) * h;
    };
    const auto intrinsic_turn = [&](double s) {
      return s * (rod.precurvature + 0.5 * rod.precurvature_slope * s);
    };
    // EI over an interval: at its midpoint (a tapered rod's varies; the rule's O(h^2) error is
    // the discretisation's own order).
    const auto ei_over = [&](int j) {
      const double ratio = 1.0 + rod.taper * 0.5 * (arc_length(j) + arc_length(j + 1));  // d(s) / d
      return rod.ei * (ratio * ratio) * (ratio * ratio);
    };
    for (int j = 0; j <= N; ++j) {
      const double w = (j == 0 || j == N ? 2.0 : 1.0) * ei_over(j) / h;
      const double d = angle(j + 1) - angle(j) -
                       (intrinsic_turn(arc_length(j + 1)) - intrinsic_turn(arc_length(j)));
      const int a = index(j + 1), b = index(j);
      if (a >= 0) kkt.gradient(a) += w * d;
      if (b >= 0) kkt.gradient(b) -= w * d;
      if (a >= 0) kkt.hessian(a, a) += w;
      if (b >= 0) kkt.hessian(b, b) += w;
      if (a >= 0 && b >= 0) {
        kkt.hessian(a, b) -= w;
        kkt.hessian(b, a) -= w;
      }
    }
    // The tip's closure: constraint value and Jacobian; the Lagrangian's -lambda . c terms.
    const Eigen::Vector2d l(lambda(2 * i), lambda(2 * i + 1));
    const Eigen::Vector2d arm(c * rod.B.x() - s * rod.B.y(), s * rod.B.x() + c * rod.B.y());
    Eigen::Vector2d tip = rod.A;
    for (int k = 0; k < N; ++k) {
      const double t = u(first + k), ct = std::cos(t), st = std::sin(t);
      tip += h * Eigen::Vector2d(ct, st);
      kkt.jacobian(2 * i, first + k) = -h * st;
      kkt.jacobian(2 * i + 1, first + k) = h * ct;
      kkt.gradient(first + k) -= l.dot(Eigen::Vector2d(-h * st, h * ct));
      kkt.hessian(first + k, first + k) += h * (l.x() * ct + l.y() * st);
    }
    kkt.constraints.segment<2>(2 * i) = tip - pose.translation() - arm;
    if (ix >= 0) {
      kkt.jacobian(2 * i, ix) = -1.0;
      kkt.gradient(ix) += l.x();
    }
    if (iy >= 0) {
      kkt.jacobian(2 * i + 1, iy) = -1.0;
      kkt.gradient(iy) += l.y();
    }
    if (ith >= 0) {
      // d arm / d phi = (-arm_y, arm_x), d^2 arm / d phi^2 = -arm.
      kkt.jacobian(2 * i, ith) = arm.y();
      kkt.jacobian(2 * i + 1, ith) = -arm.x();
      kkt.gradient(ith) -= l.dot(Eigen::Vector2d(arm.y(), -arm.x()));
      kkt.hessian(ith, ith) -= l.dot(arm);
    }
  }
  return kkt;
}

}  // namespace

EnergyStability energy_stability(const EnergyProblem& problem, const EnergyState& start,
                                 const EnergyOptions& options) {
  const int n = static_cast<int>(problem.rods.size());
  if (n < 1 || start.angles.size() != problem.rods.size()) {
    throw std::invalid_argument("energy_stability: one start angle vector per rod is needed");
  }
  const int N = static_cast<int>(start.angles.front().size());
  if (N < 2) throw std::invalid_argument("energy_stability: at least 2 segments per rod");
  double mean_length = 0, mean_ei = 0;
  for (int i = 0; i < n; ++i) {
    const EnergyRod& rod = problem.rods[static_cast<std::size_t>(i)];
    if (static_cast<int>(start.angles[static_cast<std::size_t>(i)].size()) != N ||
        !(rod.length > 0) || !(rod.ei > 0) || !(1.0 + rod.taper * rod.length > 0)) {
      throw std::invalid_argument("energy_stability: rod " + std::to_string(i) +
                                  ": positive length, EI and tip diameter, and the same segment "
                                  "count");
    }
    mean_length += rod.length / n;
    mean_ei += rod.ei / n;
  }
  Layout layout;
  layout.rods = n;
  layout.segments = N;
  layout.size = n * N;
  for (int j = 0; j < 3; ++j) {
    if (problem.platform_free[static_cast<std::size_t>(j)]) layout.pose_index[j] = layout.size++;
  }
  Eigen::VectorXd u(layout.size);
  for (int i = 0; i < n; ++i) {
    for (int k = 0; k < N; ++k) u(i * N + k) = start.angles[static_cast<std::size_t>(i)][k];
  }
  const double pose_start[3] = {start.pose.x, start.pose.y, start.pose.theta};
  for (int j = 0; j < 3; ++j) {
    if (layout.pose_index[j] >= 0) u(layout.pose_index[j]) = pose_start[j];
  }
  Eigen::VectorXd lambda = Eigen::VectorXd::Zero(2 * n);

  // Newton on the KKT conditions, in units where the energy scale is EI / l, lengths l.
  EnergyStability result;
  const double force_scale = mean_ei / (mean_length * mean_length);
  const int m = 2 * n;
  Kkt kkt;
  for (int iteration = 0;; ++iteration) {
    kkt = evaluate(problem, layout, u, lambda, start.pose);
    double norm = kkt.constraints.lpNorm<Eigen::Infinity>() / mean_length;
    for (int a = 0; a < layout.size; ++a) {
      const bool length_unknown = a == layout.pose_index[0] || a == layout.pose_index[1];
      const double scale = length_unknown ? force_scale : force_scale * mean_length;
      norm = std::max(norm, std::abs(kkt.gradient(a)) / scale);
    }
    result.iterations = iteration;
    if (!std::isfinite(norm)) break;
    if (norm <= options.tolerance) {
      result.converged = true;
      break;
    }
    if (iteration == options.max_iterations) break;
    Eigen::MatrixXd K = Eigen::MatrixXd::Zero(layout.size + m, layout.size + m);
    K.topLeftCorner(layout.size, layout.size) = kkt.hessian;
    K.topRightCorner(layout.size, m) = -kkt.jacobian.transpose();
    K.bottomLeftCorner(m, layout.size) = kkt.jacobian;
    Eigen::VectorXd rhs(layout.size + m);
    rhs << -kkt.gradient, -kkt.constraints;
    const Eigen::VectorXd step = K.fullPivLu().solve(rhs);
    u += step.head(layout.size);
    lambda += step.tail(m);
  }
  result.state.pose = pose_at(layout, u, start.pose);
  result.state.angles.assign(problem.rods.size(), std::vector<double>(static_cast<std::size_t>(N)));
  for (int i = 0; i < n; ++i) {
    for (int k = 0; k < N; ++k) result.state.angles[static_cast<std::size_t>(i)][k] = u(i * N + k);
  }
  if (!result.converged) return result;

  // The reduced Hessian: on the null space of the constraints' Jacobian, in the metric
  // M = diag(h / l for each angle, 1 / l^2 for x and y, 1 for theta), energy in units of EI / l.
  // Its smallest eigenvalue then approximates that of the continuous problem's second variation,
  // (int EI dtheta'^2 + ...) / ((EI / l) (int dtheta^2 / l + |dP|^2 / l^2 + dphi^2)), whatever N.
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(kkt.jacobian.transpose());
  const int rank = static_cast<int>(qr.rank());
  const Eigen::MatrixXd Q = qr.householderQ();
  const Eigen::MatrixXd Z = Q.rightCols(layout.size - rank);
  Eigen::VectorXd metric(layout.size);
  for (int i = 0; i < n; ++i) {
    const double h = problem.rods[static_cast<std::size_t>(i)].length / N;
    metric.segment(i * N, N).setConstant(h / mean_length);
  }
  for (int j = 0; j < 3; ++j) {
    if (layout.pose_index[j] >= 0) {
      metric(layout.pose_index[j]) = j < 2 ? 1.0 / (mean_length * mean_length) : 1.0;
    }
  }
  Eigen::MatrixXd reduced = Z.transpose() * kkt.hessian * Z / (mean_ei / mean_length);
  reduced = 0.5 * (reduced + reduced.transpose()).eval();
  const Eigen::MatrixXd reduced_metric = Z.transpose() * metric.asDiagonal() * Z;
  const Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> eigen(reduced, reduced_metric,
                                                                        Eigen::EigenvaluesOnly);
  if (eigen.info() != Eigen::Success) {
    result.converged = false;
    return result;
  }
  result.min_eigenvalue = eigen.eigenvalues()(0);
  return result;
}

EnergyProblem energy_problem(const RobotParams<double>& robot, const JointVector& q,
                             const PlatformLoad<double>& load) {
  if (q.size() != robot.num_limbs) throw std::invalid_argument("energy_problem: one q per limb");
  EnergyProblem problem;
  problem.load = load;
  for (int i = 0; i < robot.num_limbs; ++i) {
    const LimbParams<double>& limb = robot.limb(i);
    problem.rods.push_back({limb.proximal_position(q(i)), limb.alpha, limb.B, limb.beta,
                            limb.rod.length, limb.rod.bending_stiffness(), limb.rod.precurvature,
                            limb.rod.precurvature_slope,
                            limb.rod.diameter_slope / limb.rod.diameter});
  }
  return problem;
}

EnergyState energy_start(const RobotParams<double>& robot, const JointVector& q,
                         const Pose2<double>& pose,
                         const std::array<Wrench<double>, kMaxLimbs>& wrenches, int segments) {
  EnergyState start;
  start.pose = pose;
  for (int i = 0; i < robot.num_limbs; ++i) {
    const LimbParams<double>& limb = robot.limb(i);
    // The angle at each segment's midpoint: two RK4 steps per segment, so that it is a node.
    std::vector<double> angles;
    sample_rod(proximal_rod_state(limb, q(i), wrenches[static_cast<std::size_t>(i)]), limb.rod,
               2 * segments,
               [&](double, const RodState<double>& state) { angles.push_back(state.theta); });
    std::vector<double> midpoints;
    for (int k = 0; k < segments; ++k)
      midpoints.push_back(angles[static_cast<std::size_t>(2 * k + 1)]);
    start.angles.push_back(midpoints);
  }
  return start;
}

}  // namespace pcr
