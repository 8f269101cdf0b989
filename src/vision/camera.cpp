#include "pcr/vision/camera.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>
#include <string_view>

#include "pcr/files.hpp"
#include "pcr/robot_io.hpp"
#include "pcr/vision/image.hpp"

namespace pcr::vision {

namespace {

// OpenCV's distortion of normalised coordinates (rational radial + tangential).
Eigen::Vector2d distort(const Eigen::VectorXd& d, const Eigen::Vector2d& p) {
  const auto c = [&](int i) { return i < d.size() ? d[i] : 0.0; };
  const double x = p.x(), y = p.y(), r2 = x * x + y * y, r4 = r2 * r2, r6 = r4 * r2;
  const double radial =
      (1 + c(0) * r2 + c(1) * r4 + c(4) * r6) / (1 + c(5) * r2 + c(6) * r4 + c(7) * r6);
  return {x * radial + 2 * c(2) * x * y + c(3) * (r2 + 2 * x * x),
          y * radial + c(2) * (r2 + 2 * y * y) + 2 * c(3) * x * y};
}

}  // namespace

Eigen::Vector2d CameraModel::project_normalized(const Eigen::Vector2d& xn) const {
  const Eigen::Vector2d xd = distort(distortion, xn);
  return {K(0, 0) * xd.x() + K(0, 1) * xd.y() + K(0, 2), K(1, 1) * xd.y() + K(1, 2)};
}

Eigen::Vector2d CameraModel::normalize(const Eigen::Vector2d& pixel) const {
  const double yd = (pixel.y() - K(1, 2)) / K(1, 1);
  const double xd = (pixel.x() - K(0, 2) - K(0, 1) * yd) / K(0, 0);
  const Eigen::Vector2d target(xd, yd);
  Eigen::Vector2d p = target;
  // Newton on distort(p) = target with a finite-difference Jacobian; converges in a few steps for
  // any lens OpenCV can calibrate.
  for (int it = 0; it < 30; ++it) {
    const Eigen::Vector2d r = distort(distortion, p) - target;
    if (r.norm() < 1e-15) break;
    constexpr double h = 1e-7;
    Eigen::Matrix2d J;
    J.col(0) = (distort(distortion, p + Eigen::Vector2d(h, 0)) -
                distort(distortion, p - Eigen::Vector2d(h, 0))) /
               (2 * h);
    J.col(1) = (distort(distortion, p + Eigen::Vector2d(0, h)) -
                distort(distortion, p - Eigen::Vector2d(0, h))) /
               (2 * h);
    p -= J.partialPivLu().solve(r);
  }
  return p;
}

Eigen::Vector2d CameraModel::project(const Eigen::Vector3d& pc) const {
  return project_normalized(Eigen::Vector2d(pc.x() / pc.z(), pc.y() / pc.z()));
}

PlanePose PlanePose::looking_down(double height_m, double tilt_x, double tilt_y) {
  PlanePose pose;
  // Camera z down onto the plane, image x = plane x, image down = plane -y.
  const Eigen::Matrix3d base = Eigen::Vector3d(1, -1, -1).asDiagonal();
  pose.rotation = (Eigen::AngleAxisd(tilt_x, Eigen::Vector3d::UnitX()) *
                   Eigen::AngleAxisd(tilt_y, Eigen::Vector3d::UnitY()))
                      .toRotationMatrix() *
                  base;
  pose.translation = Eigen::Vector3d(0, 0, height_m);
  return pose;
}

namespace {

// OpenCV 4.6's YAML reader crashes, throws std::length_error, allocates without bound or loops
// forever on malformed text (`---%YAML:1.0` then `--`-` hangs it; tests/fuzz/fuzz_camera found
// these): it only ever sees a file in the shape OpenCV's writers give a camera. That shape, line by
// line: an optional YAML directive on line 1 (`%YAML:1.0` from OpenCV 4, `%YAML 1.2` from OpenCV
// 5; any of 1.0, 1.1, 1.2, with a colon or a space) and a lone `---` on line 1 or 2; comments;
// top-level `key: scalar` (a number, a word or a quoted string) or `key: !!opencv-matrix` followed
// by its indented `rows`, `cols`, `dt` and `data: [ numbers ]`, the list possibly spread over
// lines; optionally a lone `...` ending the document, with nothing but comments after it.
class CameraText {
 public:
  explicit CameraText(const std::string& path) : path_(path) {}

