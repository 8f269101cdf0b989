#pragma once
// What a kinematics solve reports and the settings it takes (pcr/kinematics.hpp).

#include <cstdio>
#include <limits>
#include <string>

#include "pcr/option_range.hpp"

namespace pcr {

enum class SolveStatus {
  kConverged,      ///< the scaled residual is below the tolerance
  kMaxIterations,  ///< the iteration or continuation budget ran out
  kSingular,       ///< no solution on this branch: the Jacobian became singular along the path
  kBifurcation,    ///< the path starts on, or meets, a bifurcation: solutions exist on other
                   ///< branches (kSingular: a fold, no solution ahead on this branch)
  kNonFinite,      ///< the residual became NaN or infinite
  kOutOfRange,     ///< converged, but a joint value lies outside its stroke (within_stroke):
                   ///< an equilibrium of the model the actuators cannot reach, still given
                   ///< (is_equilibrium) for what needs it (a warm start, a fit of its data)
  kUnstable,       ///< IK converged on an unstable equilibrium, and found no stable one at the
                   ///< pose (SolverOptions::stable_inverse)
  kInaccurate,     ///< converged, but the estimated discretisation error
                   ///< (SolverSummary::position_error_estimate, angle_error_estimate) exceeds
                   ///< position_accuracy or angle_accuracy even at max_rod_steps: near a
                   ///< singularity, where the inputs barely fix the outputs (singularity near 0),
                   ///< or max_rod_steps too low. Still an equilibrium (is_equilibrium), as
                   ///< accurate as its estimate says
  kUnsupported,    ///< the request is not a square problem (IK with n > 3 limbs)
  kInvalidInput,   ///< wrong sizes, NaN inputs, options outside their ranges
                   ///< (SolverOptions::is_valid), or a robot with fewer than 2 / more than
                   ///< kMaxLimbs limbs
};

inline const char* to_string(SolveStatus status) {
  switch (status) {
    case SolveStatus::kConverged:
      return "converged";
    case SolveStatus::kMaxIterations:
      return "max_iterations";
    case SolveStatus::kSingular:
      return "singular";
    case SolveStatus::kBifurcation:
      return "bifurcation";
    case SolveStatus::kNonFinite:
      return "non_finite";
    case SolveStatus::kOutOfRange:
      return "out_of_range";
    case SolveStatus::kUnstable:
      return "unstable";
    case SolveStatus::kInaccurate:
      return "inaccurate";
    case SolveStatus::kUnsupported:
      return "unsupported";
    case SolveStatus::kInvalidInput:
      return "invalid_input";
  }
  return "unknown";
}

/// Elastic stability of a solution's equilibrium with its joints held (pcr/stability.hpp).
enum class Stability {
  kUnchecked,  ///< not checked: SolverOptions::check_stability off, or no converged solution
  kStable,
  kUnstable,
};

struct SolverOptions {
  /// RK4 steps per rod; 0 chooses them from an estimate of the solution's own discretisation
  /// error (RK4 is fourth order: the residual of the N/2-step model at the N-step solution gives
  /// it, through the Jacobian, for the solved outputs themselves), so that the outputs stay within
  /// position_accuracy and angle_accuracy of the exact model's (tests/test_reference.cpp checks
  /// it against CVODE on random robots).
  int rod_steps = 0;
  /// Target of that estimate on the solved lengths (m): FK's platform x, y; IK's joints.
  double position_accuracy = 2.5e-10;
  /// Target of that estimate on the solved angles (rad): FK's theta; IK's theta for n = 2.
  double angle_accuracy = 2.5e-7;
  int min_rod_steps = 16;
  int max_rod_steps = 512;
  /// Newton iterations per solve (each sub-solve of a continuation has its own budget).
  int max_iterations = 20;
  /// Convergence: max-norm of the scaled residual (lengths / L, forces / (EI / L^2)). A run of
  /// chord steps also stops when the next one is predicted to leave an error on the outputs
  /// below chord_output_share of position_accuracy and angle_accuracy (that step is taken, its
  /// residual not evaluated): SolverSummary::final_residual_norm can then be above the tolerance.
  double tolerance = 1e-12;
  /// See tolerance. The default leaves Newton at most 0.025 nm of the 0.25 nm position target,
  /// 2.5 % of the 1 nm promise. 0 runs every solve to the tolerance, which makes the outputs a
  /// smoother function of the robot's parameters: a least-squares fit through FK (the
  /// calibration) takes fewer iterations than with the ~0.02 nm steps left between solves.
  double chord_output_share = 0.1;
  /// Step halvings of the backtracking line search.
  int max_line_search = 12;
  /// When a direct solve fails, step the input from the last solution in smaller increments.
  bool continuation = true;
  /// Sub-solves a continuation may use in total.
  int max_continuation_steps = 64;
  /// Newton iterations per sub-solve of a continuation. From its predictor a sub-solve converges
  /// in a few iterations or crawls along its line search: a shorter step is cheaper than more.
  int max_continuation_iterations = 8;
  /// Smallest continuation increment, as a fraction of the whole path.
  double min_continuation_step = 1.0 / 1024.0;
  /// Check the elastic stability of every converged solution (pcr/stability.hpp, at half its RK4
  /// steps: stability_rod_steps), and measure its distance to a singularity: about the cost of one
  /// residual-plus-Jacobian evaluation (0.8-1 us for 3 limbs), not counted in
  /// SolverSummary::residual_evaluations (the solve's own).
  bool check_stability = true;
  /// When IK converges on an unstable equilibrium, look for a stable one at the same pose
  /// (kUnstable when none is found). Needs check_stability.
  bool stable_inverse = true;
  /// A sequence (SequenceSolver) whose warm solve stops at a fold (or short of it: kSingular or
  /// kMaxIterations) follows the curve of solutions
  /// through it by pseudo-arclength continuation, as the robot snaps through: the input path
  /// turns back at each fold, and the input is reached after an even number of them (else the
  /// cold retry from home follows).
  bool through_folds = false;
  /// Points a pseudo-arclength trace may solve.
  int max_arclength_steps = 400;

