// Calibration datasets and joint configurations as CSV files and arrays (pcr/calib/dataset.hpp).
#include "calibration_bindings.hpp"
#include "pcr/calib/dataset.hpp"

namespace pcr::python {
RowMatrix poses_matrix(const std::vector<Pose2<double>>& poses) {
  RowMatrix out(static_cast<Eigen::Index>(poses.size()), 3);
  for (std::size_t r = 0; r < poses.size(); ++r) {
    out.row(static_cast<Eigen::Index>(r)) << poses[r].x, poses[r].y, poses[r].theta;
  }
  return out;
}

RowMatrix joints_matrix(const std::vector<JointVector>& rows, int n) {
  RowMatrix out(static_cast<Eigen::Index>(rows.size()), n);
  for (std::size_t r = 0; r < rows.size(); ++r)
    out.row(static_cast<Eigen::Index>(r)) = rows[r].transpose();
  return out;
}

std::vector<JointVector> joint_rows(const InputMatrix& q, int n, const char* what) {
  if (q.cols() != n) {
    throw std::invalid_argument(std::string(what) + ": expected an (N, " + std::to_string(n) +
                                ") array of joint values (m), got " + std::to_string(q.cols()) +
                                " columns");
  }
  if (!q.allFinite()) throw std::invalid_argument(std::string(what) + ": non-finite value");
  std::vector<JointVector> rows;
  for (Eigen::Index r = 0; r < q.rows(); ++r) rows.emplace_back(q.row(r).transpose());
  return rows;
}

std::vector<CalibrationSample> samples(const InputMatrix& q, const InputMatrix& measured, int n,
                                       const char* q_name, const char* measured_name) {
  const std::vector<JointVector> joints = joint_rows(q, n, q_name);
  if (measured.cols() != 3 || measured.rows() != q.rows()) {
    throw std::invalid_argument(std::string(measured_name) +
                                ": expected an (N, 3) array of pattern poses (m, m, rad) "
                                "with N = " +
                                std::to_string(q.rows()) + ", got (" +
                                std::to_string(measured.rows()) + ", " +
                                std::to_string(measured.cols()) + ")");
  }
  if (!measured.allFinite()) {
    throw std::invalid_argument(std::string(measured_name) + ": non-finite value");
  }
  std::vector<CalibrationSample> data;
  for (std::size_t r = 0; r < joints.size(); ++r) {
    const auto row = measured.row(static_cast<Eigen::Index>(r));
    data.push_back(CalibrationSample{joints[r], Pose2<double>{row(0), row(1), row(2)}});
  }
  return data;
}

void wrap_dataset(py::module_& m) {
  m.def(
      "read_dataset",
      [](const std::filesystem::path& path, int num_joints) {
        const Dataset d = read_dataset(input_path(path), num_joints);
        return py::make_tuple(joints_matrix(d.q, d.num_joints), poses_matrix(d.poses));
      },
      py::arg("path"), py::arg("num_joints") = -1,
      "Reads a calibration dataset CSV (q1..qn,x,y,theta) -> (q (N, n) m, measured (N, 3) "
      "m, m, rad). FileNotFoundError when it does not exist, ValueError naming the file, line "
      "and column.");
  m.def(
      "write_dataset",
      [](const std::filesystem::path& path, const InputMatrix& q, const InputMatrix& measured) {
        Dataset d;
        d.num_joints = static_cast<int>(q.cols());
        for (const CalibrationSample& s : samples(q, measured, d.num_joints))
          d.add(s.q, s.measured);
        write_dataset(d, output_path(path));
      },
      py::arg("path"), py::arg("q"), py::arg("measured"),
      "Writes a dataset CSV atomically (full precision).");
  m.def(
      "read_configurations",
      [](const std::filesystem::path& path, int num_joints) {
        const std::vector<JointVector> rows = read_configurations(input_path(path), num_joints);
        const int n = rows.empty() ? std::max(num_joints, 0) : static_cast<int>(rows[0].size());
        return joints_matrix(rows, n);
      },
      py::arg("path"), py::arg("num_joints") = -1,
      "Reads joint configurations (q1..qn, m) -> (N, n) array.");
  m.def(
      "write_configurations",
      [](const std::filesystem::path& path, const InputMatrix& q) {
        write_configurations(joint_rows(q, static_cast<int>(q.cols()), "q"), output_path(path));
      },
      py::arg("path"), py::arg("q"), "Writes joint configurations (m) atomically.");
}

}  // namespace pcr::python
