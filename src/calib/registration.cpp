// The extrinsics registered onto the nominal poses (Eq. 5), and the mirrored-frame warning.

#include <Eigen/QR>
#include <cmath>
#include <vector>

#include "calibration_internal.hpp"

namespace pcr::calib_internal {

Extrinsics<double> registered_extrinsics(const std::vector<Pose2<double>>& platform,
                                         const std::vector<CalibrationSample>& rows,
                                         const Extrinsics<double>& guess) {
  const Eigen::Index m = static_cast<Eigen::Index>(rows.size());
  Eigen::MatrixXd a(2 * m, 4);
  Eigen::VectorXd b(2 * m);
  const Vector2<double> g = guess.pattern.translation();
  for (Eigen::Index j = 0; j < m; ++j) {
    const Pose2<double>& measured = rows[static_cast<std::size_t>(j)].measured;
    const Vector2<double> v = measured.transform(g);  // t_Mj + R_Mj t_Pm
    a.row(2 * j) << 1, 0, v.x(), -v.y();
    a.row(2 * j + 1) << 0, 1, v.y(), v.x();
    b(2 * j) = platform[static_cast<std::size_t>(j)].x;
    b(2 * j + 1) = platform[static_cast<std::size_t>(j)].y;
  }
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(a);
  const Eigen::Vector4d x = qr.solve(b);
  if (qr.rank() < 4 || !x.allFinite() || x.tail<2>().norm() == 0) return guess;
  Extrinsics<double> out = guess;
  out.camera = Pose2<double>{x(0), x(1), std::atan2(x(3), x(2))};
  double sin_sum = 0, cos_sum = 0;
  for (std::size_t j = 0; j < rows.size(); ++j) {
    const double d = platform[j].theta - rows[j].measured.theta - out.camera.theta;
    sin_sum += std::sin(d);
    cos_sum += std::cos(d);
  }
  out.pattern.theta = std::atan2(sin_sum, cos_sum);
  return out;
}

namespace {

/// RMS distance (m) between the platform positions the measurements give through `extrinsics`
/// (Eq. 5) and `platform`.
double registration_rms(const std::vector<Pose2<double>>& platform,
                        const std::vector<CalibrationSample>& rows,
                        const Extrinsics<double>& extrinsics) {
  double square = 0;
  for (std::size_t j = 0; j < rows.size(); ++j) {
    const Pose2<double> p = extrinsics.platform_from_measurement(rows[j].measured);
    square += (p.translation() - platform[j].translation()).squaredNorm();
  }
  return std::sqrt(square / static_cast<double>(rows.size()));
}

}  // namespace

void warn_of_mirror(const std::vector<Pose2<double>>& platform,
                    const std::vector<CalibrationSample>& rows,
                    const Extrinsics<double>& registered, const Extrinsics<double>& guess,
                    CalibrationResult* result) {
  std::vector<CalibrationSample> mirrored = rows;
  for (CalibrationSample& row : mirrored) {
    row.measured.y = -row.measured.y;
    row.measured.theta = -row.measured.theta;
  }
  const double as_given = registration_rms(platform, rows, registered);
  const double as_mirrored =
      registration_rms(platform, mirrored, registered_extrinsics(platform, mirrored, guess));
  if (as_mirrored * 10 < as_given) {
    result->warnings.push_back(
        "the measured poses register onto the nominal model's " +
        format_number(as_given / as_mirrored) +
        " times better mirrored (y and theta negated): written in a left-handed frame, as an "
        "image's (y down)?");
  }
}

}  // namespace pcr::calib_internal
