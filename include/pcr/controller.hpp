#pragma once
// A fixed-rate Cartesian controller (Mauze et al. 2021, Fig. 10): at every tick the desired pose
// of a periodic path goes through warm-started inverse kinematics and the joints are sent on.
//
// Real-time safe: no heap, no exceptions (every member is noexcept), bounded work per tick (the
// solver's iteration budgets). When a tick fails, the joints of the last good tick are held and
// the warm start is kept, so the loop recovers as soon as the path is reachable again.

#include "pcr/trajectory.hpp"

namespace pcr {

/// What one tick produced.
struct ControllerTick {
  double time = 0.0;      ///< s
  Pose2<double> desired;  ///< the path's pose at `time`
  JointVector q;          ///< joints to send (m): solved, or held on failure (zero before any)
  PathPoseStatus status = PathPoseStatus::kNoSolution;
  int iterations = 0;  ///< Newton iterations spent this tick
  bool ok() const noexcept { return status == PathPoseStatus::kOk; }
};

/// Follows `Path` (anything with `Pose2<double> at(double fraction) const noexcept`, such as
/// SquarePath and CirclePath) once every `period_s` seconds.
template <class Path>
class PathFollower {
 public:
  PathFollower(const RobotParams<double>& robot, const Path& path, double period_s,
               const PathStepOptions& options = PathStepOptions()) noexcept
      : robot_(robot), path_(path), period_(period_s), options_(options) {
    reset();
  }

  /// Solves the path's start from home (a cold start). False when it is not reachable; step()
  /// then cold-starts every tick until a pose is reached.
  bool reset() noexcept {
    const PathStep start = path_ik_start(robot_, path_.at(0.0), options_);
    ready_ = start.ok();
    if (ready_) last_ = start.solution;
    return ready_;
  }

  /// The desired pose at time t (s).
  Pose2<double> desired(double t) const noexcept { return path_.at(t / period_); }

  /// One control tick at time t (s).
  ControllerTick step(double t) noexcept {
    ControllerTick tick;
    tick.time = t;
    tick.desired = desired(t);
    // Before the first good tick there is no warm start: a cold start from home.
    const PathStep step = ready_ ? path_ik_step(robot_, tick.desired, last_, options_)
                                 : path_ik_start(robot_, tick.desired, options_);
    if (!ready_ && !step.ok()) {
      tick.status = step.status;
      tick.iterations = step.iterations;
      tick.q = JointVector::Zero(robot_.num_limbs);
      return tick;
    }
    ready_ = true;
    tick.status = step.status;
    tick.iterations = step.iterations;
    if (step.ok()) last_ = step.solution;
    tick.q = last_.q;
    return tick;
  }

  /// The last good solution (its q are what the actuators hold).
  const InverseSolution& last_solution() const noexcept { return last_; }
  bool ready() const noexcept { return ready_; }
  const RobotParams<double>& robot() const noexcept { return robot_; }
  const Path& path() const noexcept { return path_; }
  double period() const noexcept { return period_; }

 private:
  RobotParams<double> robot_;
  Path path_;
  double period_;
  PathStepOptions options_;
  InverseSolution last_;
  bool ready_ = false;
};

}  // namespace pcr
