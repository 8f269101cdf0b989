#pragma once
// Shared declarations of the pcr._pcr module: one wrap_<concept>() per file (module.cpp calls
// them in order) and the small value types the bindings hand to Python.

#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <array>
#include <string>
#include <vector>

#include "pcr/kinematics.hpp"
#include "pcr/robot_io.hpp"

namespace pcr::python {

namespace py = pybind11;

void wrap_robot(py::module_& m);
void wrap_kinematics(py::module_& m);
void wrap_calibration(py::module_& m);
void wrap_accuracy(py::module_& m);  // needs pcr::calib
void wrap_vision(py::module_& m);    // needs pcr::vision

/// A solved configuration (FK or IK) as Python sees it: the solver's result plus, on request,
/// the rods' shapes (one (steps + 1, 4) array per rod: s, x, y, theta in m, m, m, rad).
struct Solution {
  int num_limbs = 0;
  JointVector q;
  Pose2<double> pose;
  std::array<Wrench<double>, kMaxLimbs> wrenches{};
  SolverSummary summary;
  py::object shapes = py::none();
  /// The solver's factorised last Jacobian, so that a warm start from Python costs what it costs
  /// in C++; only for a warm start of the same problem (FK or IK) it was solved by.
  internal::ChordMatrix jacobian;
  bool inverse = false;
};

/// The platform load from Python arguments: force (fx, fy) in N, moment in N m.
PlatformLoad<double> make_load(const Eigen::Vector2d& force, double moment);

/// (3,) array-like -> Pose2; Pose2 passes through. Throws ValueError otherwise.
Pose2<double> to_pose(const py::handle& object, const char* what);

}  // namespace pcr::python
