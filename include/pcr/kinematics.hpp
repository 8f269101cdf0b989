#pragma once
// Forward and inverse kinematics by Newton shooting (Mauze et al. 2021, Section 2.2).
//
// Real-time safe: no heap allocation, no exceptions, a bounded number of iterations. Numerical
// outcomes are reported in a SolverSummary (pcr/solver.hpp), never thrown.
//
//   FK: unknowns = proximal wrenches (3n) + platform pose (3), inputs = joints q (n).
//   IK: unknowns = proximal wrenches (3n) + joints (n) [+ theta when n = 2], inputs = pose.
// IK is square for n = 3 (full pose) and for n = 2 (x, y imposed, theta free); other n are refused.
//
// This header is the API. The machinery lives in pcr/internal/: the shooting problem
// (shooting_problem.hpp), a Newton solver generic over a problem (newton.hpp), continuation, the
// step-count refinement and the home homotopies (path.hpp), and the bodies of the functions
// declared here (kinematics_impl.hpp).

#include <array>

#include "pcr/internal/newton.hpp"
#include "pcr/internal/solver_linkage.hpp"
#include "pcr/robot.hpp"
#include "pcr/shooting.hpp"
#include "pcr/solver.hpp"

namespace pcr {

namespace internal {
struct WarmStartAccess;
}

/// What a solve leaves for the next one warm-started from it: the solver's chord matrix at the
/// end of the solve (the last Jacobian it evaluated, with the secant corrections of the chord
/// steps since), opaque. A warm start from a solution that holds one predicts its first point
/// along the tangent and takes its first, chord, steps with it instead of evaluating a new
/// Jacobian; an empty one (cleared: the solution was moved to another point) makes the next solve
/// evaluate its own.
class WarmStartJacobian {
 public:
  bool empty() const { return chord_.rows() == 0; }
  void clear() { chord_ = internal::ChordMatrix(); }

