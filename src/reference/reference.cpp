// CVODE reference integrator of the planar Kirchhoff rod and the forward kinematics built on it.

#include "pcr/reference.hpp"

#include <cvode/cvode.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>

namespace pcr {
namespace {

// CVODE state: (x, y, theta, m). n is constant (n' = 0), so it rides along as a parameter.
constexpr int kStates = 4;

// EI(s) and u*(s) come from the Rod's own formulas, evaluated at CVODE's arc lengths; the
// RK4 stepper's stage-wise evaluation is not shared.
struct RodData {
  double nx, ny;
  const Rod<double>* rod;
};

int rod_rhs(sunrealtype arc, N_Vector y, N_Vector ydot, void* user_data) {
  const auto* data = static_cast<const RodData*>(user_data);
  const double* Y = N_VGetArrayPointer(y);
  double* D = N_VGetArrayPointer(ydot);
  const double c = std::cos(Y[2]), s = std::sin(Y[2]);
  D[0] = c;
  D[1] = s;
  D[2] = Y[3] / data->rod->bending_stiffness_at(arc) + data->rod->intrinsic_curvature(arc);
  D[3] = data->nx * s - data->ny * c;
  return 0;
}

int rod_jacobian(sunrealtype arc, N_Vector y, N_Vector /*fy*/, SUNMatrix J, void* user_data,
                 N_Vector, N_Vector, N_Vector) {
  const auto* data = static_cast<const RodData*>(user_data);
  const double theta = N_VGetArrayPointer(y)[2];
  const double c = std::cos(theta), s = std::sin(theta);
  SUNMatZero(J);
  SM_ELEMENT_D(J, 0, 2) = -s;
  SM_ELEMENT_D(J, 1, 2) = c;
  SM_ELEMENT_D(J, 2, 3) = 1.0 / data->rod->bending_stiffness_at(arc);
  SM_ELEMENT_D(J, 3, 2) = data->nx * c + data->ny * s;
  return 0;
}

void capture_error(int error_code, const char* module, const char* function, char* msg,
                   void* user_data) {
  auto* out = static_cast<std::string*>(user_data);
  std::ostringstream text;
  text << module << "::" << function << " (code " << error_code << "): " << msg;
  *out = text.str();
}

// RAII owners of the SUNDIALS objects.
struct ContextDeleter {
  void operator()(SUNContext ctx) const { SUNContext_Free(&ctx); }
};
struct VectorDeleter {
  void operator()(_generic_N_Vector* v) const { N_VDestroy(v); }
};
struct MatrixDeleter {
  void operator()(_generic_SUNMatrix* m) const { SUNMatDestroy(m); }
};
struct SolverDeleter {
  void operator()(_generic_SUNLinearSolver* ls) const { SUNLinSolFree(ls); }
};
struct CvodeDeleter {
  void operator()(void* mem) const { CVodeFree(&mem); }
};

std::string describe(const char* what, double value) {
  std::ostringstream text;
  text.precision(17);
  text << what << " = " << value;
  return text.str();
}

void check_rod_input(const RodState<double>& start, const Rod<double>& rod) {
  const double ei = rod.bending_stiffness(), length = rod.length;
  const double values[] = {start.x,           start.y, start.theta,      start.nx,
                           start.ny,          start.m, rod.precurvature, rod.precurvature_slope,
                           rod.diameter_slope};
  const char* names[] = {
      "start.x",           "start.y", "start.theta",      "start.nx",
      "start.ny",          "start.m", "rod.precurvature", "rod.precurvature_slope",
      "rod.diameter_slope"};
  for (int i = 0; i < 9; ++i) {
    if (!std::isfinite(values[i])) {
      throw std::invalid_argument("pcr::integrate_rod_reference: non-finite " +
                                  describe(names[i], values[i]));
    }
  }
  if (!(ei > 0.0) || !std::isfinite(ei)) {
    throw std::invalid_argument("pcr::integrate_rod_reference: EI must be positive, " +
                                describe("ei", ei));
  }
  if (!(length > 0.0) || !std::isfinite(length)) {
    throw std::invalid_argument("pcr::integrate_rod_reference: length must be positive, " +
                                describe("length", length));
  }
  if (!(rod.diameter_at(length) > 0.0)) {
    throw std::invalid_argument(
        "pcr::integrate_rod_reference: the tip's diameter must be "
        "positive, " +
        describe("d(l)", rod.diameter_at(length)));
  }
}

// One CVODE integration over s in [0, length] and its SUNDIALS objects. The caller fills state()
// and absolute_tolerance(), then start()s it; a failed call throws std::runtime_error naming the
// caller, the call and CVODE's own message.
class CvodeIntegration {
 public:
  CvodeIntegration(const char* caller, int size, double length, const ReferenceOptions& options)
      : caller_(caller), length_(length), options_(options) {
    SUNContext raw_ctx = nullptr;
    if (SUNContext_Create(nullptr, &raw_ctx) != 0) fail("SUNContext_Create", -1);
    ctx_.reset(raw_ctx);
    y_.reset(N_VNew_Serial(size, ctx_.get()));
    abstol_.reset(N_VNew_Serial(size, ctx_.get()));
    dense_.reset(N_VNew_Serial(size, ctx_.get()));
    if (!y_ || !abstol_ || !dense_) fail("N_VNew_Serial", -1);
    matrix_.reset(SUNDenseMatrix(size, size, ctx_.get()));
    if (!matrix_) fail("SUNDenseMatrix", -1);
  }
  // capture_error keeps a pointer to error_.
  CvodeIntegration(const CvodeIntegration&) = delete;
  CvodeIntegration& operator=(const CvodeIntegration&) = delete;

