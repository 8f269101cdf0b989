#include "pcr/vision/image.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "pcr/files.hpp"
#include "pcr/robot_io.hpp"

namespace pcr::vision {

namespace {

std::uint32_t big_endian(const std::vector<unsigned char>& b, std::size_t at, int bytes) {
  std::uint32_t v = 0;
  for (int i = 0; i < bytes; ++i) v = (v << 8) | b[at + static_cast<std::size_t>(i)];
  return v;
}

std::uint32_t little_endian(const std::vector<unsigned char>& b, std::size_t at, int bytes) {
  std::uint32_t v = 0;
  for (int i = bytes - 1; i >= 0; --i) v = (v << 8) | b[at + static_cast<std::size_t>(i)];
  return v;
}

bool starts_with(const std::vector<unsigned char>& b, std::initializer_list<unsigned char> magic) {
  return b.size() >= magic.size() && std::equal(magic.begin(), magic.end(), b.begin());
}

/// JPEG: the frame header (SOF0..SOF15 but DHT, JPG and DAC) among the marker segments.
std::pair<long long, long long> jpeg_size(const std::vector<unsigned char>& b) {
  std::size_t at = 2;
  while (at + 4 <= b.size()) {
    if (b[at] != 0xFF) break;
    const unsigned char marker = b[at + 1];
    if (marker == 0xFF) {  // fill byte
      ++at;
      continue;
    }
    if (marker == 0xD8 || marker == 0x01 || (marker >= 0xD0 && marker <= 0xD7)) {
      at += 2;  // no length field
      continue;
    }
    if (marker == 0xD9 || marker == 0xDA) break;  // end of image, start of scan: no frame
    const std::size_t length = big_endian(b, at + 2, 2);
    const bool frame =
        marker >= 0xC0 && marker <= 0xCF && marker != 0xC4 && marker != 0xC8 && marker != 0xCC;
    if (frame && at + 9 <= b.size()) return {big_endian(b, at + 7, 2), big_endian(b, at + 5, 2)};
    if (length < 2) break;
    at += 2 + length;
  }
  return {-1, -1};
}

/// TIFF: ImageWidth (256) and ImageLength (257) of the first image file directory.
std::pair<long long, long long> tiff_size(const std::vector<unsigned char>& b) {
  const bool little = b[0] == 'I';
  const auto read = [&](std::size_t at, int bytes) {
    return little ? little_endian(b, at, bytes) : big_endian(b, at, bytes);
  };
  if (b.size() < 8) return {-1, -1};
  const std::size_t ifd = read(4, 4);
  if (ifd + 2 > b.size()) return {-1, -1};
  const std::size_t entries = read(ifd, 2);
  long long width = -1, height = -1;
  for (std::size_t e = 0; e < entries && ifd + 2 + 12 * (e + 1) <= b.size(); ++e) {
    const std::size_t at = ifd + 2 + 12 * e;
    const std::uint32_t tag = read(at, 2), type = read(at + 2, 2);
    const long long value = type == 3 ? read(at + 8, 2) : type == 4 ? read(at + 8, 4) : -1;
    if (tag == 256) width = value;
    if (tag == 257) height = value;
  }
  return {width, height};
}

/// PNM (P1..P6): magic, then width and height as decimal text, with # comments.
std::pair<long long, long long> pnm_size(const std::vector<unsigned char>& b) {
  std::size_t at = 2;
  long long numbers[2] = {-1, -1};
  for (long long& n : numbers) {
    while (at < b.size() && (std::isspace(b[at]) || b[at] == '#')) {
      if (b[at] == '#') {
        while (at < b.size() && b[at] != '\n') ++at;
      } else {
        ++at;
      }
    }
    if (at >= b.size() || !std::isdigit(b[at])) return {-1, -1};
    n = 0;
    while (at < b.size() && std::isdigit(b[at]) && n <= kMaxImagePixels)
      n = 10 * n + (b[at++] - '0');
    if (at >= b.size() || !std::isspace(b[at])) return {-1, -1};  // a number ends with a space
  }
  return {numbers[0], numbers[1]};
}

}  // namespace

std::pair<int, int> image_header_size(const std::vector<unsigned char>& bytes,
                                      const std::string& source) {
  std::pair<long long, long long> size{-1, -1};
  const char* format = nullptr;
  if (starts_with(bytes, {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'})) {
    format = "PNG";
    if (bytes.size() >= 24) size = {big_endian(bytes, 16, 4), big_endian(bytes, 20, 4)};
  } else if (starts_with(bytes, {0xFF, 0xD8})) {
    format = "JPEG";
    size = jpeg_size(bytes);
  } else if (starts_with(bytes, {'I', 'I', 42, 0}) || starts_with(bytes, {'M', 'M', 0, 42})) {
    format = "TIFF";
    size = tiff_size(bytes);
  } else if (starts_with(bytes, {'B', 'M'})) {
    format = "BMP";
    if (bytes.size() >= 26) {
      const auto height = static_cast<std::int32_t>(little_endian(bytes, 22, 4));
      size = {little_endian(bytes, 18, 4), std::abs(static_cast<long long>(height))};
    }
  } else if (bytes.size() >= 2 && bytes[0] == 'P' && bytes[1] >= '1' && bytes[1] <= '6') {
    format = "PNM";
    size = pnm_size(bytes);
  } else {
    throw InputError(source + ": not an image pcr reads (PNG, JPEG, TIFF, BMP or PNM)");
  }
  if (size.first <= 0 || size.second <= 0) {
    throw InputError(source + ": truncated or invalid " + format + " header");
  }
  if (size.first > kMaxImagePixels || size.second > kMaxImagePixels ||
      size.first * size.second > kMaxImagePixels) {
    throw InputError(source + ": its " + format + " header declares " + std::to_string(size.first) +
                     " x " + std::to_string(size.second) + " px, more than the " +
                     std::to_string(kMaxImagePixels / 1000000) + " Mpx pcr reads (not decoded)");
  }
  return {static_cast<int>(size.first), static_cast<int>(size.second)};
}

GrayImage read_image(const std::string& path) {
  check_input_file(path);
  // Read once, check the header's size, then decode from memory. A file larger than the
  // biggest image in its least compressed form (16-bit colour) is no image of the robot.
  std::ifstream in(path, std::ios::binary);
  std::vector<unsigned char> bytes;
  const std::uintmax_t file_size = std::filesystem::file_size(path);
  if (file_size > static_cast<std::uintmax_t>(8 * kMaxImagePixels)) {
    throw InputError(path + ": " + std::to_string(file_size) +
                     " bytes is larger than any image pcr reads");
  }
  bytes.resize(static_cast<std::size_t>(file_size));
  in.read(reinterpret_cast<char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  if (!in) throw InputError(path + ": cannot read the file");
  image_header_size(bytes, path);
  cv::Mat raw;
  try {
    raw = cv::imdecode(bytes, cv::IMREAD_ANYDEPTH | cv::IMREAD_ANYCOLOR);
  } catch (const cv::Exception& e) {
    throw InputError(path + ": cannot decode the image (" + e.what() + ")");
  }
  if (raw.empty()) throw InputError(path + ": cannot decode the image (corrupt or truncated)");
  cv::Mat gray = raw;
  if (raw.channels() == 3) cv::cvtColor(raw, gray, cv::COLOR_BGR2GRAY);
  if (raw.channels() == 4) cv::cvtColor(raw, gray, cv::COLOR_BGRA2GRAY);
  double scale = 1.0;
  switch (gray.depth()) {
    case CV_8U:
      scale = 1.0 / 255.0;
      break;
    case CV_16U:
      scale = 1.0 / 65535.0;
      break;
    case CV_32F:
      scale = 1.0;
      break;
    default:
      throw InputError(path + ": unsupported pixel depth");
  }
  cv::Mat f;
  gray.convertTo(f, CV_32F, scale);
  double lo = 0, hi = 0;
  cv::minMaxLoc(f, &lo, &hi);
  if (hi - lo < 0.05) {
    throw InputError(path + ": blank image (intensity range " + std::to_string(lo) + ".." +
                     std::to_string(hi) + ", no markers can be seen)");
  }
  GrayImage image(f.cols, f.rows);
  for (int v = 0; v < f.rows; ++v) {
    const float* row = f.ptr<float>(v);
    std::copy(row, row + f.cols, image.pixels.begin() + static_cast<std::ptrdiff_t>(v) * f.cols);
  }
  return image;
}

void write_png(const GrayImage& image, const std::string& path, int bits) {
  if (bits != 8 && bits != 16) throw std::invalid_argument("write_png: bits must be 8 or 16");
  cv::Mat f(image.height, image.width, CV_32F, const_cast<float*>(image.pixels.data()));
  cv::Mat out;
  if (bits == 8) {
    f.convertTo(out, CV_8U, 255.0);
  } else {
    f.convertTo(out, CV_16U, 65535.0);
  }
  OutputFile file(path, OutputFile::Writer::kExternal, ".png");
  if (!cv::imwrite(file.temp_path(), out)) {
    throw std::runtime_error(path + ": cannot write the image");
  }
  file.commit();
}

}  // namespace pcr::vision
