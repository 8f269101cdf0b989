#pragma once
// What the JSON file readers share (the planar robot_io.cpp and spatial_robot_io.cpp of pcr::io,
// the tag board file of pcr::vision): the JSON parse with its guards (nesting, duplicate keys,
// overflowing numbers, syntax errors by line and column), a reader whose every error names the
// file, the field path and the value, and the pretty printer the writers use. Internal to the
// libraries (no installed header): nlohmann_json stays private.

#include <Eigen/Core>
#include <cmath>
#include <initializer_list>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "pcr/csv_io.hpp"  // format_double
#include "pcr/input_error.hpp"
#include "pcr/robot_io.hpp"
#include "pcr/spatial/robot.hpp"
#include "pcr/spatial/robot_io.hpp"  // kUnitQuaternionTolerance

namespace pcr::json_io {

using Json = nlohmann::json;
using Ordered = nlohmann::ordered_json;

inline std::string join(const std::string& parent, const std::string& key) {
  return parent.empty() ? key : parent + "." + key;
}
inline std::string index(const std::string& parent, std::size_t i) {
  return parent + "[" + std::to_string(i) + "]";
}

// Physical ranges shared by the robot formats (docs/formats.md's field tables): a lab robot fits
// in a 10 m room, an angle needs no more than two turns, E spans soft polymers (1 MPa) to diamond
// (1.2 TPa), and every EI = E pi d^4 / 64 they allow is a finite, normal double.
constexpr double kMaxCoordinate = 10.0;    // m
constexpr double kMaxAngle = 4.0 * M_PI;   // rad
constexpr double kMinYoungModulus = 1e6;   // Pa
constexpr double kMaxYoungModulus = 2e12;  // Pa

/// Parses `json_text` (named `source` in errors): InputError on nesting deeper than
/// kMaxJsonNesting, a duplicate key, or a syntax error (by line and column). A number literal that
/// overflows a double is kept as a marked string, which JsonReader::number reports with its field.
Json parse_json(const std::string& json_text, const std::string& source);

/// A short rendering of an offending value for messages.
std::string show(const Json& value);
/// Whether `value` is a number literal that overflowed a double (see parse_json).
bool is_overflow(const Json& value);

/// Reads values of one parsed file; every error names the source and the field path.
class JsonReader {
 public:
  explicit JsonReader(std::string source) : source_(std::move(source)) {}

  const std::string& source() const { return source_; }

  [[noreturn]] void fail(const std::string& path, const std::string& what) const;
  [[noreturn]] void fail(const std::string& path, const std::string& what, const Json& value) const;

  /// `object` must be a JSON object whose keys are all in `allowed`.
  void check_object(const Json& object, const std::string& path,
                    std::initializer_list<const char*> allowed) const;
  const Json& required(const Json& object, const std::string& path, const char* key) const;
  double number(const Json& value, const std::string& path) const;
  /// A number in the field's physical range [lo, hi] (docs/formats.md's field tables).
  double in_range(const Json& value, const std::string& path, double lo, double hi,
                  const char* unit) const;

  /// A half-width: 0 (the parameter is known) or in [min, max]. Below min a bound would be
  /// indistinguishable from the value itself (a denormal aborts the bounded solver).
  double half_width(const Json& value, const std::string& path, double min, double max,
                    const char* unit) const;

  template <int N>
  Eigen::Matrix<double, N, 1> vector(const Json& value, const std::string& path) const {
    if (!value.is_array() || value.size() != static_cast<std::size_t>(N)) {
      fail(path, "expected an array of " + std::to_string(N) + " numbers", value);
    }
    Eigen::Matrix<double, N, 1> out;
    for (int i = 0; i < N; ++i) out(i) = number(value[static_cast<std::size_t>(i)], index(path, i));
    return out;
  }
  /// An array of N half-widths (half_width).
  template <int N>
  Eigen::Matrix<double, N, 1> half_widths(const Json& value, const std::string& path, double min,
                                          double max, const char* unit) const {
    const Eigen::Matrix<double, N, 1> v = vector<N>(value, path);
    for (int i = 0; i < N; ++i)
      half_width(value[static_cast<std::size_t>(i)], index(path, i), min, max, unit);
    return v;
  }
  /// An array of N numbers, each in [lo, hi].
  template <int N>
  Eigen::Matrix<double, N, 1> vector_in_range(const Json& value, const std::string& path, double lo,
                                              double hi, const char* unit) const {
    const Eigen::Matrix<double, N, 1> v = vector<N>(value, path);
    for (int i = 0; i < N; ++i) {
      in_range(value[static_cast<std::size_t>(i)], index(path, i), lo, hi, unit);
    }
    return v;
  }

  /// An array of numbers of unit norm within kUnitQuaternionTolerance (a quaternion (w, x, y, z)
  /// or a direction), refused rather than normalised.
  template <int N>
  Eigen::Matrix<double, N, 1> unit(const Json& value, const std::string& path,
                                   const char* what) const {
    const Eigen::Matrix<double, N, 1> v = vector<N>(value, path);
    const double norm = v.norm();
    if (!(std::abs(norm - 1.0) <= kUnitQuaternionTolerance)) {
      fail(path,
           std::string("expected ") + what + " of unit norm (within " +
               format_double(kUnitQuaternionTolerance) + "; its norm is " + format_double(norm) +
               ")",
           value);
    }
    return v;
  }

  /// A point within kMaxCoordinate of the origin in every coordinate (m).
  Vector3<double> point(const Json& value, const std::string& path) const {
    return vector_in_range<3>(value, path, -kMaxCoordinate, kMaxCoordinate, "m");
  }

  /// A pose {"position": [x, y, z], "orientation": [w, x, y, z]}, both optional (identity).
  SpatialPose<double> frame(const Json& value, const std::string& path) const {
    check_object(value, path, {"position", "orientation"});
    SpatialPose<double> pose;
    if (value.contains("position"))
      pose.position = point(value["position"], join(path, "position"));
    if (value.contains("orientation")) {
      pose.orientation =
          unit<4>(value["orientation"], join(path, "orientation"), "a quaternion (w, x, y, z)");
    }
    return pose;
  }

 private:
  std::string source_;
};

/// The "kind" field of a robot file's root (kPlanar when absent); fails on any other value.
RobotKind robot_kind(const JsonReader& reader, const Json& root);
/// Fails, naming the file, the field and the kind, unless the file describes a robot of `kind`:
/// a planar command given a spatial file, or the other way round.
void require_kind(const JsonReader& reader, const Json& root, RobotKind kind);

/// Writes `value`: objects one field per line, arrays of numbers on one line. Numbers go through
/// nlohmann's shortest round-trip formatting, so load(save(x)) == x bit for bit.
void print(const Ordered& value, int indent, std::ostringstream& out);

/// Whether two doubles have the same bits (a field equal to its default is not written).
bool same_bits(double a, double b);

}  // namespace pcr::json_io
