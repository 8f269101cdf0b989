// The spatial robot file (parse_spatial_robot): a description that loads writes back and loads
// again, the same.
#include "fuzz_input.hpp"
#include "pcr/spatial/robot_io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  pcr::SpatialRobotDescription robot;
  try {
    robot = pcr::parse_spatial_robot(pcr::fuzz::as_text(data, size), "fuzz.json");
  } catch (const pcr::InputError&) {
    return 0;
  }
  const std::string canonical = pcr::spatial_robot_to_json(robot);
  if (pcr::spatial_robot_to_json(pcr::parse_spatial_robot(canonical, "canonical.json")) !=
      canonical) {
    std::abort();
  }
  return 0;
}