  /// Throws InputError naming the first line out of shape. Returns the text as OpenCV 4.6's reader
  /// takes it, with the same lines: line 1 the directive it knows (`%YAML:1.0`; prepended to a
  /// file without one, which 4.6 would not recognise as YAML), the document end marker blanked.
  std::string check(const std::string& text) {
    text_begin_ = text.data();
    std::size_t start = 0;
    for (line_ = 1; start < text.size(); ++line_) {
      std::size_t end = text.find('\n', start);
      if (end == std::string::npos) end = text.size();
      check_line(std::string_view(text.data() + start, end - start));
      start = end + 1;
    }
    if (in_list_) fail("the 'data' list is not closed with ']'");
    end_matrix();
    std::string out = text;
    if (end_marker_ != std::string::npos) out.replace(end_marker_, 3, "   ");
    if (has_directive_) return out.replace(0, out.find('\n'), "%YAML:1.0");
    return "%YAML:1.0\n" + out;
  }

 private:
  static constexpr std::size_t kMaxLine = 4096;

  using View = std::string_view;

  [[noreturn]] void fail(const std::string& why) const {
    throw InputError(path_ + ":" + std::to_string(line_) + ": " + why +
                     " (pcr reads the camera YAML OpenCV writes)");
  }

  static View trim(View s) {
    const std::size_t b = s.find_first_not_of(' ');
    if (b == View::npos) return {};
    return s.substr(b, s.find_last_not_of(' ') - b + 1);
  }

  static bool digits(View& s) {  // consumes [0-9]+
    std::size_t n = 0;
    while (n < s.size() && s[n] >= '0' && s[n] <= '9') ++n;
    s.remove_prefix(n);
    return n > 0;
  }

  // [+-]? (digits [. digits*] | . digits) [eE [+-]? digits], or YAML's .inf / .nan.
  static bool is_number(View s) {
    if (!s.empty() && (s[0] == '+' || s[0] == '-')) s.remove_prefix(1);
    std::string lower(s);
    for (char& c : lower) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    if (lower == ".inf" || lower == ".nan") return true;
    const bool whole = digits(s);
    bool fraction = false;
    if (!s.empty() && s[0] == '.') {
      s.remove_prefix(1);
      fraction = digits(s);
    }
    if (!whole && !fraction) return false;
    if (!s.empty() && (s[0] == 'e' || s[0] == 'E')) {
      s.remove_prefix(1);
      if (!s.empty() && (s[0] == '+' || s[0] == '-')) s.remove_prefix(1);
      if (!digits(s)) return false;
    }
    return s.empty();
  }

  static bool is_word(View s) {
    if (s.empty() || s.size() > 256 ||
        !(std::isalpha(static_cast<unsigned char>(s[0])) || s[0] == '_'))
      return false;
    for (const char c : s)
      if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_' && c != '.' && c != '-' &&
          c != '+' && c != '/')
        return false;
    return true;
  }

  static bool is_quoted(View s) {
    if (s.size() < 2 || s.size() > 258 || (s[0] != '"' && s[0] != '\'') || s.back() != s[0])
      return false;
    for (const char c : s.substr(1, s.size() - 2))
      if (c == '"' || c == '\'' || c == '\\') return false;
    return true;
  }

