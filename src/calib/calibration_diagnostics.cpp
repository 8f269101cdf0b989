// What calibrate() says of its result: outliers, rank, gauge directions, covariance, warnings.

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

#include "calibration_internal.hpp"
#include "identification.hpp"

namespace pcr::calib_internal {

void leave_out_outliers(Identification& id, const std::vector<CalibrationSample>& rows,
                        bool evaluated, Eigen::MatrixXd& J, Eigen::VectorXd& r,
                        CalibrationResult& result) {
  id.update_loss_scale();
  result.outlier_threshold = id.loss_scale();
  if (!evaluated) return;
  const std::vector<std::size_t> in = id.evaluated_rows();
  calib_internal::leave_out_outliers(
      id.loss_scale(), 3, [&](std::size_t b) { return origin_of(rows, in[b]); }, J, r,
      result.outliers, result.warnings);
}

void rank_and_gauge_directions(const Identification& id, const std::vector<int>& free,
                               const std::vector<bool>& present, const std::vector<bool>& movable,
                               const Eigen::MatrixXd& J, const Eigen::VectorXd& r,
                               CalibrationResult& result) {
  Eigen::MatrixXd Js(J.rows(), static_cast<Eigen::Index>(free.size()));
  for (std::size_t c = 0; c < free.size(); ++c) {
    Js.col(static_cast<Eigen::Index>(c)) =
        J.col(free[c]) * id.half_widths()[static_cast<std::size_t>(free[c])];
  }
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(Js);
  const Eigen::VectorXd sv = svd.singularValues();
  const double smax = sv.size() > 0 ? sv(0) : 0.0;
  for (Eigen::Index k = 0; k < sv.size(); ++k) {
    result.singular_values.push_back(smax > 0 ? sv(k) / smax : 0.0);
    if (smax > 0 && sv(k) > kRankThreshold * smax) ++result.jacobian_rank;
  }
  const std::vector<GaugeGenerator> final_generators = id.generators();
  for (std::size_t g = 0; g < final_generators.size(); ++g) {
    GaugeDirection d;
    d.name = final_generators[g].name;
    d.combination = final_generators[g].combination;
    d.present = present[g];
    d.free = movable[g];
    Eigen::VectorXd scaled(static_cast<Eigen::Index>(free.size()));
    for (std::size_t c = 0; c < free.size(); ++c) {
      const std::size_t k = static_cast<std::size_t>(free[c]);
      scaled(static_cast<Eigen::Index>(c)) = final_generators[g].direction[k] / id.half_widths()[k];
    }
    d.relative_gain = (d.free && smax > 0 && scaled.norm() > 0)
                          ? (Js * scaled).norm() / (smax * scaled.norm())
                          : kNaN;
    result.gauge.push_back(d);
  }
  const double m = static_cast<double>(r.size());
  const double dof = m - static_cast<double>(result.jacobian_rank);
  result.residual_variance = dof > 0 ? r.squaredNorm() / dof : kNaN;
}

void standard_deviations(const Identification& id, const CalibrationOptions& options, int block,
                         const std::vector<int>& free, const std::vector<int>& held, bool evaluated,
                         const Eigen::MatrixXd& J, CalibrationResult& result) {
  for (int k : held) result.parameters[static_cast<std::size_t>(k)].gauge_reference = true;
  std::vector<int> estimated;
  for (int k : free) {
    if (!result.parameters[static_cast<std::size_t>(k)].gauge_reference) estimated.push_back(k);
  }
  if (options.compute_covariance) result.covariance = Eigen::MatrixXd::Zero(block, block);
  if (options.compute_covariance && evaluated && !estimated.empty() &&
      std::isfinite(result.residual_variance)) {
    const Eigen::Index p = static_cast<Eigen::Index>(estimated.size());
    Eigen::MatrixXd Je(J.rows(), p);
    for (Eigen::Index c = 0; c < p; ++c) {
      const std::size_t k = static_cast<std::size_t>(estimated[static_cast<std::size_t>(c)]);
      Je.col(c) = J.col(static_cast<Eigen::Index>(k)) * id.half_widths()[k];
    }
    const Eigen::JacobiSVD<Eigen::MatrixXd> svd(Je, Eigen::ComputeFullV);
    const Eigen::VectorXd sv = svd.singularValues();  // min(rows, p) of them; the rest are 0
    const Eigen::MatrixXd& V = svd.matrixV();         // p x p
    const double smax = sv.size() > 0 ? sv(0) : 0.0;
    result.covariance_ok = smax > 0;
    Eigen::VectorXd inverse_squares = Eigen::VectorXd::Zero(p);
    std::vector<bool> identifiable(static_cast<std::size_t>(p), true);
    for (Eigen::Index d = 0; d < p; ++d) {
      if (d < sv.size() && sv(d) > kRankThreshold * smax) {
        inverse_squares(d) = 1.0 / (sv(d) * sv(d));
        continue;
      }
      std::vector<std::pair<double, Eigen::Index>> terms;
      for (Eigen::Index c = 0; c < p; ++c) {
        if (std::abs(V(c, d)) >= 0.1) {
          terms.emplace_back(V(c, d), c);
          identifiable[static_cast<std::size_t>(c)] = false;
        }
      }
      std::sort(terms.begin(), terms.end(),
                [](const auto& a, const auto& b) { return std::abs(a.first) > std::abs(b.first); });
      std::string words;
      for (std::size_t t = 0; t < terms.size() && t < 6; ++t) {
        char coefficient[16];
        std::snprintf(coefficient, sizeof coefficient, "%s%.2f ", terms[t].first < 0 ? "- " : "+ ",
                      std::abs(terms[t].first));
        words += (t ? " " : "") + std::string(coefficient) +
                 result
                     .parameters[static_cast<std::size_t>(
                         estimated[static_cast<std::size_t>(terms[t].second)])]
                     .name;
      }
      if (terms.size() > 6) words += " ...";
      result.unidentifiable.push_back(words);
    }
    // The covariance in half-width units, then in SI: C_ab = h_a h_b (V S^-2 V^T)_ab sigma^2.
    const Eigen::MatrixXd scaled =
        V * inverse_squares.asDiagonal() * V.transpose() * result.residual_variance;
    for (Eigen::Index a = 0; a < p; ++a) {
      const std::size_t ka = static_cast<std::size_t>(estimated[static_cast<std::size_t>(a)]);
      ParameterEstimate& e = result.parameters[ka];
      e.identifiable = identifiable[static_cast<std::size_t>(a)];
      const bool known = result.covariance_ok && e.identifiable;
      for (Eigen::Index b = 0; b < p; ++b) {
        const std::size_t kb = static_cast<std::size_t>(estimated[static_cast<std::size_t>(b)]);
        const bool both = known && identifiable[static_cast<std::size_t>(b)];
        result.covariance(static_cast<Eigen::Index>(ka), static_cast<Eigen::Index>(kb)) =
            both ? 0.5 * (scaled(a, b) + scaled(b, a)) * e.half_width *
                       result.parameters[kb].half_width
                 : kNaN;
      }
      e.std_dev = known ? e.half_width * std::sqrt(scaled(a, a)) : kNaN;
    }
    if (!result.unidentifiable.empty()) {
      result.warnings.push_back(
          std::to_string(result.unidentifiable.size()) +
          " combinations of parameters (in half-widths) are not identifiable from these data, "
          "beyond the gauge: " +
          listing(result.unidentifiable, 3));
    }
  } else {
    for (int k : estimated) {
      result.parameters[static_cast<std::size_t>(k)].std_dev = kNaN;
      if (!options.compute_covariance) continue;
      for (int j : estimated) result.covariance(k, j) = kNaN;  // zero against the held ones
    }
  }
}

void add_warnings(const Identification& id, CalibrationResult* result) {
  for (int k = 0; k < id.count(); ++k) {
    const ParameterEstimate& p = result->parameters[static_cast<std::size_t>(k)];
    if (id.bounded(k) || !(p.half_width > 0)) continue;
    const double deviation = std::abs(p.value - p.nominal) / p.half_width;
    if (deviation > 1) {
      result->warnings.push_back(p.name + " = " + format_number(p.value) + " lies " +
                                 format_number(deviation) + " half-widths from its declared " +
                                 format_number(p.nominal) + " +- " + format_number(p.half_width) +
                                 ": the extrinsics guess or its uncertainty is wrong");
    }
  }
  const double dof = 3.0 * static_cast<double>(id.rows() - result->outliers.size()) -
                     static_cast<double>(result->jacobian_rank);
  result->residuals_exceed_noise =
      residuals_exceed_noise(result->residual_variance, dof, result->warnings);
  std::vector<std::string> at_bound;
  for (const ParameterEstimate& p : result->parameters)
    if (p.at_bound) at_bound.push_back(p.name);
  if (!at_bound.empty()) {
    result->warnings.push_back(
        std::to_string(at_bound.size()) +
        " parameters ended at a bound of their interval: " + listing(at_bound, 10));
  }
}

}  // namespace pcr::calib_internal
