#pragma once
// The flood that solves a workspace map, planar (pcr/calib/workspace_map.hpp) or spatial
// (pcr/spatial/workspace_map.hpp): IK over a grid of poses, outward from seeds solved cold, each
// point warm-started from a neighbour solved in the wave before; and the parallel loop it runs
// on. Not part of the API: a map says how a point is solved and recorded, this file floods.

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstddef>
#include <exception>
#include <mutex>
#include <optional>
#include <system_error>
#include <thread>
#include <utility>
#include <vector>

#include "pcr/calib/workspace_map.hpp"  // kSeedLattice
#include "pcr/kinematics.hpp"

namespace pcr::map_internal {

/// Runs task(k) for k in [0, count) on up to `threads` threads, the caller's among them, each
/// taking the next k when it is done with one (a failed solve costs a hundred converged ones).
/// Rethrows the first exception a task threw, once every thread has stopped.
template <class Task>
void parallel_for(std::size_t count, int threads, const Task& task) {
  const auto workers = std::min(count, static_cast<std::size_t>(std::max(threads, 1)));
  std::atomic<std::size_t> next{0};
  std::exception_ptr error;
  std::mutex error_mutex;
  const auto work = [&] {
    for (std::size_t k = next++; k < count; k = next++) {
      try {
        task(k);
      } catch (...) {
        const std::lock_guard<std::mutex> lock(error_mutex);
        if (!error) error = std::current_exception();
        next = count;
      }
    }
  };
  std::vector<std::thread> pool;
  for (std::size_t t = 1; t < workers; ++t) {
    try {
      pool.emplace_back(work);
    } catch (const std::system_error&) {
      break;  // no more threads to be had: the ones running take the rest
    }
  }
  work();
  for (std::thread& t : pool) t.join();
  if (error) std::rethrow_exception(error);
}

/// Threads to run on: `threads`, or one per core when 0.
inline int thread_count(int threads) {
  return threads > 0 ? threads : std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
}

/// The solver options of a neighbour's warm solve, from the cold solves' ones. A neighbour lies a
/// cell away: its warm start converges in a few iterations unless a fold lies between, where
/// Newton crawls. There the solve stops early (a point one neighbour does not reach is left to the
/// others): the budget that makes the border cost a few converged solves per point instead of a
/// hundred.
inline SolverOptions neighbour_solver_options(const SolverOptions& cold) {
  SolverOptions o = cold;
  o.max_iterations = std::min(o.max_iterations, 8);
  o.max_line_search = std::min(o.max_line_search, 4);
  o.max_continuation_steps = std::min(o.max_continuation_steps, 16);
  o.min_continuation_step = std::max(o.min_continuation_step, 1.0 / 16);
  return o;
}

/// The index in [0, count) of the grid value nearest v on [lo, hi] (count values).
inline int nearest_grid_index(double v, double lo, double hi, int count) {
  return static_cast<int>(std::clamp(std::lround((v - lo) / (hi - lo) * (count - 1)), 0L,
                                     static_cast<long>(count - 1)));
}

/// Floods IK over an nx x ny grid (point (i, j) at j * nx + i): waves of points, each wave the
/// unvisited neighbours of the points the wave before solved, warm-started from them; the points
/// of a wave in parallel. Seeds are solved cold: first `first` (when given), then the points of
/// the kSeedLattice lattice the flood left unvisited. The result does not depend on the number of
/// threads: a point's warm starts are its neighbours in the wave before, in a fixed order.
///
/// Map: `using Solution` (with a SolverSummary `summary`); `Solution cold(k)`, `Solution
/// warm(k, const Solution&)` (each with its own solver budget: neighbour_solver_options);
/// `void record(k, const Solution&)`, called once per solved point, concurrently for distinct k.
template <class Map>
class GridFlood {
 public:
  using Solution = typename Map::Solution;

  GridFlood(Map& map, int nx, int ny, int threads)
      : map_(map),
        nx_(nx),
        ny_(ny),
        threads_(thread_count(threads)),
        visited_(static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny), 0),
        slot_(visited_.size(), -1) {}

