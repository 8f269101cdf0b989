#pragma once
// The parts of choosing calibration configurations that know no robot, shared by the planar
// sampler (pcr/calib/sampling.hpp) and the spatial one (pcr/calib/spatial_sampling.hpp):
// - Poisson-disc sampling (Bridson 2007) of a box in joint space, through an admission test the
//   robot supplies (FK converges, strain, stability), each candidate drawn around an accepted
//   point whose index the test gets, so that it can start FK from that point's solution;
// - the radius chosen from a requested count (a maximal set of radius r holds ~ r^-n points);
// - the greedy D-optimal choice among candidates from their stacked identification rows;
// - the visiting order of a set of configurations.

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <vector>

namespace pcr {

/// D-optimal: eps of the criterion, relative to the whole candidate set's information (see
/// greedy_d_optimal).
inline constexpr double kDesignRegularisation = 1e-6;

/// A box of joint space (m).
struct JointBox {
  Eigen::VectorXd lo, hi;
  int dim() const { return static_cast<int>(lo.size()); }
  bool contains(const Eigen::VectorXd& q) const {
    for (int i = 0; i < dim(); ++i) {
      if (!(q(i) >= lo(i) && q(i) <= hi(i))) return false;
    }
    return true;
  }
  double volume() const {
    double v = 1.0;
    for (int i = 0; i < dim(); ++i) v *= hi(i) - lo(i);
    return v;
  }
};

/// What an admission test saw in one run.
struct AdmissionCounts {
  int candidates = 0;         ///< FK evaluations
  int rejected_fk = 0;        ///< of which FK failed
  int rejected_strain = 0;    ///< of which the strain limit was exceeded
  int rejected_unstable = 0;  ///< of which the equilibrium was unstable (spatial sampler)
};

/// Whether q is admissible (and the test keeps what it needs of it when it is). `from`: the index,
/// among the run's accepted points in their order, of the point q was drawn around; -1 for a seed
/// drawn uniformly in the box, which only happens before a run's first acceptance (a test keeping
/// solutions starts afresh there). Counts what it rejects in *counts.
using AdmissionTest =
    std::function<bool(const Eigen::VectorXd& q, int from, AdmissionCounts* counts)>;

/// One run of Bridson's algorithm with radius r (m) and `attempts` candidates per active point:
/// a maximal set of admissible points at least r apart (Euclidean), in a seeded shuffled order (any
/// prefix is spread over the whole region). Up to 1000 uniform seeds are tried for the first point.
std::vector<Eigen::VectorXd> poisson_disc_run(const JointBox& box, double r, std::uint64_t seed,
                                              int attempts, const AdmissionTest& admit,
                                              AdmissionCounts* counts);

struct PoissonDiscDraw {
  std::vector<Eigen::VectorXd> points;  ///< shuffled; empty when no run held `count`
  double radius = 0;                    ///< m
  AdmissionCounts counts;               ///< of the run kept
};

/// `count` or more points: one run at min_distance when > 0 (possibly fewer points); else the
/// radius from the count: it starts from the box volume (a maximal set of radius r holds about
/// 0.7 V / r^n points in 3-D; the unreachable part of the box makes it fewer) and each run corrects
/// it with the measured count (N ~ r^-n), up to 8 runs, keeping the first set of `count` to 1.6
/// `count` points (else the largest radius that gave `count`).
PoissonDiscDraw poisson_disc_draw(const JointBox& box, int count, double min_distance,
                                  std::uint64_t seed, int attempts, const AdmissionTest& admit);

/// The greedy D-optimal choice of `count` candidates, each `rows_per_candidate` consecutive rows
/// of `stacked` (whitened identification rows, columns in half-width units), maximising
///   log det(F_S + eps F_C)   on the identifiable subspace,
/// F_S the chosen candidates' information sum J_j^T J_j, F_C all the candidates' and
/// eps = kDesignRegularisation. The identifiable subspace is the span of the right singular
/// vectors of `stacked` above kRankThreshold of the largest: the gauge directions and any other
/// combination no candidate sees drop out. eps F_C makes the criterion finite while fewer
/// candidates than the dimension needs are chosen, so the first picks open as many directions as
/// they can; with 30 of 300 candidates chosen it weighs ~1e-5 of F_S. In coordinates of the
/// subspace where F_C = I, with U_j the rows of candidate j and A = eps I + F_S, each step adds the
/// candidate with the largest gain log det(I + U_j A^-1 U_j^T) (matrix determinant lemma) and
/// updates A^-1 by the Woodbury identity. Ties go to the lower index: deterministic.
struct GreedyDesign {
  std::vector<int> selected;  ///< candidate indices, in the order chosen
  int dimension = 0;          ///< of the identifiable subspace
  int rank = 0;               ///< of the chosen set on it (= dimension: all identified)
  /// log det of the chosen rows' information on the subspace (orthonormal basis), computed
  /// afresh from them.
  double log_det = 0;
};
GreedyDesign greedy_d_optimal(const Eigen::MatrixXd& stacked, int rows_per_candidate, int count);

/// The order an experiment visits `configurations` in: a greedy nearest-neighbour tour (joint
/// space, Euclidean) from the one nearest home. Every FK then starts next to the last solution:
/// in the sampler's shuffled order, warm starts across the stroke box do about 5 times the work.
/// Vector: any Eigen column vector (JointVector, SpatialJointVector).
template <class Vector>
std::vector<std::size_t> visiting_order(const std::vector<Vector>& configurations) {
  std::vector<std::size_t> left(configurations.size()), order;
  for (std::size_t k = 0; k < left.size(); ++k) left[k] = k;
  const auto take_nearest = [&](const Vector& from) {
    std::size_t best = 0;
    for (std::size_t k = 1; k < left.size(); ++k) {
      if ((configurations[left[k]] - from).squaredNorm() <
          (configurations[left[best]] - from).squaredNorm()) {
        best = k;
      }
    }
    order.push_back(left[best]);
    left.erase(left.begin() + static_cast<std::ptrdiff_t>(best));
  };
  if (!left.empty()) take_nearest(Vector::Zero(configurations[left[0]].size()));
  while (!left.empty()) take_nearest(configurations[order.back()]);
  return order;
}

}  // namespace pcr
