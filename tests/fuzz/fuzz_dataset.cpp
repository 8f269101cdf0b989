// Dataset CSV (q1..qn,x,y,theta; parse_dataset) and joint configurations CSV (q1..qn;
// parse_configurations): the same bytes through both.
#include <sstream>

#include "fuzz_input.hpp"
#include "pcr/calib/dataset.hpp"
#include "pcr/robot_io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text = pcr::fuzz::as_text(data, size);
  for (const int joints : {-1, 3}) {
    try {
      std::istringstream in(text);
      pcr::parse_dataset(in, "fuzz.csv", joints);
    } catch (const pcr::InputError&) {
    }
    try {
      std::istringstream in(text);
      pcr::parse_configurations(in, "fuzz.csv", joints);
    } catch (const pcr::InputError&) {
    }
  }
  return 0;
}