  double* state() { return N_VGetArrayPointer(y_.get()); }
  double* absolute_tolerance() { return N_VGetArrayPointer(abstol_.get()); }

  // Sets the method, tolerances and right-hand side up from the filled state at s = 0. Without
  // a Jacobian function CVODE approximates it by difference quotients: it only steers the
  // corrector's Newton iteration, never the solution.
  void start(CVRhsFn rhs, void* user_data, CVLsJacFn jacobian) {
    const int lmm = options_.method == ReferenceOptions::Method::kBdf ? CV_BDF : CV_ADAMS;
    mem_.reset(CVodeCreate(lmm, ctx_.get()));
    if (!mem_) fail("CVodeCreate", -1);
    check("CVodeSetErrHandlerFn", CVodeSetErrHandlerFn(mem_.get(), capture_error, &error_));
    check("CVodeInit", CVodeInit(mem_.get(), rhs, 0.0, y_.get()));
    check("CVodeSVtolerances",
          CVodeSVtolerances(mem_.get(), options_.relative_tolerance, abstol_.get()));
    check("CVodeSetUserData", CVodeSetUserData(mem_.get(), user_data));
    check("CVodeSetStopTime", CVodeSetStopTime(mem_.get(), length_));
    solver_.reset(SUNLinSol_Dense(y_.get(), matrix_.get(), ctx_.get()));
    if (!solver_) fail("SUNLinSol_Dense", -1);
    check("CVodeSetLinearSolver", CVodeSetLinearSolver(mem_.get(), solver_.get(), matrix_.get()));
    if (jacobian) check("CVodeSetJacFn", CVodeSetJacFn(mem_.get(), jacobian));
  }

  // One internal step towards s = length; returns the s reached, state() holds the state there.
  double step() {
    // CV_ONE_STEP bypasses CVodeSetMaxNumSteps (it bounds one CV_NORMAL call): count here.
    if (++steps_ > options_.max_steps) {
      error_ = "more than max_steps = " + std::to_string(options_.max_steps) +
               " internal steps before s = " + std::to_string(length_) +
               " m, at s = " + std::to_string(s_) + " m";
      fail("CVode", CV_TOO_MUCH_WORK);
    }
    check("CVode", CVode(mem_.get(), length_, y_.get(), &s_, CV_ONE_STEP));
    return s_;
  }