  // The numbers of a flow list after its '[' or on a continuation line; sets in_list_.
  void list_items(View s) {
    for (bool first = true;; first = false) {
      const std::size_t comma = s.find(',');
      View item = trim(s.substr(0, comma));
      if (comma == View::npos) {
        if (item.empty() || item.back() != ']') fail("a line of the 'data' list ends without ','");
        item = trim(item.substr(0, item.size() - 1));
        if (!(item.empty() && first && list_empty_)) {
          if (!is_number(item)) fail("'" + excerpt(std::string(item)) + "' is not a number");
        }
        in_list_ = false;
        return;
      }
      s.remove_prefix(comma + 1);
      if (!is_number(item)) fail("'" + excerpt(std::string(item)) + "' is not a number");
      list_empty_ = false;
      if (trim(s).empty()) return;  // the list goes on on the next line
    }
  }

  void end_matrix() {
    if (in_matrix_ && matrix_fields_ != 0xf)
      fail("the opencv-matrix above lacks one of rows, cols, dt, data");
    in_matrix_ = false;
  }

  void check_line(View raw) {
    if (raw.size() > kMaxLine) fail("a line longer than " + std::to_string(kMaxLine) + " bytes");
    if (!raw.empty() && raw.back() == '\r') raw.remove_suffix(1);
    for (const char c : raw)
      if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f)
        fail("a control character (tabs included: YAML indents with spaces)");
    const std::size_t indent = std::min(raw.find_first_not_of(' '), raw.size());
    const View text = trim(raw);
    if (in_list_) {
      if (indent == 0 || text.empty()) fail("the 'data' list is not closed with ']'");
      list_items(text);
      return;
    }
    if (text.empty() || text[0] == '#') return;
    if (ended_) fail("'" + excerpt(std::string(text)) + "' after the end of the document ('...')");
    if (text[0] == '%' || text.substr(0, 3) == "---" || text.substr(0, 3) == "...") {
      const bool directive = line_ == 1 && is_directive(raw);
      const bool start = raw == "---" && line_ <= 2 && !seen_content_;
      if (raw == "..." && seen_content_) {
        ended_ = true;
        end_marker_ = static_cast<std::size_t>(raw.data() - text_begin_);
        return;
      }
      if (!directive && !start) {
        fail("'" + excerpt(std::string(text)) +
             "': only line 1 may be a YAML directive ('%YAML:1.0' as OpenCV 4 writes it, "
             "'%YAML 1.2' as OpenCV 5 does), only line 1 or 2 a lone '---' and only the last "
             "line a lone '...'");
      }
      has_directive_ = has_directive_ || directive;
      return;
    }
    seen_content_ = true;
    const std::size_t colon = text.find(':');
    if (colon == View::npos || colon == 0 || colon > 64 || !is_word(text.substr(0, colon)) ||
        (colon + 1 < text.size() && text[colon + 1] != ' ')) {
      fail("'" + excerpt(std::string(text)) + "' is not a 'key: value' line");
    }
    const View key = text.substr(0, colon), value = trim(text.substr(colon + 1));
    if (indent == 0) {
      end_matrix();
      if (value == "!!opencv-matrix") {
        in_matrix_ = true;
        matrix_fields_ = 0;
        matrix_indent_ = 0;
      } else if (!is_number(value) && !is_word(value) && !is_quoted(value)) {
        fail("'" + excerpt(std::string(key)) +
             "' is neither a number, a word, a quoted string nor an opencv-matrix");
      }
      return;
    }
    if (!in_matrix_) fail("an indented line outside an opencv-matrix");
    if (matrix_indent_ == 0) matrix_indent_ = indent;
    if (indent != matrix_indent_) fail("the opencv-matrix's fields are not indented alike");
    static constexpr View kFields[] = {"rows", "cols", "dt", "data"};
    const auto field = std::find(std::begin(kFields), std::end(kFields), key) - std::begin(kFields);
    if (field == 4) fail("'" + std::string(key) + "' is not a field of an opencv-matrix");
    if (matrix_fields_ & (1 << field)) fail("'" + std::string(key) + "' given twice");
    matrix_fields_ |= 1 << field;
    View v = value;
    if (field < 2) {
      if (!digits(v) || !v.empty() || value.size() > 9)
        fail("'" + std::string(key) + ": " + excerpt(std::string(value)) + "' is not a count");
    } else if (field == 2) {
      if (v.size() >= 2 && v[0] == '"' && v.back() == '"') v = v.substr(1, v.size() - 2);
      digits(v);
      if (v.size() != 1 || View("ucwsifdhr").find(v[0]) == View::npos)
        fail("'dt: " + excerpt(std::string(value)) + "' is not an OpenCV element type");
    } else {
      if (v.empty() || v[0] != '[') fail("'data' does not open a list with '['");
      in_list_ = list_empty_ = true;
      list_items(v.substr(1));
    }
  }