 private:
  friend struct internal::WarmStartAccess;
  internal::ChordMatrix chord_;
};

namespace internal {
/// The solvers' access to a WarmStartJacobian's chord matrix.
struct WarmStartAccess {
  static ChordMatrix& chord(WarmStartJacobian& w) { return w.chord_; }
  static const ChordMatrix& chord(const WarmStartJacobian& w) { return w.chord_; }
};
}  // namespace internal

struct ForwardSolution {
  /// The joints of the returned configuration (m): the requested ones when converged; on a
  /// failure, those of the last point solved on the way (summary.path_fraction says where).
  JointVector q;
  Pose2<double> pose;                                ///< platform pose ^W T_P
  std::array<Wrench<double>, kMaxLimbs> wrenches{};  ///< proximal wrench (n, m)(0) of each rod
  SolverSummary summary;
  /// For a warm start from this solution (see WarmStartJacobian).
  WarmStartJacobian jacobian;
};

struct InverseSolution {
  /// The pose of the returned configuration: the requested one when converged (theta solved for
  /// when n = 2); on a failure, that of the last point solved on the way.
  Pose2<double> pose;
  JointVector q;                                     ///< joint values (m)
  std::array<Wrench<double>, kMaxLimbs> wrenches{};  ///< proximal wrench (n, m)(0) of each rod
  SolverSummary summary;
  /// As ForwardSolution::jacobian, for the inverse problem.
  WarmStartJacobian jacobian;
};

/// Forward kinematics warm-started from a previous solution (the normal case in a control loop).
PCR_SOLVER_INLINE ForwardSolution forward_kinematics(
    const RobotParams<double>& robot, const JointVector& q, const ForwardSolution& warm_start,
    const SolverOptions& options = SolverOptions(),
    const PlatformLoad<double>& load = PlatformLoad<double>());

/// The home solution, q = 0: from the straight, unloaded guess, or for a robot whose straight
/// guess fails (a pre-stressed robot with n >= 4 limbs) from a bowed variant of the robot (see
/// docs/kinematics.md, "Accuracy and branches").
PCR_SOLVER_INLINE ForwardSolution
home_solution(const RobotParams<double>& robot, const SolverOptions& options = SolverOptions(),
              const PlatformLoad<double>& load = PlatformLoad<double>());

/// `robot` saying which of its homes it is in (LimbParams::home_bow), from its home pose
/// `measured` (^W T_P at q = 0): of the homes the robot reaches saying nothing and saying each
/// pattern of sides (2^n of them for n >= 4; a pre-stressed robot has several homes), the one
/// whose pose lies nearest, in pose_distance with weight l_mean (1 nm ties keep the earlier: a
/// robot in the home it reaches unsaid comes back as it is). The home solve of `out` reaches that
/// home. False when no home solves.
PCR_SOLVER_INLINE bool choose_home(const RobotParams<double>& robot, const Pose2<double>& measured,
                                   RobotParams<double>& out,
                                   const SolverOptions& options = SolverOptions(),
                                   const PlatformLoad<double>& load = PlatformLoad<double>());

/// Forward kinematics from a cold start: the home solution, then forward_kinematics_from_home.
PCR_SOLVER_INLINE ForwardSolution
forward_kinematics(const RobotParams<double>& robot, const JointVector& q,
                   const SolverOptions& options = SolverOptions(),
                   const PlatformLoad<double>& load = PlatformLoad<double>());

/// Forward kinematics from the home solution (home_solution's, with or without its stability
/// checked), on the branch connected to it: a (continued) path from home to q. When
/// home is a bifurcation (straight rods of a robot with n >= 4 limbs), or with n >= 4 the path
/// from home fails, q is solved directly from a bowed variant of the robot instead: the branch
/// whose rods bow to their left, else the one where they bow to their right (then the same with
/// twice and with half the bow). A home that did not converge is returned as it is. The summary
/// does not count the home solve's iterations.
PCR_SOLVER_INLINE ForwardSolution forward_kinematics_from_home(
    const RobotParams<double>& robot, const JointVector& q, const ForwardSolution& home,
    const SolverOptions& options = SolverOptions(),
    const PlatformLoad<double>& load = PlatformLoad<double>());

/// Inverse kinematics warm-started from a previous solution. For n = 2 only x and y of `pose`
/// are imposed and theta is solved for.
PCR_SOLVER_INLINE InverseSolution inverse_kinematics(
    const RobotParams<double>& robot, const Pose2<double>& pose, const InverseSolution& warm_start,
    const SolverOptions& options = SolverOptions(),
    const PlatformLoad<double>& load = PlatformLoad<double>());

/// Inverse kinematics from a cold start: the home solution, then inverse_kinematics_from_home.
PCR_SOLVER_INLINE InverseSolution
inverse_kinematics(const RobotParams<double>& robot, const Pose2<double>& pose,
                   const SolverOptions& options = SolverOptions(),
                   const PlatformLoad<double>& load = PlatformLoad<double>());

/// Inverse kinematics from the home solution along the straight pose path from home's pose, on
/// the branch connected to home. A home that did not converge is returned as a failed solution.
/// The summary does not count the home solve's iterations.
PCR_SOLVER_INLINE InverseSolution inverse_kinematics_from_home(
    const RobotParams<double>& robot, const Pose2<double>& pose, const ForwardSolution& home,
    const SolverOptions& options = SolverOptions(),
    const PlatformLoad<double>& load = PlatformLoad<double>());

/// Inverse kinematics warm-started from a forward solution (same unknowns, other inputs). The FK
/// Jacobian is left behind: its pose columns are not the IK's joint columns, so the first IK solve
/// evaluates its own.
inline InverseSolution as_inverse_warm_start(const ForwardSolution& fk);

/// The equilibrium an IK solution found (is_equilibrium: its joints may lie outside the stroke, or
/// it may not hold) as a converged forward solution at those joints: for what takes one, such as
/// a forward warm start or pcr::predicted_accuracy. The IK factorisation is left behind.
inline ForwardSolution as_forward_solution(const InverseSolution& ik);

/// Whether every joint of q lies within its actuator's stroke (LimbParams::within_stroke). FK and
/// IK report a converged solution outside it as SolveStatus::kOutOfRange, so every caller (the
/// CLI, Python, the calibration, the sampler) gives the same verdict.
inline bool within_stroke(const RobotParams<double>& robot, const JointVector& q);

/// How many random joint vectors of the stroke box a round trip of FK and IK over it solves (pcr
/// workspace --samples; the library has no such loop): ten million round trips is already a long
/// run, beyond is a typo.
inline constexpr OptionRange kWorkspaceSamplesRange{"samples", 0, 1e7};

/// Seeds of a solution's other equilibria at the same input (joints or pose), per rod.
inline constexpr int kBuckledSeedsPerRod = 4;

/// Seed k (0 <= k < kBuckledSeedsPerRod n) of the other equilibria at `at`'s input: one rod bent
/// further one way or the other, its proximal moment moved by 1 and 2 times 2 pi EI / l (a
/// clamped-clamped rod's buckled shapes); the rods in turn from `first_rod`. A warm solve from it
/// at the same input (forward_kinematics(robot, at.q, seed)) finds the equilibrium it leads to.
template <class Solution>
Solution buckled_seed(const RobotParams<double>& robot, const Solution& at, int k,
                      int first_rod = 0);

/// One input of a sequence (see SequenceSolver): warm-started from `warm` when there is one (may
/// be null), retried from home when that fails (the warm start lies on another branch, or too far
/// along a fold). The summary counts the iterations and residual evaluations of both.
PCR_SOLVER_INLINE ForwardSolution forward_kinematics_or_cold(
    const RobotParams<double>& robot, const JointVector& q, const ForwardSolution* warm,
    const SolverOptions& options = SolverOptions(),
    const PlatformLoad<double>& load = PlatformLoad<double>());

/// IK of one input of a sequence; as forward_kinematics_or_cold.
PCR_SOLVER_INLINE InverseSolution inverse_kinematics_or_cold(
    const RobotParams<double>& robot, const Pose2<double>& pose, const InverseSolution* warm,
    const SolverOptions& options = SolverOptions(),
    const PlatformLoad<double>& load = PlatformLoad<double>());

/// Does nothing with the points of a traced path.
struct NoPathVisitor {
  template <class Solution>
  void operator()(const Solution&) const {}
};

/// Forward kinematics from a warm start along the straight joint path to q by pseudo-arclength
/// continuation: through folds, where the joints' path turns back (the robot snaps through). The
/// solution at q when the curve of solutions comes back to it (after an even number of folds),
/// else the last point traced with status kSingular. summary.folds_passed and first_fold say
/// where it turned. visit(point) sees every point of the curve (path_fraction: where its input
/// lies on the path; its stability checked as SolverOptions::check_stability says).
template <class Visitor = NoPathVisitor>
ForwardSolution forward_kinematics_through_folds(
    const RobotParams<double>& robot, const JointVector& q, const ForwardSolution& warm_start,
    const SolverOptions& options = SolverOptions(),
    const PlatformLoad<double>& load = PlatformLoad<double>(), Visitor&& visit = Visitor());

/// As forward_kinematics_through_folds, for IK along a straight pose path.
template <class Visitor = NoPathVisitor>
InverseSolution inverse_kinematics_through_folds(
    const RobotParams<double>& robot, const Pose2<double>& pose, const InverseSolution& warm_start,
    const SolverOptions& options = SolverOptions(),
    const PlatformLoad<double>& load = PlatformLoad<double>(), Visitor&& visit = Visitor());

/// What the inputs of a sequence are, and so which equilibrium each one gets (a robot may hold
/// several at the same joints or pose).
enum class SequenceMode {
  /// Inputs each on its own, in any order (a set of configurations or poses, a file's rows):
  /// each on the branch connected to home, exactly the cold solve's (forward_kinematics(robot,
  /// q) or inverse_kinematics(robot, pose)), from the home solution the sequence computes once.
  kIndependent,
  /// A path the robot follows in this order (a trajectory, a control loop, an experiment in the
  /// order it was run): each input continued from the last usable solution along the straight
  /// input path, on its branch (the step control of solve_path_at_fixed_steps); where the branch
  /// ends at a fold, followed through it with SolverOptions::through_folds (the robot snaps
  /// through), else solved cold from home.
  kPath,
};

/// What SequenceSolver needs of a kind of solution: the robot, input and load types, what the
/// sequence keeps for its independent inputs (Home, solved once), and the policy's two solves:
///   static Home home(const Robot&, const SolverOptions&, const Load&);
///   /// kIndependent: exactly the cold solve's result, from `home`.
///   static Solution independent(const Robot&, const Input&, const Home&, const SolverOptions&,
///                               const Load&);
///   /// kPath: warm-started from `warm` (null: none), retried cold when that fails.
///   static Solution continued(const Robot&, const Input&, const Solution* warm,
///                             const SolverOptions&, const Load&);
/// Specialised below for the planar solutions, in pcr/spatial/sequence.hpp for the spatial ones.
template <class Solution>
struct SequenceTraits;

template <>
struct SequenceTraits<ForwardSolution> {
  using Robot = RobotParams<double>;
  using Input = JointVector;
  using Load = PlatformLoad<double>;
  using Home = ForwardSolution;
  static Home home(const Robot& robot, const SolverOptions& options, const Load& load);
  static ForwardSolution independent(const Robot& robot, const Input& q, const Home& home,
                                     const SolverOptions& options, const Load& load) {
    return forward_kinematics_from_home(robot, q, home, options, load);
  }
  static ForwardSolution continued(const Robot& robot, const Input& q, const ForwardSolution* warm,
                                   const SolverOptions& options, const Load& load) {
    return forward_kinematics_or_cold(robot, q, warm, options, load);
  }
};

template <>
struct SequenceTraits<InverseSolution> {
  using Robot = RobotParams<double>;
  using Input = Pose2<double>;
  using Load = PlatformLoad<double>;
  using Home = ForwardSolution;
  static Home home(const Robot& robot, const SolverOptions& options, const Load& load) {
    return SequenceTraits<ForwardSolution>::home(robot, options, load);
  }
  static InverseSolution independent(const Robot& robot, const Input& pose, const Home& home,
                                     const SolverOptions& options, const Load& load) {
    return inverse_kinematics_from_home(robot, pose, home, options, load);
  }
  static InverseSolution continued(const Robot& robot, const Input& pose,
                                   const InverseSolution* warm, const SolverOptions& options,
                                   const Load& load) {
    return inverse_kinematics_or_cold(robot, pose, warm, options, load);
  }
};

/// Solves a sequence of FK (ForwardSequence) or IK (InverseSequence) inputs: the rows of a file,
/// a batch, a trajectory, a measurement campaign; the spatial robots' too
/// (SpatialForwardSequence, SpatialInverseSequence in pcr/spatial/sequence.hpp). One policy,
/// everywhere in pcr, chosen by what the inputs are (SequenceMode). In a path, each input is
/// warm-started from the last usable solution (usable_as_warm_start), and a warm solve that fails
/// is retried cold, from home (one that stops at a fold is first followed through it, with
/// SolverOptions::through_folds). A failed input leaves the warm start as it was, so the input
/// after it starts from the last usable solution again. No heap: the solutions live in the
/// solver, which keeps the home solution, the last usable one and the latest one.
template <class Solution>
class SequenceSolver {
 public:
  using Traits = SequenceTraits<Solution>;
  using Robot = typename Traits::Robot;
  /// JointVector for FK, Pose2<double> for IK (the spatial ones: SpatialJointVector,
  /// SpatialPose<double>).
  using Input = typename Traits::Input;
  using Load = typename Traits::Load;

