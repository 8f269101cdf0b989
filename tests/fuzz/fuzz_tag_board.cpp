// Tag board JSON (parse_tag_board).
#include "fuzz_input.hpp"
#include "pcr/robot_io.hpp"
#include "pcr/vision/tag_board.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    pcr::vision::parse_tag_board(pcr::fuzz::as_text(data, size), "fuzz.json");
  } catch (const pcr::InputError&) {
  }
  return 0;
}
