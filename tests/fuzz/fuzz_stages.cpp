// Calibration stages JSON (load_calibration_stages).
#include "fuzz_input.hpp"
#include "pcr/calib/calibrator.hpp"
#include "pcr/robot_io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    pcr::load_calibration_stages(pcr::fuzz::as_file(data, size, ".json"));
  } catch (const pcr::InputError&) {
  }
  return 0;
}
