// Pose CSVs: a path (x,y,theta; load_path_csv) and measured poses (pose,x_c,y_c,theta_c,x,y,theta;
// load_measured_csv): the same bytes through both.
#include "fuzz_input.hpp"
#include "pcr/calib/accuracy.hpp"
#include "pcr/robot_io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string& path = pcr::fuzz::as_file(data, size, ".csv");
  try {
    pcr::load_path_csv(path);
  } catch (const pcr::InputError&) {
  }
  try {
    pcr::load_measured_csv(path);
  } catch (const pcr::InputError&) {
  }
  return 0;
}
