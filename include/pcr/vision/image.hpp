#pragma once
// A grey-level image as plain floats, so pcr::vision's public headers need no OpenCV.
// Pixel (u, v) = column u, row v; intensities in [0, 1]. OpenCV's convention: the centre of pixel
// (u, v) is at the coordinates (u, v), so pixel u covers [u - 0.5, u + 0.5].

#include <string>
#include <utility>
#include <vector>

namespace pcr::vision {

struct GrayImage {
  int width{0};
  int height{0};
  std::vector<float> pixels;  ///< row-major, width * height values in [0, 1]

  GrayImage() = default;
  GrayImage(int w, int h, float value = 0.f)
      : width(w),
        height(h),
        pixels(static_cast<std::size_t>(w) * static_cast<std::size_t>(h), value) {}

  bool empty() const { return width <= 0 || height <= 0; }
  float& at(int u, int v) { return pixels[static_cast<std::size_t>(v) * width + u]; }
  float at(int u, int v) const { return pixels[static_cast<std::size_t>(v) * width + u]; }
};

/// The most pixels an image, a camera or a render may have: the largest sensors sold have about
/// 150 Mpx. It bounds memory (a float per pixel, and OpenCV's decoded copy) before any decoding.
inline constexpr long long kMaxImagePixels = 200'000'000;

/// The width and height (px) a PNG, JPEG, TIFF, BMP or PNM file declares in its header, read
/// without decoding it. Throws pcr::InputError naming `source` when `bytes` are none of these or
/// their header is truncated.
std::pair<int, int> image_header_size(const std::vector<unsigned char>& bytes,
                                      const std::string& source);

/// Reads an 8- or 16-bit grey or colour PNG, JPEG, TIFF, BMP or PNM image; colour is converted
/// to grey. Throws pcr::InputError naming the file when it cannot be read, when its header
/// declares more than kMaxImagePixels (checked before decoding: a few hundred compressed bytes
/// can unpack to gigabytes) or when it has no contrast (blank).
GrayImage read_image(const std::string& path);

/// Writes a PNG with 8 or 16 bits per pixel (temporary file, then renamed).
void write_png(const GrayImage& image, const std::string& path, int bits = 8);

}  // namespace pcr::vision
