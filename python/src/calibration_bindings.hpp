#pragma once
// Shared by the bindings of pcr::calib (wrap_calibration.cpp and the files of its topics): joints
// and poses as row-major arrays, and the checked conversions of datasets and stages.

#include <vector>

#include "bindings.hpp"
#include "pcr/calib/calibrator.hpp"

namespace pcr::python {

using RowMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
using InputMatrix = Eigen::Ref<const RowMatrix>;

// ---- datasets (defined in wrap_dataset.cpp) ---------------------------------------------------

/// Joint configurations as an (N, n) array (m).
RowMatrix joints_matrix(const std::vector<JointVector>& rows, int n);

/// (N, n) joints, checked against the robot's limb count and for finite values.
std::vector<JointVector> joint_rows(const InputMatrix& q, int n, const char* what);

/// The rows of a dataset: q (N, n) and measured (N, 3), named in messages as `q_name` and
/// `measured_name`.
std::vector<CalibrationSample> samples(const InputMatrix& q, const InputMatrix& measured, int n,
                                       const char* q_name = "q",
                                       const char* measured_name = "measured");

// ---- stages (defined in wrap_calibration_stages.cpp) ------------------------------------------

/// Stages as a list of dicts (name, free, bounds_scale).
py::list stages_list(const std::vector<CalibrationStage>& stages);

/// A stages argument as a list of dicts (name, free, bounds_scale; default_stages() gives them)
/// or a stages JSON file's path (a str or an os.PathLike). ValueError naming the stage and the
/// field otherwise.
std::vector<CalibrationStage> stages_from(const py::handle& object);

}  // namespace pcr::python