  // The state at s = at inside the last step, by CVODE's dense output.
  const double* dense(double at) {
    check("CVodeGetDky", CVodeGetDky(mem_.get(), at, 0, dense_.get()));
    return N_VGetArrayPointer(dense_.get());
  }

  [[noreturn]] void fail(const char* call, int flag) const {
    std::ostringstream text;
    text << caller_ << ": CVODE " << call << " failed (flag " << flag << ")";
    if (!error_.empty()) text << ": " << error_;
    throw std::runtime_error(text.str());
  }
  void check(const char* call, int flag) const {
    if (flag < 0) fail(call, flag);
  }

 private:
  std::string caller_;
  double length_;
  ReferenceOptions options_;
  std::string error_;
  std::unique_ptr<_SUNContext, ContextDeleter> ctx_;
  std::unique_ptr<_generic_N_Vector, VectorDeleter> y_, abstol_, dense_;
  std::unique_ptr<_generic_SUNMatrix, MatrixDeleter> matrix_;
  std::unique_ptr<_generic_SUNLinearSolver, SolverDeleter> solver_;
  std::unique_ptr<void, CvodeDeleter> mem_;
  double s_ = 0.0;
  long steps_ = 0;
};

// Integrates one rod with CVODE, reporting the state at each requested arc length (sorted, in
// [0, length]) through `samples` and max |m| at the internal steps.
RodState<double> integrate(const RodState<double>& start, const Rod<double>& rod,
                           const ReferenceOptions& options, const std::vector<double>& arc_lengths,
                           std::vector<RodState<double>>* samples, double* max_abs_moment) {
  check_rod_input(start, rod);
  const double ei = rod.bending_stiffness(), length = rod.length;
  CvodeIntegration cvode("pcr::integrate_rod_reference", kStates, length, options);
  double* Y = cvode.state();
  Y[0] = start.x;
  Y[1] = start.y;
  Y[2] = start.theta;
  Y[3] = start.m;
  const double force = std::hypot(start.nx, start.ny);
  const double moment_scale = std::max({ei / length, std::abs(start.m), force * length});
  double* A = cvode.absolute_tolerance();
  A[0] = options.absolute_tolerance * length;
  A[1] = options.absolute_tolerance * length;
  A[2] = options.absolute_tolerance;
  A[3] = options.absolute_tolerance * moment_scale;
  RodData data{start.nx, start.ny, &rod};
  cvode.start(rod_rhs, &data, rod_jacobian);

  const auto state_of = [&](const double* v) {
    return RodState<double>{v[0], v[1], v[2], start.nx, start.ny, v[3]};
  };
  std::size_t next_sample = 0;
  // Samples at s = 0 need no step.
  while (samples && next_sample < arc_lengths.size() && arc_lengths[next_sample] <= 0.0) {
    samples->push_back(start);
    ++next_sample;
  }
  double max_m = std::abs(start.m);
  double s = 0.0;
  while (s < length) {
    // One internal step at a time: max |m| is tracked at every step and the samples come from
    // the dense output of the step that covers them.
    s = cvode.step();
    // Scaled to the proximal section, as RodTip::max_abs_moment: the strain's largest.
    const double thinning = rod.diameter / rod.diameter_at(std::min(s, length));
    max_m = std::max(max_m, std::abs(Y[3]) * thinning * thinning * thinning);
    while (samples && next_sample < arc_lengths.size() &&
           (arc_lengths[next_sample] <= s || s >= length)) {
      samples->push_back(state_of(cvode.dense(std::min(arc_lengths[next_sample], s))));
      ++next_sample;
    }
  }
  if (max_abs_moment) *max_abs_moment = max_m;
  return state_of(Y);
}

// ---- The spatial rod ----------------------------------------------------------------------------

// CVODE state of the spatial rod: p (3), R (9, column-major), m (3). The orientation is the
// rotation matrix itself, R' = R [u]x, not the RK4 core's quaternion; n(s) = n(0) - f s is exact
// and rides along in closed form.
constexpr int kSpatialStates = 15;

struct SpatialRodData {
  Eigen::Vector3d base_force;         // n(0) (N)
  Eigen::Vector3d distributed_force;  // f = rho A g (N/m)
  Eigen::Vector3d bending_stiffness;  // (EI, EI, GJ) (N m^2)
  Eigen::Vector3d shear_stiffness;    // (GA, GA, EA) (N)
  Eigen::Vector3d intrinsic_curvature;
  bool shear_and_extension;
};

int spatial_rod_rhs(sunrealtype arc, N_Vector y, N_Vector ydot, void* user_data) {
  const auto* data = static_cast<const SpatialRodData*>(user_data);
  const double* Y = N_VGetArrayPointer(y);
  double* D = N_VGetArrayPointer(ydot);
  const Eigen::Map<const Eigen::Matrix3d> R(Y + 3);
  const Eigen::Map<const Eigen::Vector3d> m(Y + 12);
  const Eigen::Vector3d n = data->base_force - arc * data->distributed_force;
  const Eigen::Vector3d u =
      (R.transpose() * m).cwiseQuotient(data->bending_stiffness) + data->intrinsic_curvature;
  Eigen::Vector3d v = Eigen::Vector3d::UnitZ();
  if (data->shear_and_extension) v += (R.transpose() * n).cwiseQuotient(data->shear_stiffness);
  const Eigen::Vector3d p_prime = R * v;
  Eigen::Matrix3d u_hat;
  u_hat << 0, -u.z(), u.y(), u.z(), 0, -u.x(), -u.y(), u.x(), 0;
  Eigen::Map<Eigen::Vector3d> p_dot(D), m_dot(D + 12);
  Eigen::Map<Eigen::Matrix3d> R_dot(D + 3);
  p_dot = p_prime;
  R_dot.noalias() = R * u_hat;
  m_dot = -p_prime.cross(n);
  return 0;
}

void check_spatial_rod_input(const SpatialRodState<double>& base, const SpatialRod<double>& rod,
                             const Vector3<double>& gravity) {
  const char* caller = "pcr::integrate_spatial_rod_reference: ";
  const auto check_finite = [&](const char* name, const auto& values) {
    for (int i = 0; i < values.size(); ++i) {
      if (!std::isfinite(values[i])) {
        const std::string what = std::string(name) + "[" + std::to_string(i) + "]";
        throw std::invalid_argument(caller + ("non-finite " + describe(what.c_str(), values[i])));
      }
    }
  };
  check_finite("base.position", base.position);
  check_finite("base.orientation", base.orientation);
  check_finite("base.force", base.force);
  check_finite("base.moment", base.moment);
  check_finite("rod.intrinsic_curvature", rod.intrinsic_curvature);
  check_finite("gravity", gravity);
  if (!(base.orientation.squaredNorm() > 0.0)) {
    throw std::invalid_argument(caller + std::string("base.orientation is the zero quaternion"));
  }
  const double positive[] = {rod.length, rod.diameter, rod.young_modulus, rod.shear_modulus};
  const char* names[] = {"rod.length", "rod.diameter", "rod.young_modulus", "rod.shear_modulus"};
  for (int i = 0; i < 4; ++i) {
    if (!(positive[i] > 0.0) || !std::isfinite(positive[i])) {
      throw std::invalid_argument(caller +
                                  ("must be positive, " + describe(names[i], positive[i])));
    }
  }
  if (!(rod.density >= 0.0) || !std::isfinite(rod.density)) {
    throw std::invalid_argument(caller +
                                ("must be non-negative, " + describe("rod.density", rod.density)));
  }
}

}  // namespace

RodState<double> integrate_rod_reference(const RodState<double>& start, const Rod<double>& rod,
                                         const ReferenceOptions& options, double* max_abs_moment) {
  return integrate(start, rod, options, {}, nullptr, max_abs_moment);
}

SpatialRodState<double> integrate_spatial_rod_reference(const SpatialRodState<double>& base,
                                                        const SpatialRod<double>& rod,
                                                        const Vector3<double>& gravity,
                                                        const ReferenceOptions& options) {
  check_spatial_rod_input(base, rod, gravity);
  const double length = rod.length, ei = rod.bending_stiffness();
  SpatialRodData data;
  data.base_force = base.force;
  data.distributed_force = rod.mass_per_length() * gravity;
  data.bending_stiffness << ei, ei, rod.torsional_stiffness();
  data.shear_stiffness << rod.shear_stiffness(), rod.shear_stiffness(), rod.axial_stiffness();
  data.intrinsic_curvature = rod.intrinsic_curvature;
  data.shear_and_extension = rod.shear_and_extension;

  CvodeIntegration cvode("pcr::integrate_spatial_rod_reference", kSpatialStates, length, options);
  double* Y = cvode.state();
  // Eigen's quaternion conversions, not the core's rotation_of / quaternion_of.
  const Eigen::Quaterniond base_rotation(base.orientation[0], base.orientation[1],
                                         base.orientation[2], base.orientation[3]);
  Eigen::Map<Eigen::Vector3d> position(Y), moment(Y + 12);
  Eigen::Map<Eigen::Matrix3d> rotation(Y + 3);
  position = base.position;
  rotation = base_rotation.normalized().toRotationMatrix();
  moment = base.moment;
  const double moment_scale = std::max({ei / length, base.moment.norm(), base.force.norm() * length,
                                        data.distributed_force.norm() * length * length});
  double* A = cvode.absolute_tolerance();
  for (int i = 0; i < 3; ++i) A[i] = options.absolute_tolerance * length;
  for (int i = 3; i < 12; ++i) A[i] = options.absolute_tolerance;
  for (int i = 12; i < 15; ++i) A[i] = options.absolute_tolerance * moment_scale;
  cvode.start(spatial_rod_rhs, &data, nullptr);
  for (double s = 0.0; s < length;) s = cvode.step();

  SpatialRodState<double> tip;
  tip.position = position;
  const Eigen::Matrix3d tip_matrix = rotation;
  const Eigen::Quaterniond tip_rotation(tip_matrix);
  tip.orientation << tip_rotation.w(), tip_rotation.x(), tip_rotation.y(), tip_rotation.z();
  tip.orientation.normalize();
  tip.force = base.force - length * data.distributed_force;
  tip.moment = moment;
  return tip;
}

std::vector<RodState<double>> sample_rod_reference(const RodState<double>& start,
                                                   const Rod<double>& rod,
                                                   const std::vector<double>& arc_lengths,
                                                   const ReferenceOptions& options) {
  const double length = rod.length;
  for (std::size_t i = 0; i < arc_lengths.size(); ++i) {
    const double s = arc_lengths[i];
    const std::string name = "arc_lengths[" + std::to_string(i) + "]";
    if (!(s >= 0.0 && s <= length)) {
      throw std::invalid_argument("pcr::sample_rod_reference: outside [0, length = " +
                                  std::to_string(length) + "]: " + describe(name.c_str(), s));
    }
    if (i > 0 && s < arc_lengths[i - 1]) {
      throw std::invalid_argument("pcr::sample_rod_reference: arc lengths must not decrease: " +
                                  describe(name.c_str(), s));
    }
  }
  std::vector<RodState<double>> samples;
  samples.reserve(arc_lengths.size());
  integrate(start, rod, options, arc_lengths, &samples, nullptr);
  return samples;
}

double shooting_residual_reference(const RobotParams<double>& robot,
                                   const ShootingPoint<double>& point,
                                   const PlatformLoad<double>& load, const ShootingScale& scale,
                                   ResidualVector<double>& residual,
                                   const ReferenceOptions& options) {
  // The rods by CVODE, the equations from their tips as pcr::shooting_residual forms them.
  const int n = robot.num_limbs;
  if (n < 2 || n > kMaxLimbs) {
    throw std::invalid_argument("pcr::shooting_residual_reference: " +
                                describe("robot.num_limbs", n));
  }
  RodTip<double> tips[kMaxLimbs];
  for (int i = 0; i < n; ++i) {
    const LimbParams<double>& limb = robot.limb(i);
    tips[i].state = integrate_rod_reference(proximal_rod_state(limb, point.q[i], point.wrenches[i]),
                                            limb.rod, options, &tips[i].max_abs_moment);
  }
  return shooting_residual_from_tips(robot, point, load, scale, tips, residual);
}

ForwardSolution forward_kinematics_reference(const RobotParams<double>& robot, const JointVector& q,
                                             const ForwardSolution& start,
                                             const ReferenceOptions& options,
                                             const PlatformLoad<double>& load) {
  const int n = robot.num_limbs;
  if (n < 2 || n > kMaxLimbs) {
    throw std::invalid_argument("pcr::forward_kinematics_reference: " +
                                describe("robot.num_limbs", n));
  }
  if (q.size() != n) {
    throw std::invalid_argument("pcr::forward_kinematics_reference: q has " +
                                std::to_string(q.size()) + " entries for " + std::to_string(n) +
                                " limbs");
  }
  if (!q.allFinite()) {
    throw std::invalid_argument("pcr::forward_kinematics_reference: q is not finite");
  }
  const ShootingScale scale = shooting_scale(robot);
  // The RK4 FK problem at the reference's Jacobian step count: the scaling of the unknowns and
  // the Newton matrix.
  SolverOptions rk4;
  rk4.rod_steps = options.jacobian_rod_steps;
  internal::ShootingProblem problem(internal::ShootingProblem::Kind::kForward, robot, load, rk4);
  problem.set_input(q);

  ShootingPoint<double> start_point;
  start_point.pose = start.pose;
  for (int i = 0; i < n; ++i) start_point.wrenches[i] = start.wrenches[i];
  ShootingVector z = problem.pack(start_point);

  ForwardSolution solution;
  solution.q = q;
  SolverSummary& summary = solution.summary;
  ResidualVector<double> r;
  ShootingVector r_rk4;
  JacobianMatrix J;
  internal::JacobianLU lu;

  // Quasi-Newton: the residual is CVODE's, the matrix the RK4 Jacobian. The fixed point is the
  // CVODE solution; the iteration contracts by about the RK4 discretisation error of J.
  ShootingVector best_z = z;
  double best_norm = std::numeric_limits<double>::infinity();
  int stalls = 0;
  summary.status = SolveStatus::kMaxIterations;
  for (int iter = 0;; ++iter) {
    const ShootingPoint<double> p = problem.unpack(z);
    const double strain = shooting_residual_reference(robot, p, load, scale, r, options);
    ++summary.residual_evaluations;
    const double norm = internal::max_norm(r);
    if (iter == 0) summary.initial_residual_norm = norm;
    if (!std::isfinite(norm)) {
      summary.status = SolveStatus::kNonFinite;
      break;
    }
    if (norm < best_norm) {
      best_norm = norm;
      best_z = z;
      summary.max_strain = strain;
      stalls = 0;
    } else if (++stalls >= 3) {
      break;  // CVODE's rounding floor, or divergence: keep the best point
    }
    if (norm <= options.tolerance) {
      summary.status = SolveStatus::kConverged;
      break;
    }
    if (iter >= options.max_iterations) break;
    ++summary.iterations;
    problem.evaluate(z, r_rk4, &J);
    lu.compute(J);
    if (!(std::abs(lu.determinant()) > 0.0) || !(lu.rcond() > 1e-14)) {
      summary.status = SolveStatus::kSingular;
      break;
    }
    z -= lu.solve(ShootingVector(r));
  }
  summary.final_residual_norm = best_norm;
  const ShootingPoint<double> p = problem.unpack(best_z);
  solution.pose = p.pose;
  for (int i = 0; i < n; ++i) solution.wrenches[i] = p.wrenches[i];
  return solution;
}

}  // namespace pcr
