// CVODE reference integrator of the planar Kirchhoff rod and the forward kinematics built on it.

#include "pcr/reference.hpp"

#include <cvode/cvode.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>

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

// Integrates one rod with CVODE, reporting the state at each requested arc length (sorted, in
// [0, length]) through `samples` and max |m| at the internal steps.
RodState<double> integrate(const RodState<double>& start, const Rod<double>& rod,
                           const ReferenceOptions& options, const std::vector<double>& arc_lengths,
                           std::vector<RodState<double>>* samples, double* max_abs_moment) {
  check_rod_input(start, rod);
  const double ei = rod.bending_stiffness(), length = rod.length;
  std::string error;
  const auto fail = [&](const char* call, int flag) {
    std::ostringstream text;
    text << "pcr::integrate_rod_reference: CVODE " << call << " failed (flag " << flag << ")";
    if (!error.empty()) text << ": " << error;
    throw std::runtime_error(text.str());
  };
  const auto check = [&](const char* call, int flag) {
    if (flag < 0) fail(call, flag);
  };

  SUNContext raw_ctx = nullptr;
  if (SUNContext_Create(nullptr, &raw_ctx) != 0) fail("SUNContext_Create", -1);
  std::unique_ptr<_SUNContext, ContextDeleter> ctx(raw_ctx);

  std::unique_ptr<_generic_N_Vector, VectorDeleter> y(N_VNew_Serial(kStates, ctx.get()));
  std::unique_ptr<_generic_N_Vector, VectorDeleter> abstol(N_VNew_Serial(kStates, ctx.get()));
  std::unique_ptr<_generic_N_Vector, VectorDeleter> dense(N_VNew_Serial(kStates, ctx.get()));
  if (!y || !abstol || !dense) fail("N_VNew_Serial", -1);
  double* Y = N_VGetArrayPointer(y.get());
  Y[0] = start.x;
  Y[1] = start.y;
  Y[2] = start.theta;
  Y[3] = start.m;
  const double force = std::hypot(start.nx, start.ny);
  const double moment_scale = std::max({ei / length, std::abs(start.m), force * length});
  double* A = N_VGetArrayPointer(abstol.get());
  A[0] = options.absolute_tolerance * length;
  A[1] = options.absolute_tolerance * length;
  A[2] = options.absolute_tolerance;
  A[3] = options.absolute_tolerance * moment_scale;

  const int lmm = options.method == ReferenceOptions::Method::kBdf ? CV_BDF : CV_ADAMS;
  std::unique_ptr<void, CvodeDeleter> mem(CVodeCreate(lmm, ctx.get()));
  if (!mem) fail("CVodeCreate", -1);
  check("CVodeSetErrHandlerFn", CVodeSetErrHandlerFn(mem.get(), capture_error, &error));
  check("CVodeInit", CVodeInit(mem.get(), rod_rhs, 0.0, y.get()));
  check("CVodeSVtolerances",
        CVodeSVtolerances(mem.get(), options.relative_tolerance, abstol.get()));
  RodData data{start.nx, start.ny, &rod};
  check("CVodeSetUserData", CVodeSetUserData(mem.get(), &data));
  check("CVodeSetStopTime", CVodeSetStopTime(mem.get(), length));

  std::unique_ptr<_generic_SUNMatrix, MatrixDeleter> matrix(
      SUNDenseMatrix(kStates, kStates, ctx.get()));
  if (!matrix) fail("SUNDenseMatrix", -1);
  std::unique_ptr<_generic_SUNLinearSolver, SolverDeleter> solver(
      SUNLinSol_Dense(y.get(), matrix.get(), ctx.get()));
  if (!solver) fail("SUNLinSol_Dense", -1);
  check("CVodeSetLinearSolver", CVodeSetLinearSolver(mem.get(), solver.get(), matrix.get()));
  check("CVodeSetJacFn", CVodeSetJacFn(mem.get(), rod_jacobian));

  const auto state_of = [&](const double* v) {
    return RodState<double>{v[0], v[1], v[2], start.nx, start.ny, v[3]};
  };
  std::size_t next_sample = 0;
  const double* D = N_VGetArrayPointer(dense.get());
  // Samples at s = 0 need no step.
  while (samples && next_sample < arc_lengths.size() && arc_lengths[next_sample] <= 0.0) {
    samples->push_back(start);
    ++next_sample;
  }
  double max_m = std::abs(start.m);
  double s = 0.0;
  long steps = 0;
  while (s < length) {
    // CV_ONE_STEP bypasses CVodeSetMaxNumSteps (it bounds one CV_NORMAL call): count here.
    if (++steps > options.max_steps) {
      error = "more than max_steps = " + std::to_string(options.max_steps) +
              " internal steps before s = " + std::to_string(length) +
              " m, at s = " + std::to_string(s) + " m";
      fail("CVode", CV_TOO_MUCH_WORK);
    }
    // One internal step at a time: max |m| is tracked at every step and the samples come from
    // the dense output of the step that covers them.
    check("CVode", CVode(mem.get(), length, y.get(), &s, CV_ONE_STEP));
    // Scaled to the proximal section, as RodTip::max_abs_moment: the strain's largest.
    const double thinning = rod.diameter / rod.diameter_at(std::min(s, length));
    max_m = std::max(max_m, std::abs(Y[3]) * thinning * thinning * thinning);
    while (samples && next_sample < arc_lengths.size() &&
           (arc_lengths[next_sample] <= s || s >= length)) {
      const double at = std::min(arc_lengths[next_sample], s);
      check("CVodeGetDky", CVodeGetDky(mem.get(), at, 0, dense.get()));
      samples->push_back(state_of(D));
      ++next_sample;
    }
  }
  if (max_abs_moment) *max_abs_moment = max_m;
  return state_of(Y);
}

}  // namespace

RodState<double> integrate_rod_reference(const RodState<double>& start, const Rod<double>& rod,
                                         const ReferenceOptions& options, double* max_abs_moment) {
  return integrate(start, rod, options, {}, nullptr, max_abs_moment);
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
