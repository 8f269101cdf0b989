// OpenCV camera YAML (load_camera).
#include "fuzz_input.hpp"
#include "pcr/robot_io.hpp"
#include "pcr/vision/camera.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    pcr::vision::load_camera(pcr::fuzz::as_file(data, size, ".yaml"));
  } catch (const pcr::InputError&) {
  }
  return 0;
}