  // The documented ranges of the fields (is_valid).
  static constexpr OptionRange kRodSteps{"rod_steps", 0, 100000};  ///< 0: chosen
  static constexpr OptionRange kPositionAccuracy{"position_accuracy", 1e-15, 1e-3, "m"};
  static constexpr OptionRange kAngleAccuracy{"angle_accuracy", 1e-15, 1e-1, "rad"};
  static constexpr OptionRange kMinRodSteps{"min_rod_steps", 1, 100000};
  static constexpr OptionRange kMaxRodSteps{"max_rod_steps", 1, 100000};
  static constexpr OptionRange kMaxIterations{"max_iterations", 1, 10000};
  static constexpr OptionRange kTolerance{"tolerance", 1e-16, 1e-3};
  static constexpr OptionRange kChordOutputShare{"chord_output_share", 0, 1};
  static constexpr OptionRange kMaxLineSearch{"max_line_search", 0, 64};
  static constexpr OptionRange kMaxContinuationSteps{"max_continuation_steps", 1, 100000};
  static constexpr OptionRange kMaxContinuationIterations{"max_continuation_iterations", 1, 10000};
  static constexpr OptionRange kMinContinuationStep{"min_continuation_step", 1e-12, 1};
  static constexpr OptionRange kMaxArclengthSteps{"max_arclength_steps", 1, 1000000};

