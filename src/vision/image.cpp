#include "pcr/vision/image.hpp"

#include <cstdio>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "pcr/files.hpp"
#include "pcr/robot_io.hpp"

namespace pcr::vision {

GrayImage read_image(const std::string& path) {
  check_input_file(path);
  const cv::Mat raw = cv::imread(path, cv::IMREAD_ANYDEPTH | cv::IMREAD_ANYCOLOR);
  if (raw.empty()) throw InputError(path + ": cannot read the image (missing or not an image)");
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