  explicit SequenceSolver(const Robot& robot, const SolverOptions& options = SolverOptions(),
                          const Load& load = Load(), SequenceMode mode = SequenceMode::kIndependent)
      : robot_(robot), options_(options), load_(load), mode_(mode) {}
  /// The default load (a spatial robot carries its load in its parameters).
  SequenceSolver(const Robot& robot, const SolverOptions& options, SequenceMode mode)
      : SequenceSolver(robot, options, Load(), mode) {}

  /// Solves the next input; the reference stays valid until the next call.
  const Solution& solve(const Input& input);

  /// Starts the next input of a path from `warm` (a usable solution), as if it had been the last
  /// one.
  void set_warm_start(const Solution& warm) {
    slots_[last_] = warm;
    has_last_ = true;
  }
  /// The next input starts cold.
  void reset() { has_last_ = false; }
  /// The last usable solution, or null.
  const Solution* last_usable() const { return has_last_ ? &slots_[last_] : nullptr; }

  const Robot& robot() const { return robot_; }
  const SolverOptions& options() const { return options_; }
  const Load& load() const { return load_; }
  SequenceMode mode() const { return mode_; }

 private:
  Robot robot_;
  SolverOptions options_;
  Load load_;
  SequenceMode mode_;
  typename Traits::Home home_;  ///< kIndependent: the home solution, once solved (has_home_)
  bool has_home_ = false;
  Solution slots_[2];  ///< the last usable solution and the latest one
  int last_ = 0;
  bool has_last_ = false;
};

using ForwardSequence = SequenceSolver<ForwardSolution>;
using InverseSequence = SequenceSolver<InverseSolution>;

/// Calls visit(limb, s, RodState) along every rod of a solved configuration (for plots, strain).
template <class Visitor>
void visit_rod_shapes(const RobotParams<double>& robot, const JointVector& q,
                      const std::array<Wrench<double>, kMaxLimbs>& wrenches, int rod_steps,
                      Visitor&& visit);

}  // namespace pcr

#include "pcr/internal/kinematics_impl.hpp"