  /// `%YAML:1.N` (OpenCV 4) or `%YAML 1.N` (OpenCV 5), N = 0, 1, 2: the YAML versions whose
  /// syntax OpenCV's reader shares (it refuses other majors).
  static bool is_directive(View line) {
    return line.size() == 9 && line.substr(0, 5) == "%YAML" && (line[5] == ':' || line[5] == ' ') &&
           line.substr(6, 2) == "1." && line[8] >= '0' && line[8] <= '2';
  }

  const std::string& path_;
  const char* text_begin_ = nullptr;
  int line_ = 0;
  bool seen_content_ = false;
  bool has_directive_ = false;
  bool ended_ = false;                          ///< after a `...` line
  std::size_t end_marker_ = std::string::npos;  ///< offset of the `...` line
  bool in_list_ = false, list_empty_ = false;
  bool in_matrix_ = false;
  unsigned matrix_fields_ = 0;  // bit k: kFields[k] seen
  std::size_t matrix_indent_ = 0;
};

CameraModel read_camera(const std::string& path) {
  // OpenCV's calibration output with every view's points is a few MB at most.
  constexpr std::size_t kMaxBytes = std::size_t{64} << 20;
  const std::string text =
      CameraText(path).check(read_input_file(path, kMaxBytes, "a camera file"));
  cv::FileStorage fs(text, cv::FileStorage::READ | cv::FileStorage::MEMORY);
  if (!fs.isOpened()) throw InputError(path + ": cannot parse the camera file");
  CameraModel camera;
  const auto need = [&](const char* key) {
    cv::FileNode node = fs[key];
    if (node.empty()) throw InputError(path + ": missing field '" + key + "'");
    return node;
  };
  const auto read_int = [&](const char* key) {
    cv::FileNode node = need(key);
    if (!node.isInt() && !node.isReal())
      throw InputError(path + ": field '" + key + "' is not a number");
    const double v = static_cast<double>(node);
    if (!(v >= 1 && v <= 100000) || v != std::floor(v)) {
      throw InputError(path + ": field '" + key + "' = " + std::to_string(v) +
                       " is not a valid size in px");
    }
    return static_cast<int>(v);
  };
  camera.width = read_int("image_width");
  camera.height = read_int("image_height");
  if (static_cast<long long>(camera.width) * camera.height > kMaxImagePixels) {
    throw InputError(path + ": image_width x image_height = " + std::to_string(camera.width) +
                     " x " + std::to_string(camera.height) + " px is more than the " +
                     std::to_string(kMaxImagePixels / 1000000) + " Mpx pcr handles");
  }
  // A matrix's size is checked before OpenCV allocates it: `rows` and `cols` are the file's word.
  const auto matrix = [&](const char* key, int max_values) {
    const cv::FileNode node = need(key);
    const cv::FileNode rows = node["rows"], cols = node["cols"];
    if (!node.isMap() || !rows.isInt() || !cols.isInt() || static_cast<int>(rows) < 0 ||
        static_cast<int>(cols) < 0 ||
        static_cast<long long>(static_cast<int>(rows)) * static_cast<int>(cols) > max_values) {
      throw InputError(path + ": field '" + key + "' is not an opencv-matrix of at most " +
                       std::to_string(max_values) + " values (rows, cols, dt, data)");
    }
    cv::Mat m;
    try {
      node >> m;
    } catch (const cv::Exception& e) {
      throw InputError(path + ": field '" + key + "' is not a matrix (" + e.what() + ")");
    }
    return m;
  };
  cv::Mat K = matrix("camera_matrix", 9), D = matrix("distortion_coefficients", 14);
  if (K.rows != 3 || K.cols != 3) {
    throw InputError(path + ": field 'camera_matrix' must be 3x3, got " + std::to_string(K.rows) +
                     "x" + std::to_string(K.cols));
  }
  K.convertTo(K, CV_64F);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) camera.K(r, c) = K.at<double>(r, c);
  const int n = static_cast<int>(D.total());
  if (!(n == 0 || n == 4 || n == 5 || n == 8)) {
    throw InputError(path +
                     ": field 'distortion_coefficients' must hold 0, 4, 5 or 8 values, got " +
                     std::to_string(n));
  }
  D.convertTo(D, CV_64F);
  camera.distortion = Eigen::VectorXd::Zero(std::max(n, 5));
  for (int i = 0; i < n; ++i) camera.distortion[i] = D.ptr<double>()[i];
  if (!camera.K.allFinite() || !camera.distortion.allFinite()) {
    throw InputError(path + ": non-finite value in camera_matrix or distortion_coefficients");
  }
  if (!(camera.K(0, 0) > 0) || !(camera.K(1, 1) > 0) || camera.K(1, 0) != 0 ||
      camera.K(2, 0) != 0 || camera.K(2, 1) != 0 || camera.K(2, 2) != 1) {
    throw InputError(path +
                     ": field 'camera_matrix' is not an intrinsic matrix [fx s cx; 0 fy cy; 0 0 1] "
                     "with fx, fy > 0");
  }
  if (camera.K(0, 2) < 0 || camera.K(0, 2) > camera.width || camera.K(1, 2) < 0 ||
      camera.K(1, 2) > camera.height) {
    throw InputError(
        path + ": principal point (" + std::to_string(camera.K(0, 2)) + ", " +
        std::to_string(camera.K(1, 2)) + ") lies outside the image_width x image_height = " +
        std::to_string(camera.width) + " x " + std::to_string(camera.height) + " image");
  }
  return camera;
}

}  // namespace

