// pcr-robot JSON (parse_robot): a description that loads writes back and loads again, the same.
#include "fuzz_input.hpp"
#include "pcr/robot_io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  pcr::RobotDescription robot;
  try {
    robot = pcr::parse_robot(pcr::fuzz::as_text(data, size), "fuzz.json");
  } catch (const pcr::InputError&) {
    return 0;
  }
  const std::string canonical = pcr::robot_to_json(robot);
  if (pcr::robot_to_json(pcr::parse_robot(canonical, "canonical.json")) != canonical) std::abort();
  return 0;
}
