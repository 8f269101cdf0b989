#pragma once
// Where the robot can work: maps of reachability, elastic stability (pcr/stability.hpp),
// singularity and predicted accuracy over a grid of platform positions at a fixed orientation,
// the constant-orientation workspace's area, and the rotation range at a position.

#include <array>
#include <functional>
#include <iosfwd>
#include <limits>
#include <optional>
#include <vector>

#include "pcr/calib/predicted_accuracy.hpp"
#include "pcr/kinematics.hpp"

namespace pcr {

/// One grid point of a map. NaN fields where the value does not apply.
struct WorkspaceMapPoint {
  double x = 0, y = 0;  ///< platform position (m)
  /// IK was run here: false where the flood from the seeds never came (see workspace_map), a
  /// point that lies beyond the border of the equilibria found (reachable and stable false,
  /// status meaningless).
  bool visited = false;
  /// IK found an equilibrium at this pose with its joints inside the stroke.
  bool reachable = false;
  /// That equilibrium (or, outside the stroke, the one IK found) holds with the joints held.
  bool stable = false;
  SolveStatus status = SolveStatus::kMaxIterations;
  JointVector q;  ///< joints of the equilibrium (m), NaN when IK found none
  double max_strain = std::numeric_limits<double>::quiet_NaN();
  double stability_margin = std::numeric_limits<double>::quiet_NaN();
  double singularity = std::numeric_limits<double>::quiet_NaN();
  /// Predicted errors from the calibration's covariance (3 sigma) and the worst case over the
  /// uncertainty intervals (m, rad); NaN unless WorkspaceMapOptions::accuracy fills them.
  double position_3sigma = std::numeric_limits<double>::quiet_NaN();
  double orientation_3sigma = std::numeric_limits<double>::quiet_NaN();
  double worst_position = std::numeric_limits<double>::quiet_NaN();
  double worst_orientation = std::numeric_limits<double>::quiet_NaN();
};

struct WorkspaceMapOptions {
  double theta = 0;  ///< platform orientation of the map (rad)
  int grid = 200;    ///< points per side (>= 2)
  /// x_min, x_max, y_min, y_max (m); default: stroke_pose_box, with a margin of a tenth.
  std::optional<std::array<double, 4>> range;
  SolverOptions solver;
  PlatformLoad<double> load;
  /// Fills the accuracy fields of a point from its equilibrium (for example from a calibration's
  /// covariance); called on every point where IK found an equilibrium.
  /// Called from the map's threads, concurrently, each call for its own point.
  std::function<void(const InverseSolution&, WorkspaceMapPoint&)> accuracy;
  /// Threads that solve the map (0: std::thread::hardware_concurrency()); the map is the same
  /// whatever their number.
  int threads = 0;