CameraModel load_camera(const std::string& path) {
  check_input_file(path);
  // OpenCV's reader reports a malformed file with cv::Exception, and with std::length_error
  // where it mis-sizes a string (found by tests/fuzz/fuzz_camera): all are the file's fault.
  try {
    return read_camera(path);
  } catch (const InputError&) {
    throw;
  } catch (const std::exception& e) {
    throw InputError(path + ": cannot parse the camera file (" + e.what() + ")");
  }
}

void save_camera(const CameraModel& camera, const std::string& path, double rms_px) {
  OutputFile file(path, OutputFile::Writer::kExternal, ".yaml");
  {
    cv::FileStorage fs(file.temp_path(), cv::FileStorage::WRITE);
    if (!fs.isOpened()) throw std::runtime_error(path + ": cannot write the camera file");
    cv::Mat K(3, 3, CV_64F), D(1, static_cast<int>(camera.distortion.size()), CV_64F);
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) K.at<double>(r, c) = camera.K(r, c);
    for (int i = 0; i < camera.distortion.size(); ++i) D.at<double>(0, i) = camera.distortion[i];
    fs << "image_width" << camera.width << "image_height" << camera.height << "camera_matrix" << K
       << "distortion_coefficients" << D;
    if (rms_px >= 0) fs << "avg_reprojection_error" << rms_px;
  }
  file.commit();
}

void check_image_size(const CameraModel& camera, int width, int height,
                      const std::string& camera_source, const std::string& image_source) {
  if (width != camera.width || height != camera.height) {
    throw InputError(image_source + ": image is " + std::to_string(width) + " x " +
                     std::to_string(height) + " px but the camera file " + camera_source +
                     " describes image_width x image_height = " + std::to_string(camera.width) +
                     " x " + std::to_string(camera.height));
  }
}

