// Attachment layout JSON (parse_attachment_layout).
#include "fuzz_input.hpp"
#include "pcr/robot_io.hpp"
#include "pcr/vision/attachment_points.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    pcr::vision::parse_attachment_layout(pcr::fuzz::as_text(data, size), "fuzz.json");
  } catch (const pcr::InputError&) {
  }
  return 0;
}
