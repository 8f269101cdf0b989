#pragma once
// The outlier rule both calibrations share (calibrate and calibrate_spatial): the Huber scale
// of a stage, the gross outliers a stage leaves out, the outliers named at the result, and the
// residual test against the declared noise. Each row's residual is a block of whitened values
// (3 for a planar pose, 6 for a spatial one), O(1) each at the declared noise.

#include <Eigen/Core>
#include <functional>
#include <string>
#include <vector>

namespace pcr::calib_internal {

/// Rows whose residual at a stage's start exceeds this many times the Huber scale are left out of
/// the stage (see gross_outliers).
inline constexpr double kGrossOutlier = 100;

/// While the model is still far (the rows' median residual above its value at the noise), a row
/// beyond this many times the median row is left out too (see gross_outliers).
inline constexpr double kGrossOutlierOfTypical = 10;

/// The Huber scale: `robust_scale` declared noise units, or as many times the rows' typical
/// residual when the model is still far (a stage that starts from the nominal geometry sees
/// micrometres on every row): a row is an outlier against the others, not against a floor the
/// model has not reached. `norms`: each row's whitened residual norm (NaN: a row not evaluated,
/// left out), blocks of `block` values; the median of such a norm at the noise is that of a
/// chi distribution with `block` degrees of freedom (1.538 for 3, 2.313 for 6). 0 without a
/// robust loss.
double huber_scale(double robust_scale, const std::vector<double>& norms, int block);

/// The rows a stage leaves out: residual at its start beyond kGrossOutlier times the Huber
/// `scale` (a measurement of another equilibrium branch, a row millimetres off), or not evaluated.
/// The Huber cost grows linearly in the residual: one such row outweighs all the others together,
/// and Ceres' relative convergence test then stops on decreases many noise units large (a planar
/// row 10 mm off: the validation mean at 0.073 um instead of the floor). While the model is far,
/// the Huber scale is wide (huber_scale) and a row a millimetre off sits within a hundred of it
/// (a spatial stage starting 52 um off: a row 1 mm off is 19 typical rows, 9 Huber scales), yet
/// its linear cost still outweighs the others and stalls the stage with the geometry at its
/// bounds. So a row beyond kGrossOutlierOfTypical times the median row is left out as well (but
/// not one within kGrossOutlier times `robust_scale` noise units); near the noise the first rule
/// alone holds. A row left out of a stage's start is looked at again when the stage is solved
/// again with a narrower scale, by the next stage and at the result.
/// None when `scale` is 0.
std::vector<bool> gross_outliers(const std::vector<double>& norms, double scale,
                                 double robust_scale, int block);

/// Whether a stage solved with the Huber scale `used` is solved again with `now`, the scale of
/// its result's residual `norms` (its gross outliers `gross`, gross_outliers with `now`): the
/// scale follows the residuals down while it shrinks by half (a stage that starts far from the
/// data first fits with a wide one), unless no row it keeps lies beyond `now`. Every such row then
/// sits in the quadratic part of both losses, so the result already solves the stage with `now`
/// (a stage that converged onto the noise: one solve, not two).
bool solve_stage_again(double used, double now, const std::vector<double>& norms,
                       const std::vector<bool>& gross);

/// Outliers at the result: the rows (blocks of `block` values of `r`) whose whitened residual norm
/// exceeds `threshold` (> 0) are named in `outliers` ("line 12 (850 x the noise)", `origin` of the
/// block's index), one warning says so, and their blocks leave `J` and `r`: the rank, residual
/// variance and covariance are the other rows'.
void leave_out_outliers(double threshold, int block,
                        const std::function<std::string(std::size_t)>& origin, Eigen::MatrixXd& J,
                        Eigen::VectorXd& r, std::vector<std::string>& outliers,
                        std::vector<std::string>& warnings);

/// The residual test: whitened residuals have unit variance at the declared noise; a `variance`
/// more than 5 standard deviations of its chi-square estimate (`dof` degrees of freedom) above 1
/// is an inconsistency, not chance. With a warning in `warnings` when it fails.
bool residuals_exceed_noise(double variance, double dof, std::vector<std::string>& warnings);

}  // namespace pcr::calib_internal