std::pair<int, int> parse_board_size(const std::string& text, const std::string& option) {
  const auto count = [](std::string_view digits, int* value) {
    if (digits.empty() || digits.size() > 3) return false;
    *value = 0;
    for (const char c : digits) {
      if (c < '0' || c > '9') return false;
      *value = 10 * *value + (c - '0');
    }
    return *value >= 2 && *value <= 100;
  };
  const std::size_t x = text.find('x');
  int cols = 0, rows = 0;
  if (x == std::string::npos || !count(std::string_view(text).substr(0, x), &cols) ||
      !count(std::string_view(text).substr(x + 1), &rows)) {
    throw InputError(option + ": expected COLSxROWS (inner corners, 2 to 100 each), got '" +
                     excerpt(text) + "'");
  }
  return {cols, rows};
}

CalibrationResult calibrate_camera(const std::vector<std::string>& image_paths,
                                   const ChessboardSpec& board) {
  if (board.cols < 2 || board.rows < 2 || !(board.square_m > 0)) {
    throw InputError("chessboard: need at least 2 x 2 inner corners and a positive square size");
  }
  CalibrationResult result;
  std::vector<std::vector<cv::Point3f>> object_points;
  std::vector<std::vector<cv::Point2f>> image_points;
  std::vector<cv::Point3f> board_points;
  for (int r = 0; r < board.rows; ++r)
    for (int c = 0; c < board.cols; ++c)
      board_points.emplace_back(static_cast<float>(c * board.square_m),
                                static_cast<float>(r * board.square_m), 0.f);
  cv::Size size;
  for (const std::string& path : image_paths) {
    const GrayImage image = read_image(path);
    if (size.width == 0) size = cv::Size(image.width, image.height);
    if (image.width != size.width || image.height != size.height) {
      throw InputError(path + ": image size " + std::to_string(image.width) + " x " +
                       std::to_string(image.height) + " differs from the first image's");
    }
    cv::Mat f(image.height, image.width, CV_32F, const_cast<float*>(image.pixels.data())), u8;
    f.convertTo(u8, CV_8U, 255.0);
    std::vector<cv::Point2f> corners;
    // FAST_CHECK: an image without the board (a wrong file) is rejected at once instead of
    // after minutes of adaptive-threshold search.
    const bool found = cv::findChessboardCorners(
        u8, cv::Size(board.cols, board.rows), corners,
        cv::CALIB_CB_ADAPTIVE_THRESH | cv::CALIB_CB_NORMALIZE_IMAGE | cv::CALIB_CB_FAST_CHECK);
    if (!found) {
      result.rejected.push_back(path);
      continue;
    }
    cv::cornerSubPix(u8, corners, cv::Size(5, 5), cv::Size(-1, -1),
                     cv::TermCriteria(cv::TermCriteria::EPS | cv::TermCriteria::COUNT, 100, 1e-4));
    image_points.push_back(corners);
    object_points.push_back(board_points);
    result.used.push_back(path);
  }
  if (image_points.size() < 3) {
    throw InputError("camera calibration: the board (" + std::to_string(board.cols) + " x " +
                     std::to_string(board.rows) + " inner corners) was found in only " +
                     std::to_string(image_points.size()) + " image(s), at least 3 are needed");
  }
  cv::Mat K, D;
  std::vector<cv::Mat> rvecs, tvecs;
  result.rms_px = cv::calibrateCamera(object_points, image_points, size, K, D, rvecs, tvecs);
  result.camera.width = size.width;
  result.camera.height = size.height;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) result.camera.K(r, c) = K.at<double>(r, c);
  result.camera.distortion = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(D.total()));
  for (int i = 0; i < static_cast<int>(D.total()); ++i)
    result.camera.distortion[i] = D.ptr<double>()[i];
  return result;
}

}  // namespace pcr::vision
