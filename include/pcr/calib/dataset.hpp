#pragma once
// Calibration datasets and joint-configuration lists as CSV (docs/formats.md).
//
// Dataset: header `q1,...,qn,x,y,theta`, one row per configuration: joint values (m) and the
// measured pattern pose in the camera frame ^Se T_M (m, m, rad). Configurations: header
// `q1,...,qn`. Columns whose header starts with '#' are comments (ignored); lines starting with
// '#' are skipped. A wrong column count, a non-numeric field or a NaN throws InputError naming
// the file, the line and the column (pcr/csv_io.hpp rules), and so does a pose outside its
// range (kMaxDatasetPosition, kMaxDatasetAngle). Files are written atomically.

#include <iosfwd>
#include <string>
#include <vector>

#include "pcr/input_error.hpp"
#include "pcr/robot_description.hpp"
#include "pcr/se2.hpp"
#include "pcr/shooting.hpp"
#include "pcr/spatial/shooting.hpp"

namespace pcr {

struct Dataset {
  int num_joints = 0;
  std::vector<JointVector> q;        ///< joint values (m)
  std::vector<Pose2<double>> poses;  ///< measured ^Se T_M (m, m, rad)
  std::vector<int> line_numbers;     ///< 1-based source line of each row (empty if built in code)

  std::size_t size() const { return q.size(); }
  void add(const JointVector& joints, const Pose2<double>& pose);
};

/// The ranges of a dataset's measured pose: |x|, |y| (m) and |theta| (rad). The largest values a
/// unit slip can make of a pose within a pcr-robot file's ranges (10 m in millimetres, 4 pi rad in
/// degrees), which the calibration names with their likely unit; beyond, no unit makes a pose of a
/// robot of them (1e308 is a corrupted row).
inline constexpr double kMaxDatasetPosition = 1e4;
inline constexpr double kMaxDatasetAngle = 720.0;

/// "q1", ..., "qn", "x", "y", "theta".
std::vector<std::string> dataset_columns(int num_joints);

/// num_joints < 0: taken from the header (the number of q columns), or columns - 3 without one.
/// A header is required when num_joints < 0 and the file has comment columns.
Dataset parse_dataset(std::istream& in, const std::string& source, int num_joints = -1);
Dataset read_dataset(const std::string& path, int num_joints = -1);
std::string dataset_to_csv(const Dataset& data);
/// Temporary file + rename.
void write_dataset(const Dataset& data, const std::string& path);

/// A spatial robot's dataset: header `q1,...,qn,x,y,z,rx,ry,rz`, one row per configuration: the
/// joint values (m, n up to kMaxSpatialRods) and the measured marker pose ^S T_M, its position (m)
/// and its orientation M -> S as a rotation vector (rad: angle times unit axis, as `pcr fk`
/// writes a spatial pose). The same rules as Dataset's; the rotation vector's components are
/// angles (within kMaxDatasetAngle).
struct SpatialDataset {
  int num_joints = 0;
  std::vector<SpatialJointVector> q;       ///< joint values (m)
  std::vector<SpatialPose<double>> poses;  ///< measured ^S T_M
  std::vector<int> line_numbers;           ///< 1-based source line of each row (empty if built)

  std::size_t size() const { return q.size(); }
  void add(const SpatialJointVector& joints, const SpatialPose<double>& pose);
};

/// "q1", ..., "qn", "x", "y", "z", "rx", "ry", "rz".
std::vector<std::string> spatial_dataset_columns(int num_joints);
SpatialDataset parse_spatial_dataset(std::istream& in, const std::string& source,
                                     int num_joints = -1);
SpatialDataset read_spatial_dataset(const std::string& path, int num_joints = -1);
/// The orientation as quaternion_log's rotation vector (angle in [0, pi]).
std::string spatial_dataset_to_csv(const SpatialDataset& data);
/// Temporary file + rename.
void write_spatial_dataset(const SpatialDataset& data, const std::string& path);

/// Joint configurations, header `q1,...,qn` (num_joints < 0: from the file).
std::vector<JointVector> parse_configurations(std::istream& in, const std::string& source,
                                              int num_joints = -1);
std::vector<JointVector> read_configurations(const std::string& path, int num_joints = -1);
std::string configurations_to_csv(const std::vector<JointVector>& configurations);
void write_configurations(const std::vector<JointVector>& configurations, const std::string& path);

}  // namespace pcr
