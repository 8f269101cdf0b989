// The pcr._pcr extension module: bindings of the pcr C++ library (see python/pcr/__init__.py).
#include "bindings.hpp"

#ifndef PCR_VERSION
#define PCR_VERSION "unknown"
#endif

PYBIND11_MODULE(_pcr, m) {
  namespace py = pybind11;
  m.doc() =
      "pcr: planar and spatial parallel continuum robots (C++ bindings). SI units: m, rad, N, Pa.";
  m.attr("__version__") = PCR_VERSION;
  // pcr::InputError derives from std::invalid_argument, which pybind11 already maps to
  // ValueError; other std::exception types become RuntimeError. Both keep the C++ message.
  pcr::python::wrap_robot(m);
  pcr::python::wrap_kinematics(m);
  pcr::python::wrap_spatial(m);
#ifdef PCR_PYTHON_HAS_CALIB
  pcr::python::wrap_sensitivity(m);
  pcr::python::wrap_virtual_robot(m);
  pcr::python::wrap_dataset(m);
  pcr::python::wrap_workspace_map(m);
  pcr::python::wrap_sampling(m);
  pcr::python::wrap_calibration_stages(m);
  pcr::python::wrap_pose_errors(m);
  // after wrap_pose_errors: CalibrationTable's fields are PoseErrorStats
  pcr::python::wrap_calibration(m);
  pcr::python::wrap_spatial_calibration(m);  // after wrap_spatial: returns SpatialRobot
  pcr::python::wrap_accuracy(m);             // after wrap_virtual_robot: uses VirtualRobot
  pcr::python::wrap_predicted_accuracy(m);
  pcr::python::wrap_method(m);          // its result holds the classes above
  pcr::python::wrap_spatial_method(m);  // after wrap_spatial_calibration: the same dicts
  m.attr("has_calibration") = true;
#else
  m.attr("has_calibration") = false;
#endif
#ifdef PCR_PYTHON_HAS_VISION
  pcr::python::wrap_vision(m);
  m.attr("has_vision") = true;
#else
  m.attr("has_vision") = false;
#endif
}
