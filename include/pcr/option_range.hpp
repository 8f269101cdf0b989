#pragma once
// The documented range of a numeric option: the one home of what pcr accepts for it. Each options
// struct checks its fields against its ranges (is_valid, as Ceres' Solver::Options::IsValid), the
// library's entry points refuse what is_valid refuses, and the front-ends only translate: the
// command line builds its validators and help from the same ranges, Python reports the message.

#include <cmath>
#include <limits>
#include <sstream>
#include <string>

namespace pcr {

struct OptionRange {
  const char* name;                                      ///< the field, as C++ and Python spell it
  double lo = -std::numeric_limits<double>::infinity();  ///< closed; infinite: unbounded
  double hi = std::numeric_limits<double>::infinity();
  const char* unit = "";  ///< "" for a dimensionless value

  /// A finite value within [lo, hi] (a NaN is never within).
  bool contains(double value) const { return std::isfinite(value) && value >= lo && value <= hi; }

  /// "a number from 1e-06 to 0.1 (m)", "a finite number >= 0", "a finite number (N m)".
  std::string expected() const {
    std::ostringstream s;
    if (std::isfinite(lo) && std::isfinite(hi)) {
      s << "a number from " << lo << " to " << hi;
    } else if (std::isfinite(lo)) {
      s << "a finite number >= " << lo;
    } else if (std::isfinite(hi)) {
      s << "a finite number <= " << hi;
    } else {
      s << "a finite number";
    }
    if (*unit != '\0') s << " (" << unit << ")";
    return s.str();
  }

  /// Whether `value` lies within the range; if not, *error (when given) says so, naming the field
  /// with `prefix` ("effects." for a nested struct): "strain_limit: expected a number from 1e-06
  /// to 0.1, got 0.5".
  bool check(double value, std::string* error, const char* prefix = "") const {
    if (contains(value)) return true;
    if (error != nullptr) {
      std::ostringstream s;
      s << prefix << name << ": expected " << expected() << ", got " << value;
      *error = s.str();
    }
    return false;
  }
};

}  // namespace pcr
