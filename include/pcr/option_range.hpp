#pragma once
// The documented range of a numeric option: the one home of what pcr accepts for it. Each options
// struct checks its fields against its ranges (is_valid, as Ceres' Solver::Options::IsValid), the
// library's entry points refuse what is_valid refuses, and the front-ends only translate: the
// command line builds its validators and help from the same ranges, Python reports the message.

#include <charconv>
#include <cmath>
#include <limits>
#include <string>

namespace pcr {

struct OptionRange {
  const char* name;                                      ///< the field, as C++ and Python spell it
  double lo = -std::numeric_limits<double>::infinity();  ///< closed; infinite: unbounded
  double hi = std::numeric_limits<double>::infinity();
  const char* unit = "";  ///< "" for a dimensionless value

  /// A finite value within [lo, hi] (a NaN is never within).
  bool contains(double value) const { return std::isfinite(value) && value >= lo && value <= hi; }

  /// The shortest text that reads back as `value`, positional from 1e-4 to 1e16 as Python prints
  /// numbers ("3.141592653589793", "100000", "0.0001", "1e-06", "nan"): the library's messages
  /// and the command line's print a bound alike, and exactly.
  static std::string text(double value) {
    char out[48];  // the longest form is under 30 characters
    const double magnitude = std::abs(value);
    const auto format = magnitude == 0 || (magnitude >= 1e-4 && magnitude < 1e16)
                            ? std::chars_format::fixed
                            : std::chars_format::scientific;
    return std::string(out, std::to_chars(out, out + sizeof out, value, format).ptr);
  }

  /// "a number from 1e-06 to 0.1 (m)", "a finite number >= 0", "a finite number (N m)".
  std::string expected() const {
    std::string s;
    if (std::isfinite(lo) && std::isfinite(hi)) {
      s = "a number from " + text(lo) + " to " + text(hi);
    } else if (std::isfinite(lo)) {
      s = "a finite number >= " + text(lo);
    } else if (std::isfinite(hi)) {
      s = "a finite number <= " + text(hi);
    } else {
      s = "a finite number";
    }
    if (*unit != '\0') s += std::string(" (") + unit + ")";
    return s;
  }

  /// Whether `value` lies within the range; if not, *error (when given) says so, naming the field
  /// with `prefix` ("effects." for a nested struct): "strain_limit: expected a number from 1e-06
  /// to 0.1, got 0.5".
  bool check(double value, std::string* error, const char* prefix = "") const {
    if (contains(value)) return true;
    if (error != nullptr) {
      *error = std::string(prefix) + name + ": expected " + expected() + ", got " + text(value);
    }
    return false;
  }
};

}  // namespace pcr
