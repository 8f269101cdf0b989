#include "pcr/calib/experiment_design.hpp"

#include <Eigen/Cholesky>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <random>

#include "pcr/calib/calibrator.hpp"  // kRankThreshold

namespace pcr {

std::vector<Eigen::VectorXd> poisson_disc_run(const JointBox& box, double r, std::uint64_t seed,
                                              int attempts, const AdmissionTest& admit,
                                              AdmissionCounts* counts) {
  std::seed_seq seq{seed, std::uint64_t{0x706f6973736f6e}};
  std::mt19937_64 rng(seq);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::normal_distribution<double> gauss(0.0, 1.0);
  const int n = box.dim();
  *counts = AdmissionCounts();

  std::vector<Eigen::VectorXd> points;
  std::vector<std::size_t> active;
  // Seed point: uniform in the box until one is admissible.
  const int max_seed_tries = 1000;
  for (int t = 0; t < max_seed_tries && points.empty(); ++t) {
    Eigen::VectorXd q(n);
    for (int i = 0; i < n; ++i) q(i) = box.lo(i) + (box.hi(i) - box.lo(i)) * unit(rng);
    if (admit(q, -1, counts)) {
      points.push_back(q);
      active.push_back(0);
    }
  }
  const double shell = std::pow(2.0, n) - 1.0;
  while (!active.empty()) {
    const std::size_t pick = static_cast<std::size_t>(unit(rng) * active.size()) % active.size();
    const std::size_t from = active[pick];
    bool found = false;
    for (int k = 0; k < attempts; ++k) {
      // Uniform in the spherical shell r <= |d| <= 2r.
      Eigen::VectorXd d(n);
      for (int i = 0; i < n; ++i) d(i) = gauss(rng);
      const double norm = d.norm();
      if (!(norm > 0)) continue;
      const double radius = r * std::pow(1.0 + shell * unit(rng), 1.0 / n);
      const Eigen::VectorXd q = points[from] + d * (radius / norm);
      if (!box.contains(q)) continue;
      bool far = true;
      for (const Eigen::VectorXd& p : points) {
        if ((p - q).squaredNorm() < r * r) {
          far = false;
          break;
        }
      }
      if (!far || !admit(q, static_cast<int>(from), counts)) continue;
      points.push_back(q);
      active.push_back(points.size() - 1);
      found = true;
      break;
    }
    if (!found) {
      active[pick] = active.back();
      active.pop_back();
    }
  }
  // Seeded shuffle, so any prefix is spread over the whole region.
  std::shuffle(points.begin(), points.end(), rng);
  return points;
}

PoissonDiscDraw poisson_disc_draw(const JointBox& box, int count, double min_distance,
                                  std::uint64_t seed, int attempts, const AdmissionTest& admit) {
  PoissonDiscDraw draw;
  if (min_distance > 0) {
    draw.radius = min_distance;
    draw.points = poisson_disc_run(box, min_distance, seed, attempts, admit, &draw.counts);
    return draw;
  }
  // Each run costs thousands of FK solves: accept the first set holding `count` to 1.6 `count`.
  const int n = box.dim();
  const double target = count * 1.2 + 1.0;
  double r = std::pow(0.5 * box.volume() / target, 1.0 / n);
  for (int iteration = 0; iteration < 8; ++iteration) {
    AdmissionCounts counts;
    std::vector<Eigen::VectorXd> set = poisson_disc_run(box, r, seed, attempts, admit, &counts);
    const double size = static_cast<double>(set.size());
    if (static_cast<int>(set.size()) >= count && r > draw.radius) {
      draw.radius = r;
      draw.points = std::move(set);
      draw.counts = counts;
      if (size <= 1.6 * count) break;
    }
    const double ratio = std::max(size, 1.0) / target;
    r *= std::clamp(std::pow(ratio, 1.0 / n), 0.5, 2.0);
  }
  return draw;
}

GreedyDesign greedy_d_optimal(const Eigen::MatrixXd& stacked, int rows_per_candidate, int count) {
  const Eigen::Index m = rows_per_candidate;
  const std::size_t candidates = static_cast<std::size_t>(stacked.rows() / m);
  GreedyDesign result;

  // Identifiable subspace, in coordinates where the candidates' information is the identity:
  // T = V_r S_r^-1, rows U_j = J_j T.
  const Eigen::BDCSVD<Eigen::MatrixXd> svd(stacked, Eigen::ComputeThinV);
  const Eigen::VectorXd& sv = svd.singularValues();
  const double smax = sv.size() > 0 ? sv(0) : 0.0;
  Eigen::Index r = 0;
  while (r < sv.size() && smax > 0 && sv(r) > kRankThreshold * smax) ++r;
  result.dimension = static_cast<int>(r);
  const Eigen::MatrixXd basis = svd.matrixV().leftCols(r);
  const Eigen::MatrixXd U = stacked * basis * sv.head(r).cwiseInverse().asDiagonal();

  // Greedy choice: A = eps I + sum of the chosen U_j^T U_j, A^-1 kept up to date.
  Eigen::MatrixXd A_inv = Eigen::MatrixXd::Identity(r, r) / kDesignRegularisation;
  const Eigen::MatrixXd I = Eigen::MatrixXd::Identity(m, m);
  std::vector<bool> chosen(candidates, false);
  for (int step = 0; step < count; ++step) {
    double best_gain = -INFINITY;
    std::size_t best = candidates;
    for (std::size_t j = 0; j < candidates; ++j) {
      if (chosen[j]) continue;
      const auto Uj = U.middleRows(m * static_cast<Eigen::Index>(j), m);
      const Eigen::MatrixXd G = I + Uj * A_inv * Uj.transpose();
      const Eigen::LLT<Eigen::MatrixXd> llt(G);
      if (llt.info() != Eigen::Success) continue;
      const double gain = 2.0 * llt.matrixLLT().diagonal().array().log().sum();
      if (gain > best_gain) {
        best_gain = gain;
        best = j;
      }
    }
    if (best == candidates) break;  // no candidate left with a finite gain
    chosen[best] = true;
    result.selected.push_back(static_cast<int>(best));
    const auto Ub = U.middleRows(m * static_cast<Eigen::Index>(best), m);
    const Eigen::MatrixXd W = Ub * A_inv;  // m x r
    const Eigen::MatrixXd G = I + W * Ub.transpose();
    A_inv -= W.transpose() * G.ldlt().solve(W);
    A_inv = 0.5 * (A_inv + A_inv.transpose()).eval();
  }

  // The chosen set's criterion afresh, in an orthonormal basis of the subspace.
  Eigen::MatrixXd rows(m * static_cast<Eigen::Index>(result.selected.size()), r);
  for (std::size_t j = 0, k = 0; j < candidates; ++j) {
    if (!chosen[j]) continue;
    rows.middleRows(m * static_cast<Eigen::Index>(k++), m) =
        stacked.middleRows(m * static_cast<Eigen::Index>(j), m) * basis;
  }
  const Eigen::VectorXd chosen_sv = Eigen::BDCSVD<Eigen::MatrixXd>(rows).singularValues();
  for (Eigen::Index k = 0; k < r; ++k) {
    const double s = k < chosen_sv.size() ? chosen_sv(k) : 0.0;
    if (chosen_sv.size() > 0 && s > kRankThreshold * chosen_sv(0)) ++result.rank;
    result.log_det += 2.0 * std::log(s);
  }
  return result;
}

}  // namespace pcr
