// How the calibration's messages name rows and list items.

#include <sstream>
#include <string>
#include <vector>

#include "calibration_internal.hpp"

namespace pcr::calib_internal {

std::string format_number(double v) {
  std::ostringstream s;
  s.precision(6);
  s << v;
  return s.str();
}

std::string origin_of(const std::vector<CalibrationSample>& data, std::size_t j) {
  return data[j].origin.empty() ? "configuration " + std::to_string(j + 1) : data[j].origin;
}

std::string joints_text(const JointVector& q) {
  std::string out = "q = (";
  for (Eigen::Index i = 0; i < q.size(); ++i) out += (i ? ", " : "") + format_number(q[i]);
  return out + ") m";
}

std::string listing(const std::vector<std::string>& items, std::size_t shown) {
  std::string out;
  for (std::size_t k = 0; k < items.size() && k < shown; ++k) out += (k ? "; " : "") + items[k];
  if (items.size() > shown) out += "; and " + std::to_string(items.size() - shown) + " more";
  return out;
}

}  // namespace pcr::calib_internal