  /// Whether every field lies in its range (and min_rod_steps <= max_rod_steps); if not, *error
  /// (when given) names the field and its value. No heap unless it writes *error: the solvers
  /// call it and refuse invalid options with SolveStatus::kInvalidInput.
  bool is_valid(std::string* error = nullptr) const {
    if (!(kRodSteps.check(rod_steps, error) && kPositionAccuracy.check(position_accuracy, error) &&
          kAngleAccuracy.check(angle_accuracy, error) && kMinRodSteps.check(min_rod_steps, error) &&
          kMaxRodSteps.check(max_rod_steps, error) && kMaxIterations.check(max_iterations, error) &&
          kTolerance.check(tolerance, error) &&
          kChordOutputShare.check(chord_output_share, error) &&
          kMaxLineSearch.check(max_line_search, error) &&
          kMaxContinuationSteps.check(max_continuation_steps, error) &&
          kMaxContinuationIterations.check(max_continuation_iterations, error) &&
          kMinContinuationStep.check(min_continuation_step, error) &&
          kMaxArclengthSteps.check(max_arclength_steps, error))) {
      return false;
    }
    if (min_rod_steps > max_rod_steps) {
      if (error != nullptr) {
        *error = "min_rod_steps: " + std::to_string(min_rod_steps) + " is above max_rod_steps " +
                 std::to_string(max_rod_steps);
      }
      return false;
    }
    return true;
  }
};

struct SolverSummary {
  SolveStatus status = SolveStatus::kMaxIterations;
  int iterations = 0;            ///< Newton iterations, all sub-solves included
  int residual_evaluations = 0;  ///< residual (+ Jacobian) evaluations
  int continuation_steps = 0;    ///< sub-solves of the continuation; 0 for a direct solve
  double initial_residual_norm = std::numeric_limits<double>::quiet_NaN();  ///< scaled max-norm
  /// Scaled max-norm; after a last chord step taken without evaluating the residual (its
  /// contraction is steady), the value that contraction predicts.
  double final_residual_norm = std::numeric_limits<double>::quiet_NaN();
  double max_strain =
      std::numeric_limits<double>::quiet_NaN();  ///< max |kappa| d / 2 over the rods
  int rod_steps = 0;                             ///< RK4 steps per rod of the returned solution
  /// Estimated discretisation error of the returned outputs against the exact model (NaN when
  /// not estimated: a fixed rod_steps, or no converged solution): lengths (m) and angles (rad).
  double position_error_estimate = std::numeric_limits<double>::quiet_NaN();
  double angle_error_estimate = std::numeric_limits<double>::quiet_NaN();
  /// Where the returned configuration lies on the input path from the warm start (0) to the
  /// requested input (1): 1 when converged; on a failure, the last point solved along the way,
  /// which the solution's q and pose describe.
  double path_fraction = 0.0;
  /// Stability of the returned equilibrium (kUnchecked unless converged, or IK's kOutOfRange or
  /// kUnstable, and SolverOptions::check_stability).
  Stability stability = Stability::kUnchecked;
  /// EquilibriumStability::margin: positive when stable, through zero at a fold (NaN unchecked).
  double stability_margin = std::numeric_limits<double>::quiet_NaN();
  /// EquilibriumStability::singularity: reciprocal condition number of the scaled forward
  /// Jacobian, zero at a fold or a bifurcation (NaN unchecked).
  double singularity = std::numeric_limits<double>::quiet_NaN();
  /// Folds a pseudo-arclength trace passed (SolverOptions::through_folds), and the path fraction
  /// of the first: where the input turned back.
  int folds_passed = 0;
  double first_fold = std::numeric_limits<double>::quiet_NaN();
  bool converged() const { return status == SolveStatus::kConverged; }
};

/// A converged solution whose estimated discretisation error exceeds the accuracy targets (the
/// step-count refinement stopped at max_rod_steps short of them) is kInaccurate: the one rule
/// the planar and spatial solvers apply to what they return. An estimate of NaN (a fixed
/// rod_steps) says nothing and changes nothing.
inline void mark_inaccurate(const SolverOptions& options, SolverSummary& summary) {
  if (summary.converged() && (summary.position_error_estimate > options.position_accuracy ||
                              summary.angle_error_estimate > options.angle_accuracy)) {
    summary.status = SolveStatus::kInaccurate;
  }
}

/// Whether a solution can warm-start the next solve: a converged one, or a valid equilibrium
/// whose joints lie outside their stroke (kOutOfRange) or whose error estimate exceeds the
/// accuracy targets (kInaccurate).
inline bool usable_as_warm_start(const SolverSummary& summary) {
  return summary.converged() || summary.status == SolveStatus::kOutOfRange ||
         summary.status == SolveStatus::kInaccurate;
}

/// Whether a solution is an equilibrium of the robot, within the stroke or not: usable as a warm
/// start, or IK's kUnstable (an equilibrium that would not hold).
inline bool is_equilibrium(const SolverSummary& summary) {
  return usable_as_warm_start(summary) || summary.status == SolveStatus::kUnstable;
}

/// Why a kInaccurate solution is not accurate, in words for an error message.
inline std::string inaccuracy_message(const SolverSummary& summary) {
  char text[240];
  std::snprintf(text, sizeof text,
                "inaccurate: estimated error %.3g m, %.3g rad at %d RK4 steps per rod exceeds the "
                "accuracy targets (singularity measure %.3g: the inputs barely fix the pose here)",
                summary.position_error_estimate, summary.angle_error_estimate, summary.rod_steps,
                summary.singularity);
  return text;
}

}  // namespace pcr
