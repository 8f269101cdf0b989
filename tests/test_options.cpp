// Each options struct decides its own ranges (is_valid): its defaults are valid, every value drawn
// inside a range is accepted and every value outside it refused, naming the field and the value;
// the solvers and the library's entry points refuse what is_valid refuses.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <random>
#include <string>
#include <type_traits>
#include <vector>

#include "pcr/calib/accuracy.hpp"
#include "pcr/calib/calibrator.hpp"
#include "pcr/calib/method.hpp"
#include "pcr/calib/sampling.hpp"
#include "pcr/calib/sensitivity.hpp"
#include "pcr/calib/virtual_robot.hpp"
#include "pcr/calib/workspace_map.hpp"

namespace pcr {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

/// A field of an options struct and its range: sets the field of a default struct to a value
/// and asks is_valid.
struct Field {
  OptionRange range;
  std::string prefix;  ///< "effects." for a nested struct's field
  bool integer;
  std::function<bool(double, std::string*)> valid_with;
};

template <class Options, class T>
Field field(const OptionRange& range, T Options::*member, const char* prefix = "") {
  return Field{range, prefix, std::is_integral_v<T>, [member](double v, std::string* error) {
                 Options o;
                 o.*member = static_cast<T>(v);
                 return o.is_valid(error);
               }};
}

std::vector<Field> all_fields() {
  using S = SolverOptions;
  using C = CalibrationOptions;
  std::vector<Field> f = {
      field(S::kRodSteps, &S::rod_steps),
      field(S::kPositionAccuracy, &S::position_accuracy),
      field(S::kAngleAccuracy, &S::angle_accuracy),
      field(S::kMaxIterations, &S::max_iterations),
      field(S::kTolerance, &S::tolerance),
      field(S::kChordOutputShare, &S::chord_output_share),
      field(S::kMaxLineSearch, &S::max_line_search),
      field(S::kMaxContinuationSteps, &S::max_continuation_steps),
      field(S::kMaxContinuationIterations, &S::max_continuation_iterations),
      field(S::kMinContinuationStep, &S::min_continuation_step),
      field(S::kMaxArclengthSteps, &S::max_arclength_steps),
      field(kStrainLimitRange, &PathStepOptions::strain_limit),
      field(AccuracyOptions::kRepeat, &AccuracyOptions::repeat),
      field(SamplingOptions::kCount, &SamplingOptions::count),
      field(SamplingOptions::kMinDistance, &SamplingOptions::min_distance),
      field(kStrainLimitRange, &SamplingOptions::strain_limit),
      field(SamplingOptions::kAttempts, &SamplingOptions::attempts),
      field(SamplingOptions::kCandidates, &SamplingOptions::candidates),
      field(SamplingOptions::kNoisePosition, &SamplingOptions::noise_position),
      field(SamplingOptions::kNoiseAngle, &SamplingOptions::noise_angle),
      field(SensitivityOptions::kStep, &SensitivityOptions::step),
      field(VirtualRobotOptions::kTruthAtFraction, &VirtualRobotOptions::truth_at_fraction),
      field(VirtualRobotOptions::kNoisePosition, &VirtualRobotOptions::noise_position),
      field(VirtualRobotOptions::kNoiseAngle, &VirtualRobotOptions::noise_angle),
      field(WorkspaceMapOptions::kTheta, &WorkspaceMapOptions::theta),
      field(WorkspaceMapOptions::kGrid, &WorkspaceMapOptions::grid),
      field(WorkspaceMapOptions::kThreads, &WorkspaceMapOptions::threads),
      field(C::kOrientationWeight, &C::orientation_weight),
      field(C::kResidualScale, &C::residual_scale),
      field(C::kMaxIterations, &C::max_iterations),
      field(C::kGaugePriorWeight, &C::gauge_prior_weight),
      field(C::kFunctionTolerance, &C::function_tolerance),
      field(C::kIntermediateFunctionTolerance, &C::intermediate_function_tolerance),
      field(C::kRobustScale, &C::robust_scale),
      field(SquarePath::kSide, &SquarePath::side),
      field(SquarePath::kTheta, &SquarePath::theta),
      field(SquarePath::kNumPoses, &SquarePath::num_poses),
      field(CirclePath::kDiameter, &CirclePath::diameter),
      field(CirclePath::kTheta, &CirclePath::theta),
      field(CirclePath::kNumPoses, &CirclePath::num_poses),
      field(PlatformLoad<double>::kMoment, &PlatformLoad<double>::moment),
  };
  // The effects are a nested struct: VirtualRobotOptions names them with their prefix.
  for (auto [range, member] : {std::pair{UnmodelledEffects::kMisalignmentHalfWidth,
                                         &UnmodelledEffects::misalignment_half_width},
                               std::pair{UnmodelledEffects::kDiameterHalfWidth,
                                         &UnmodelledEffects::diameter_half_width}}) {
    f.push_back(Field{range, "effects.", false, [member = member](double v, std::string* error) {
                        VirtualRobotOptions o;
                        o.effects.*member = v;
                        return o.is_valid(error);
                      }});
  }
  // The options that carry a load check its moment; the effects name it with their prefix.
  const OptionRange moment = PlatformLoad<double>::kMoment;
  f.push_back(Field{moment, "", false, [](double v, std::string* error) {
                      PathStepOptions o;
                      o.load.moment = v;
                      return o.is_valid(error);
                    }});
  f.push_back(Field{moment, "", false, [](double v, std::string* error) {
                      SamplingOptions o;
                      o.load.moment = v;
                      return o.is_valid(error);
                    }});
  f.push_back(Field{moment, "effects.load.", false, [](double v, std::string* error) {
                      VirtualRobotOptions o;
                      o.effects.load.moment = v;
                      return o.is_valid(error);
                    }});
  // The method's paths are nested: named as "square.num_poses".
  f.push_back(Field{SquarePath::kNumPoses, "square.", true, [](double v, std::string* error) {
                      MethodOptions o;
                      o.square.num_poses = static_cast<int>(v);
                      return o.is_valid(error);
                    }});
  f.push_back(Field{CirclePath::kNumPoses, "circle.", true, [](double v, std::string* error) {
                      MethodOptions o;
                      o.circle.num_poses = static_cast<int>(v);
                      return o.is_valid(error);
                    }});
  return f;
}

TEST(Options, DefaultsAreValid) {
  std::string error;
  EXPECT_TRUE(SolverOptions().is_valid(&error)) << error;
  EXPECT_TRUE(PathStepOptions().is_valid(&error)) << error;
  EXPECT_TRUE(AccuracyOptions().is_valid(&error)) << error;
  EXPECT_TRUE(SamplingOptions().is_valid(&error)) << error;
  EXPECT_TRUE(SensitivityOptions().is_valid(&error)) << error;
  EXPECT_TRUE(VirtualRobotOptions().is_valid(&error)) << error;
  EXPECT_TRUE(WorkspaceMapOptions().is_valid(&error)) << error;
  EXPECT_TRUE(CalibrationOptions().is_valid(&error)) << error;
  EXPECT_TRUE(SquarePath().is_valid(&error)) << error;
  EXPECT_TRUE(CirclePath().is_valid(&error)) << error;
  EXPECT_TRUE(PlatformLoad<double>().is_valid(&error)) << error;
  EXPECT_TRUE(MethodOptions().is_valid(&error)) << error;
  EXPECT_TRUE(sampling_solver_options().is_valid(&error)) << error;
  EXPECT_TRUE(calibration_solver_options().is_valid(&error)) << error;
}

TEST(Options, ValuesInsideTheRangeAreAcceptedAndOutsideRefusedByName) {
  std::mt19937_64 rng(29);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (const Field& f : all_fields()) {
    const OptionRange& r = f.range;
    SCOPED_TRACE(f.prefix + r.name);
    std::string error;
    // The bounds themselves, and values drawn inside (log-uniform over a wide positive range).
    std::vector<double> inside = {r.lo, r.hi};
    for (int k = 0; k < 20; ++k) {
      const double u = unit(rng);
      double v = r.lo > 0 && r.hi / r.lo > 1e3 ? r.lo * std::pow(r.hi / r.lo, u)
                                               : r.lo + u * (r.hi - r.lo);
      if (f.integer) v = std::min(r.hi, std::max(r.lo, std::round(v)));
      inside.push_back(v);
    }
    for (double v : inside) EXPECT_TRUE(f.valid_with(v, &error)) << v << ": " << error;
    // Just outside each bound, and the values no range holds.
    const double step = f.integer ? 1.0 : 1e-3 * std::max(std::abs(r.hi - r.lo), 1e-300);
    std::vector<double> outside = {r.lo - step, r.hi + step};
    if (!f.integer) outside.insert(outside.end(), {kNaN, kInf, -kInf});  // no int holds them
    for (double v : outside) {
      error.clear();
      EXPECT_FALSE(f.valid_with(v, &error)) << v;
      EXPECT_EQ(error.rfind(f.prefix + r.name + ": expected ", 0), 0u) << error;
      EXPECT_NE(error.find(", got "), std::string::npos) << error;
    }
  }
}

TEST(Options, TheMessageSaysTheRangeAndTheValue) {
  SamplingOptions o;
  o.strain_limit = 0.5;
  std::string error;
  EXPECT_FALSE(o.is_valid(&error));
  EXPECT_EQ(error, "strain_limit: expected a number from 1e-06 to 0.1, got 0.5");
  SolverOptions s;
  s.min_rod_steps = 64;
  s.max_rod_steps = 32;
  EXPECT_FALSE(s.is_valid(&error));
  EXPECT_EQ(error, "min_rod_steps: 64 is above max_rod_steps 32");
  VirtualRobotOptions v;
  v.solver.tolerance = kNaN;  // a nested solver's field is named as it is
  EXPECT_FALSE(v.is_valid(&error));
  EXPECT_EQ(error, "tolerance: expected a number from 1e-16 to 0.001, got nan");
}

TEST(Options, VectorFieldsAreCheckedComponentByComponent) {
  std::string error;
  SquarePath square;
  square.centre = Vector2<double>(0.0, 0.2);  // 200 mm: a centre in mm typed as m
  EXPECT_FALSE(square.is_valid(&error));
  EXPECT_EQ(error, "centre: expected a number from -0.1 to 0.1 (m), got 0.2");
  CirclePath circle;
  circle.centre = Vector2<double>(kNaN, 0.0);
  EXPECT_FALSE(circle.is_valid(&error));
  EXPECT_EQ(error, "centre: expected a number from -0.1 to 0.1 (m), got nan");
  SamplingOptions sampling;
  sampling.box_min = JointVector::Constant(3, -2e-3);
  sampling.box_max = JointVector::Constant(3, 2e-3);
  EXPECT_TRUE(sampling.is_valid(&error)) << error;
  sampling.box_max(2) = 2.0;
  EXPECT_FALSE(sampling.is_valid(&error));
  EXPECT_EQ(error, "box_max: expected a number from -1 to 1 (m), got 2");
  sampling.box_max(2) = 2e-3;
  sampling.box_min(0) = -kInf;
  EXPECT_FALSE(sampling.is_valid(&error));
  EXPECT_EQ(error, "box_min: expected a number from -1 to 1 (m), got -inf");
  PathStepOptions step;
  step.load.force = Vector2<double>(kNaN, 0.0);
  EXPECT_FALSE(step.is_valid(&error));
  EXPECT_EQ(error, "force: not finite");
  VirtualRobotOptions robot;
  robot.effects.load.force = Vector2<double>(0.0, kInf);
  EXPECT_FALSE(robot.is_valid(&error));
  EXPECT_EQ(error, "effects.load.force: not finite");
}

TEST(Options, TheSolversRefuseInvalidOptions) {
  const RobotParams<double> robot = femto_3pf();
  SolverOptions bad;
  bad.max_iterations = 0;
  JointVector q(3);
  q << 0.001, 0.0, -0.001;
  EXPECT_EQ(home_solution(robot, bad).summary.status, SolveStatus::kInvalidInput);
  EXPECT_EQ(forward_kinematics(robot, q, bad).summary.status, SolveStatus::kInvalidInput);
  const ForwardSolution home = home_solution(robot);
  ASSERT_TRUE(home.summary.converged());
  EXPECT_EQ(forward_kinematics(robot, q, home, bad).summary.status, SolveStatus::kInvalidInput);
  EXPECT_EQ(forward_kinematics_through_folds(robot, q, home, bad).summary.status,
            SolveStatus::kInvalidInput);
  EXPECT_EQ(inverse_kinematics(robot, home.pose, bad).summary.status, SolveStatus::kInvalidInput);
  ForwardSequence rows(robot, bad);
  EXPECT_EQ(rows.solve(q).summary.status, SolveStatus::kInvalidInput);
}

TEST(Options, TheLibraryRefusesWhatIsValidRefuses) {
  const RobotDescription robot = default_robot();
  const auto refused = [](const std::function<void()>& call, const std::string& message) {
    try {
      call();
      ADD_FAILURE() << "accepted; expected: " << message;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << e.what();
    }
  };
  SamplingOptions sampling;
  sampling.strain_limit = 0.0;
  refused([&] { poisson_disc_sample(robot.params, sampling); },
          "poisson_disc_sample: strain_limit: expected a number from 1e-06 to 0.1, got 0");
  refused([&] { sample_configurations(robot, sampling, 0); }, "strain_limit");
  JointVector q(3);
  q.setZero();
  refused([&] { admissible_configuration(robot.params, q, 0.2); }, "strain_limit");
  SensitivityOptions sensitivity;
  sensitivity.step = 0.02;
  refused([&] { sensitivity_analysis(robot, sensitivity); }, "sensitivity: step: expected");
  VirtualRobotOptions virtual_robot;
  virtual_robot.noise_angle = -1.0;
  refused([&] { VirtualRobot v(robot, virtual_robot); }, "noise_angle: expected");
  WorkspaceMapOptions map;
  map.grid = 1;
  refused([&] { workspace_map(robot.params, map); }, "workspace_map: grid: expected");
  CalibrationOptions calibration;
  calibration.robust_scale = kNaN;
  std::vector<CalibrationSample> data(1);
  data[0].q = q;
  refused([&] { calibrate(robot, data, calibration); }, "robust_scale: expected");
  VirtualRobot v(robot);
  AccuracyOptions accuracy;
  accuracy.repeat = 1;
  refused([&] { evaluate_on_virtual_robot(robot.params, v, {Pose2<double>()}, accuracy); },
          "evaluate_on_virtual_robot: repeat: expected a number from 2 to 100000, got 1");
  PathCommandOptions command;
  command.step.solver.rod_steps = -1;
  refused([&] { command_path(robot.params, {Pose2<double>()}, command); },
          "command_path: rod_steps: expected");
  command = PathCommandOptions();
  command.step.load.moment = 2e3;
  refused([&] { command_path(robot.params, {Pose2<double>()}, command); },
          "command_path: moment: expected a number from -1000 to 1000 (N m), got 2000");
  SquarePath square;
  square.side = 1.0;
  refused([&] { square_path(square); },
          "square_path: side: expected a number from 1e-06 to 0.1 (m), got 1");
  CirclePath circle;
  circle.theta = 4.0;
  refused([&] { circle_path(circle); }, "circle_path: theta: expected");
  sampling = SamplingOptions();
  sampling.box_min = JointVector::Constant(3, -2.0);
  sampling.box_max = JointVector::Constant(3, 2e-3);
  refused([&] { poisson_disc_sample(robot.params, sampling); },
          "poisson_disc_sample: box_min: expected a number from -1 to 1 (m), got -2");
  MethodOptions method;
  method.circle.num_poses = 0;
  refused([&] { run_method(robot, v, method); },
          "run_method: circle.num_poses: expected a number from 1 to 100000, got 0");
}

}  // namespace
}  // namespace pcr
