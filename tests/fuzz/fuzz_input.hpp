#pragma once
// What every fuzz target shares. A target feeds libFuzzer's bytes to one parser: an InputError is
// the parser's answer to a bad file and ends the run normally; anything else (another exception,
// a crash, a sanitizer report, a hang) is a bug libFuzzer keeps as a reproducer.

#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

namespace pcr::fuzz {

/// The input as text.
inline std::string as_text(const std::uint8_t* data, std::size_t size) {
  return std::string(reinterpret_cast<const char*>(data), size);
}

/// The input written to a file, for the loaders that take a path (they check the file first):
/// one file per process in $TMPDIR, rewritten for every input and removed at exit.
inline const std::string& as_file(const std::uint8_t* data, std::size_t size, const char* suffix) {
  static const std::string path = [suffix] {
    const char* dir = std::getenv("TMPDIR");
    std::string name = std::string(dir && *dir ? dir : "/tmp") + "/pcr-fuzz-XXXXXX" + suffix;
    const int fd = mkstemps(name.data(), static_cast<int>(std::string(suffix).size()));
    if (fd < 0) std::abort();
    close(fd);
    static std::string to_remove;
    to_remove = name;
    std::atexit([] { std::remove(to_remove.c_str()); });
    return name;
  }();
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (f == nullptr || std::fwrite(data, 1, size, f) != size || std::fclose(f) != 0) std::abort();
  return path;
}

}  // namespace pcr::fuzz
