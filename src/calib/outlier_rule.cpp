// The outlier rule both calibrations share (outlier_rule.hpp).

#include "outlier_rule.hpp"

#include <algorithm>
#include <cmath>

#include "calibration_internal.hpp"

namespace pcr::calib_internal {
namespace {

/// The median of the norm of a whitened `block`-vector at the noise (a chi distribution's).
double median_norm_at_noise(int block) { return block == 6 ? 2.3126 : 1.538; }

/// The median of the finite norms (NaN: none).
double median_of_evaluated(const std::vector<double>& norms) {
  std::vector<double> evaluated;
  for (const double norm : norms)
    if (std::isfinite(norm)) evaluated.push_back(norm);
  if (evaluated.empty()) return kNaN;
  std::nth_element(evaluated.begin(), evaluated.begin() + evaluated.size() / 2, evaluated.end());
  return evaluated[evaluated.size() / 2];
}

}  // namespace

double huber_scale(double robust_scale, const std::vector<double>& norms, int block) {
  if (!(robust_scale > 0)) return 0.0;
  const double median = median_of_evaluated(norms);
  if (!std::isfinite(median)) return robust_scale;
  return robust_scale * std::max(1.0, median / median_norm_at_noise(block));
}

std::vector<bool> gross_outliers(const std::vector<double>& norms, double scale,
                                 double robust_scale, int block) {
  std::vector<bool> gross(norms.size(), false);
  if (!(scale > 0)) return gross;
  double threshold = kGrossOutlier * scale;
  const double median = median_of_evaluated(norms);
  if (median > median_norm_at_noise(block)) {  // still far
    threshold = std::min(threshold,
                         std::max(kGrossOutlierOfTypical * median, kGrossOutlier * robust_scale));
  }
  for (std::size_t j = 0; j < norms.size(); ++j) gross[j] = !(norms[j] <= threshold);
  return gross;
}

bool solve_stage_again(double used, double now, const std::vector<double>& norms,
                       const std::vector<bool>& gross) {
  if (!(used > 0 && now < 0.5 * used)) return false;
  for (std::size_t j = 0; j < norms.size(); ++j) {
    if (!(j < gross.size() && gross[j]) && norms[j] > now) return true;
  }
  return false;
}

void leave_out_outliers(double threshold, int block,
                        const std::function<std::string(std::size_t)>& origin, Eigen::MatrixXd& J,
                        Eigen::VectorXd& r, std::vector<std::string>& outliers,
                        std::vector<std::string>& warnings) {
  if (!(threshold > 0)) return;
  std::vector<Eigen::Index> kept;
  const std::size_t rows = static_cast<std::size_t>(r.size() / block);
  for (std::size_t b = 0; b < rows; ++b) {
    const Eigen::Index at = block * static_cast<Eigen::Index>(b);
    const double norm = r.segment(at, block).norm();
    if (norm > threshold) {
      outliers.push_back(origin(b) + " (" + format_number(norm) + " x the noise)");
    } else {
      for (int k = 0; k < block; ++k) kept.push_back(at + k);
    }
  }
  if (outliers.empty()) return;
  warnings.push_back(std::to_string(outliers.size()) + " rows are outliers (residual beyond " +
                     format_number(threshold) +
                     " x the declared noise), down-weighted: " + listing(outliers));
  const Eigen::MatrixXd J_kept = J(kept, Eigen::all);
  const Eigen::VectorXd r_kept = r(kept);
  J = J_kept;
  r = r_kept;
}

bool residuals_exceed_noise(double variance, double dof, std::vector<std::string>& warnings) {
  const bool exceed = std::isfinite(variance) && dof > 0 && variance > 1 + 5 * std::sqrt(2 / dof);
  if (exceed) {
    warnings.push_back(
        "the residuals are " + format_number(std::sqrt(variance)) +
        " times the declared noise (residual_scale): an unmodelled effect, outliers, wrong "
        "extrinsics or more noise than declared");
  }
  return exceed;
}

}  // namespace pcr::calib_internal
