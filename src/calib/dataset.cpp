#include "pcr/calib/dataset.hpp"

#include <cmath>
#include <fstream>
#include <istream>
#include <sstream>

#include "pcr/csv_io.hpp"
#include "pcr/files.hpp"

namespace pcr {
namespace {

std::vector<std::string> joint_columns(int num_joints) {
  std::vector<std::string> columns;
  for (int i = 1; i <= num_joints; ++i) columns.push_back("q" + std::to_string(i));
  return columns;
}

/// Number of leading q1..qk columns of a header (the numeric columns only).
int count_joint_columns(const std::vector<std::string>& columns) {
  int k = 0;
  while (k < static_cast<int>(columns.size()) && columns[k] == "q" + std::to_string(k + 1)) ++k;
  return k;
}

/// "q1,...,qn" followed by the pose columns, for messages.
std::string expected_header(const std::vector<std::string>& pose) {
  std::string out = "q1,...,qn";
  for (const std::string& c : pose) out += "," + c;
  return out;
}

/// The joint count of a table read without expected columns: the header's q columns, or the
/// field count minus the pose columns without one; at most max_joints.
int infer_joints(const CsvTable& table, const std::vector<std::string>& pose, int max_joints,
                 const std::string& source) {
  if (table.has_header) {
    const int k = count_joint_columns(table.columns);
    if (k < 1)
      throw InputError(source + ": header has no q1 column (expected " + expected_header(pose) +
                       ")");
    return k;
  }
  if (table.rows.empty()) throw InputError(source + ": no data rows and no header");
  const int k = static_cast<int>(table.columns.size() - pose.size());
  if (k < 1 || k > max_joints) {
    throw InputError(source + ": " + std::to_string(table.columns.size()) +
                     " columns cannot hold " + expected_header(pose) +
                     " with 1 <= n <= " + std::to_string(max_joints));
  }
  return k;
}

/// A table of joints followed by the `pose` columns (none for configurations).
CsvTable read_table(std::istream& in, const std::string& source, int num_joints,
                    const std::vector<std::string>& pose, int max_joints, int* joints) {
  const auto columns = [&](int n) {
    std::vector<std::string> out = joint_columns(n);
    out.insert(out.end(), pose.begin(), pose.end());
    return out;
  };
  if (num_joints < 0) {
    // Read once (within the table limits), parsed twice: peek, then read.
    const std::string text = read_table_text(in, source);
    std::istringstream first(text);
    const CsvTable peek = parse_csv(first, source);
    num_joints = infer_joints(peek, pose, max_joints, source);
    std::istringstream second(text);
    CsvReadOptions options;
    options.columns = columns(num_joints);
    *joints = num_joints;
    return parse_csv(second, source, options);
  }
  if (num_joints < 1 || num_joints > max_joints) {
    throw InputError(source + ": invalid number of joints " + std::to_string(num_joints));
  }
  CsvReadOptions options;
  options.columns = columns(num_joints);
  *joints = num_joints;
  return parse_csv(in, source, options);
}

/// Every pose field of a row within its range: a pose no robot can give in any unit (a
/// corrupted row) would be fitted like any other. `angle(c)`: whether column c holds an angle.
template <class IsAngle>
void check_pose_fields(const CsvTable& table, std::size_t r, std::size_t first,
                       IsAngle angle_column, const std::string& source) {
  const CsvRow row = table.rows[r];
  for (std::size_t c = first; c < row.size(); ++c) {
    const bool angle = angle_column(c - first);
    const double limit = angle ? kMaxDatasetAngle : kMaxDatasetPosition;
    if (std::abs(row[c]) <= limit) continue;
    const int column = c < table.source_columns.size() ? table.source_columns[c] : 0;
    throw InputError(
        source + ":" + std::to_string(table.line_numbers[r]) +
        (column > 0 ? ":" + std::to_string(column) : std::string()) + ": column " +
        std::to_string(column) + " (" + table.columns[c] + "): " + format_double(row[c]) +
        (angle ? " rad" : " m") + " is outside [" + format_double(-limit) + ", " +
        format_double(limit) +
        (angle ? "] rad, the range of a measured angle" : "] m, the range of a measured position"));
  }
}

const std::vector<std::string> kPlanarPose = {"x", "y", "theta"};
const std::vector<std::string> kSpatialPose = {"x", "y", "z", "rx", "ry", "rz"};

std::ifstream open(const std::string& path) { return open_input_file(path); }

}  // namespace

void Dataset::add(const JointVector& joints, const Pose2<double>& pose) {
  if (num_joints == 0) num_joints = static_cast<int>(joints.size());
  if (joints.size() != num_joints) {
    throw InputError("Dataset::add: configuration with " + std::to_string(joints.size()) +
                     " joints in a dataset of " + std::to_string(num_joints));
  }
  q.push_back(joints);
  poses.push_back(pose);
}

std::vector<std::string> dataset_columns(int num_joints) {
  std::vector<std::string> columns = joint_columns(num_joints);
  columns.insert(columns.end(), kPlanarPose.begin(), kPlanarPose.end());
  return columns;
}

Dataset parse_dataset(std::istream& in, const std::string& source, int num_joints) {
  Dataset data;
  const CsvTable table =
      read_table(in, source, num_joints, kPlanarPose, kMaxLimbs, &data.num_joints);
  const int n = data.num_joints;
  for (std::size_t r = 0; r < table.rows.size(); ++r) {
    // The joints are the calibration's to check: a row out of reach is named or dropped there.
    check_pose_fields(
        table, r, static_cast<std::size_t>(n), [](std::size_t c) { return c == 2; }, source);
    const CsvRow row = table.rows[r];
    JointVector q(n);
    for (int i = 0; i < n; ++i) q(i) = row[static_cast<std::size_t>(i)];
    data.q.push_back(q);
    data.poses.push_back(Pose2<double>{row[n], row[n + 1], row[n + 2]});
    data.line_numbers.push_back(table.line_numbers[r]);
  }
  return data;
}

Dataset read_dataset(const std::string& path, int num_joints) {
  std::ifstream in = open(path);
  return parse_dataset(in, path, num_joints);
}

std::string dataset_to_csv(const Dataset& data) {
  std::string out = csv_line(dataset_columns(data.num_joints));
  for (std::size_t r = 0; r < data.size(); ++r) {
    std::vector<std::string> fields;
    for (int i = 0; i < data.q[r].size(); ++i) fields.push_back(format_double(data.q[r](i)));
    fields.push_back(format_double(data.poses[r].x));
    fields.push_back(format_double(data.poses[r].y));
    fields.push_back(format_double(data.poses[r].theta));
    out += csv_line(fields);
  }
  return out;
}

void write_dataset(const Dataset& data, const std::string& path) {
  if (data.q.size() != data.poses.size()) {
    throw InputError(path + ": dataset has " + std::to_string(data.q.size()) +
                     " configurations and " + std::to_string(data.poses.size()) + " poses");
  }
  write_file_atomically(path, dataset_to_csv(data));
}

std::vector<JointVector> parse_configurations(std::istream& in, const std::string& source,
                                              int num_joints) {
  int n = 0;
  const CsvTable table = read_table(in, source, num_joints, {}, kMaxLimbs, &n);
  std::vector<JointVector> out;
  for (const CsvRow row : table.rows) {
    JointVector q(n);
    for (int i = 0; i < n; ++i) q(i) = row[static_cast<std::size_t>(i)];
    out.push_back(q);
  }
  return out;
}

std::vector<JointVector> read_configurations(const std::string& path, int num_joints) {
  std::ifstream in = open(path);
  return parse_configurations(in, path, num_joints);
}

std::string configurations_to_csv(const std::vector<JointVector>& configurations) {
  const int n = configurations.empty() ? 0 : static_cast<int>(configurations[0].size());
  std::string out = csv_line(joint_columns(n));
  for (const JointVector& q : configurations) {
    if (q.size() != n) throw InputError("configurations_to_csv: configurations of unequal sizes");
    std::vector<std::string> fields;
    for (int i = 0; i < n; ++i) fields.push_back(format_double(q(i)));
    out += csv_line(fields);
  }
  return out;
}

void write_configurations(const std::vector<JointVector>& configurations, const std::string& path) {
  write_file_atomically(path, configurations_to_csv(configurations));
}

std::vector<std::string> spatial_dataset_columns(int num_joints) {
  std::vector<std::string> columns = joint_columns(num_joints);
  columns.insert(columns.end(), kSpatialPose.begin(), kSpatialPose.end());
  return columns;
}

void SpatialDataset::add(const SpatialJointVector& joints, const SpatialPose<double>& pose) {
  if (num_joints == 0) num_joints = static_cast<int>(joints.size());
  if (joints.size() != num_joints) {
    throw InputError("SpatialDataset::add: configuration with " + std::to_string(joints.size()) +
                     " joints in a dataset of " + std::to_string(num_joints));
  }
  q.push_back(joints);
  poses.push_back(pose);
}

SpatialDataset parse_spatial_dataset(std::istream& in, const std::string& source, int num_joints) {
  SpatialDataset data;
  const CsvTable table =
      read_table(in, source, num_joints, kSpatialPose, kMaxSpatialRods, &data.num_joints);
  const int n = data.num_joints;
  for (std::size_t r = 0; r < table.rows.size(); ++r) {
    check_pose_fields(
        table, r, static_cast<std::size_t>(n), [](std::size_t c) { return c >= 3; }, source);
    const CsvRow row = table.rows[r];
    SpatialJointVector q(n);
    for (int i = 0; i < n; ++i) q(i) = row[static_cast<std::size_t>(i)];
    const Vector3<double> position(row[n], row[n + 1], row[n + 2]);
    const Vector3<double> turn(row[n + 3], row[n + 4], row[n + 5]);
    data.q.push_back(q);
    data.poses.push_back(SpatialPose<double>{position, quaternion_exp(turn)});
    data.line_numbers.push_back(table.line_numbers[r]);
  }
  return data;
}

SpatialDataset read_spatial_dataset(const std::string& path, int num_joints) {
  std::ifstream in = open(path);
  return parse_spatial_dataset(in, path, num_joints);
}

std::string spatial_dataset_to_csv(const SpatialDataset& data) {
  std::string out = csv_line(spatial_dataset_columns(data.num_joints));
  for (std::size_t r = 0; r < data.size(); ++r) {
    std::vector<std::string> fields;
    for (int i = 0; i < data.q[r].size(); ++i) fields.push_back(format_double(data.q[r](i)));
    const Vector3<double> turn = quaternion_log(data.poses[r].orientation);
    for (int k = 0; k < 3; ++k) fields.push_back(format_double(data.poses[r].position(k)));
    for (int k = 0; k < 3; ++k) fields.push_back(format_double(turn(k)));
    out += csv_line(fields);
  }
  return out;
}

void write_spatial_dataset(const SpatialDataset& data, const std::string& path) {
  if (data.q.size() != data.poses.size()) {
    throw InputError(path + ": dataset has " + std::to_string(data.q.size()) +
                     " configurations and " + std::to_string(data.poses.size()) + " poses");
  }
  write_file_atomically(path, spatial_dataset_to_csv(data));
}

}  // namespace pcr