  void run(std::optional<std::size_t> first) {
    if (first) flood(solve_cold({*first}));
    std::vector<std::size_t> lattice;
    const int levels_x = std::min(kSeedLattice, nx_), levels_y = std::min(kSeedLattice, ny_);
    for (int b = 0; b < levels_y; ++b) {
      for (int a = 0; a < levels_x; ++a) {
        const std::size_t k =
            index(static_cast<int>(std::lround(1.0 * a * (nx_ - 1) / (levels_x - 1))),
                  static_cast<int>(std::lround(1.0 * b * (ny_ - 1) / (levels_y - 1))));
        if (!visited_[k]) lattice.push_back(k);
      }
    }
    flood(solve_cold(lattice));
  }

  std::size_t index(int i, int j) const {
    return static_cast<std::size_t>(j) * static_cast<std::size_t>(nx_) +
           static_cast<std::size_t>(i);
  }

 private:
  /// The solved points of a wave and their solutions.
  struct Wave {
    std::vector<std::size_t> points;
    std::vector<Solution> solutions;
  };

  /// The four neighbours of point k in a fixed order (left, right, below, above; the grid's size
  /// where there is none), so that the warm start a point gets does not depend on the threads.
  std::array<std::size_t, 4> neighbours(std::size_t k) const {
    const auto nx = static_cast<std::size_t>(nx_), size = visited_.size();
    const std::size_t i = k % nx;
    return {i > 0 ? k - 1 : size, i + 1 < nx ? k + 1 : size, k >= nx ? k - nx : size,
            k + nx < size ? k + nx : size};
  }

  /// IK from up to two warm starts (null: skipped), cold when there is none. Returns a usable
  /// solution when one of them gives it, else an equilibrium (IK's kUnstable), else the last
  /// failure.
  Solution solve_from_neighbours(std::size_t k, const Solution* first,
                                 const Solution* second) const {
    Solution best;
    bool tried = false, have_equilibrium = false;
    for (const Solution* warm : {first, second}) {
      if (warm == nullptr) continue;
      tried = true;
      Solution s = map_.warm(k, *warm);
      if (usable_as_warm_start(s.summary)) return s;
      if (!have_equilibrium) {
        have_equilibrium = is_equilibrium(s.summary);
        best = std::move(s);
      }
    }
    if (!tried) return map_.cold(k);
    return best;
  }

  /// Marks the points visited, solves them with `solve(k)` in parallel, and returns the wave of
  /// those that can warm-start their neighbours.
  template <class Solve>
  Wave solve_wave(std::vector<std::size_t> points, const Solve& solve) {
    for (std::size_t k : points) visited_[k] = 1;
    std::vector<Solution> solutions(points.size());
    parallel_for(points.size(), threads_, [&](std::size_t w) {
      solutions[w] = solve(points[w]);
      map_.record(points[w], solutions[w]);
    });
    Wave wave;
    for (std::size_t w = 0; w < points.size(); ++w) {
      if (!usable_as_warm_start(solutions[w].summary)) continue;
      wave.points.push_back(points[w]);
      wave.solutions.push_back(std::move(solutions[w]));
    }
    return wave;
  }

  Wave solve_cold(std::vector<std::size_t> points) {
    return solve_wave(std::move(points), [&](std::size_t k) { return map_.cold(k); });
  }

  void flood(Wave wave) {
    const std::size_t none = visited_.size();
    while (!wave.points.empty()) {
      std::vector<std::size_t> next;
      for (std::size_t w = 0; w < wave.points.size(); ++w) {
        slot_[wave.points[w]] = static_cast<std::ptrdiff_t>(w);
        for (std::size_t k : neighbours(wave.points[w])) {
          if (k != none && !visited_[k]) {
            visited_[k] = 1;
            next.push_back(k);
          }
        }
      }
      Wave solved = solve_wave(std::move(next), [&](std::size_t k) {
        std::array<const Solution*, 2> warm{nullptr, nullptr};
        std::size_t found = 0;
        for (std::size_t m : neighbours(k)) {
          if (m != none && slot_[m] >= 0 && found < warm.size()) {
            warm[found++] = &wave.solutions[static_cast<std::size_t>(slot_[m])];
          }
        }
        return solve_from_neighbours(k, warm[0], warm[1]);
      });
      for (std::size_t k : wave.points) slot_[k] = -1;
      wave = std::move(solved);
    }
  }

  Map& map_;
  int nx_, ny_;
  int threads_;
  std::vector<char> visited_;
  std::vector<std::ptrdiff_t> slot_;  ///< a point's place in the current wave, -1 if not in it
};

}  // namespace pcr::map_internal