  static constexpr OptionRange kTheta{"theta", -2 * M_PI, 2 * M_PI, "rad"};
  /// 4000 x 4000 points is 16 million IK solves, minutes of work: beyond, a typo.
  static constexpr OptionRange kGrid{"grid", 2, 4000};
  static constexpr OptionRange kThreads{"threads", 0, 1024};
  /// As SolverOptions::is_valid, for these fields, the solver's and the load's (the range, given
  /// or from the strokes, is checked by workspace_map).
  bool is_valid(std::string* error = nullptr) const {
    return kTheta.check(theta, error) && kGrid.check(grid, error) &&
           kThreads.check(threads, error) && solver.is_valid(error) && load.is_valid(error);
  }
};

struct WorkspaceMap {
  double theta = 0;
  int nx = 0, ny = 0;
  double x_min = 0, x_max = 0, y_min = 0, y_max = 0;
  std::vector<WorkspaceMapPoint> points;  ///< row by row: point (i, j) at j * nx + i, y_j rising
  double reachable_area = 0;              ///< m^2: the reachable points times a cell's area
  double stable_area = 0;                 ///< m^2: the points reachable and stable
  double seconds = 0;                     ///< wall time of the solves
  double cell_area() const { return (x_max - x_min) / (nx - 1) * (y_max - y_min) / (ny - 1); }
  double x(int i) const { return x_min + (x_max - x_min) * i / (nx - 1); }  ///< of column i (m)
  double y(int j) const { return y_min + (y_max - y_min) * j / (ny - 1); }  ///< of row j (m)
};

/// The bounding box x_min, x_max, y_min, y_max (m) of the platform positions of an FK scan of the
/// stroke box (`levels` values per joint, 2 to 1000), over every orientation the scan reaches; each
/// configuration solved as from home (SequenceMode::kIndependent), on `threads` threads (0: one per
/// core).
std::array<double, 4> stroke_pose_box(const RobotParams<double>& robot, int levels = 7,
                                      const SolverOptions& options = SolverOptions(),
                                      const PlatformLoad<double>& load = PlatformLoad<double>(),
                                      int threads = 0);

/// A WorkspaceMapOptions::accuracy that fills each point's predicted errors (predicted_accuracy at
/// its equilibrium): 3 sigma when the covariance names parameters, the worst case when
/// options.half_widths are given.
std::function<void(const InverseSolution&, WorkspaceMapPoint&)> predicted_accuracy_of_points(
    const RobotParams<double>& robot, ParameterCovariance covariance,
    PredictedAccuracyOptions options);

/// IK over the grid, flooded outward from seeds: each point warm-started from a neighbour (of its
/// four) solved in the wave before, from a second one when that fails; the points of a wave in
/// parallel. Seeds are solved cold (inverse_kinematics from home): first the grid point nearest
/// home's position, then the points of a kSeedLattice x kSeedLattice lattice over the grid that
/// the flood left unvisited (regions of equilibria cut off from the first at this orientation).
///
/// Each point gets the equilibrium of the branch the flood follows (within the stroke or not, as
/// the flood goes on through both); where that one is unstable the point is marked so, even where
/// a stable equilibrium of another branch exists (SolverOptions::stable_inverse is not used: as
/// rotation_range, the map follows its branch). A neighbour's solve has a small budget (8
/// iterations, 4 line-search halvings, continuation down to a sixteenth of the cell): a warm start
/// a cell away converges in a few iterations unless a fold lies between. So a point beyond the
/// branch's border costs a few failed short solves, and a point no solved neighbour or seed leads
/// to costs nothing: it stays unvisited (WorkspaceMapPoint::visited), unreachable. The border is
/// located to about a cell; a region of equilibria smaller than the lattice's spacing, cut off from
/// the others, may be missed. The result does not depend on the number of threads.
///
/// Robots with 2 or 3 limbs (IK is square); throws std::invalid_argument otherwise, or on a grid
/// below 2 or an empty range.
inline constexpr int kSeedLattice = 9;
WorkspaceMap workspace_map(const RobotParams<double>& robot, const WorkspaceMapOptions& options);

/// The interval of orientations reachable (an equilibrium within the stroke, and stable) at the
/// position (x, y), found by warm-started IK in steps of `step` from `theta` both ways, each end
/// refined by bisection to `tolerance` (rad). reachable is false when theta itself is not.
struct RotationRange {
  bool reachable = false;
  double theta_min = std::numeric_limits<double>::quiet_NaN();
  double theta_max = std::numeric_limits<double>::quiet_NaN();
};
RotationRange rotation_range(const RobotParams<double>& robot, double x, double y, double theta = 0,
                             const SolverOptions& options = SolverOptions(),
                             const PlatformLoad<double>& load = PlatformLoad<double>(),
                             double step = 0.01, double tolerance = 1e-5);

/// The map as CSV: x, y, theta, reachable, stable, status, q1..qn, max_strain, stability_margin,
/// singularity, position_3sigma, orientation_3sigma, worst_position, worst_orientation.
void write_workspace_map_csv(const WorkspaceMap& map, int num_limbs, std::ostream& out);

}  // namespace pcr
