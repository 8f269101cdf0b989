// Image headers (image_header_size): the size a PNG, JPEG, TIFF, BMP or PNM declares, read before
// anything is decoded.
#include <vector>

#include "fuzz_input.hpp"
#include "pcr/robot_io.hpp"
#include "pcr/vision/image.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    const auto [width, height] =
        pcr::vision::image_header_size(std::vector<unsigned char>(data, data + size), "fuzz");
    if (width <= 0 || height <= 0 ||
        static_cast<long long>(width) * height > pcr::vision::kMaxImagePixels)
      std::abort();
  } catch (const pcr::InputError&) {
  }
  return 0;
}
