#include "pcr/files.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <cerrno>
#include <climits>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <mutex>
#include <stdexcept>
#include <utility>
#include <vector>

#include "pcr/robot_io.hpp"  // InputError

namespace pcr {
namespace {

std::string error_text() { return std::strerror(errno); }

/// The innermost OutputTransaction alive on this thread.
thread_local OutputTransaction* current_transaction = nullptr;

// ---- the inputs of this process ---------------------------------------------------------------
struct FileIdentity {
  dev_t device;
  ino_t inode;
  std::string path;
};

std::mutex& inputs_mutex() {
  static std::mutex mutex;
  return mutex;
}

std::atomic<bool> inputs_protected{false};

std::vector<FileIdentity>& inputs() {
  static std::vector<FileIdentity> files;
  return files;
}

/// The input `path` is (by device and inode), if any.
const FileIdentity* input_at(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) return nullptr;
  for (const FileIdentity& input : inputs()) {
    if (input.device == st.st_dev && input.inode == st.st_ino) return &input;
  }
  return nullptr;
}

void refuse_input_as_output(const std::string& path) {
  std::lock_guard<std::mutex> lock(inputs_mutex());
  if (const FileIdentity* input = input_at(path)) {
    throw InputError(path + ": is also an input of this command (" + input->path +
                     "): refusing to write over it");
  }
}

/// Whether two output paths name the same file: "-" (stdout) only itself; by device and inode
/// when both exist, else by their weakly canonical paths (symbolic links and `..` resolved). A
/// character device (/dev/null) takes any number of outputs.
bool same_output(const std::string& a, const std::string& b) {
  if (a == "-" || b == "-") return a == b;
  struct stat sa {};
  struct stat sb {};
  if (::stat(a.c_str(), &sa) == 0 && ::stat(b.c_str(), &sb) == 0) {
    return sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino && !S_ISCHR(sa.st_mode);
  }
  namespace fs = std::filesystem;
  std::error_code ea, eb;
  const fs::path ca = fs::weakly_canonical(fs::absolute(a, ea), ea);
  const fs::path cb = fs::weakly_canonical(fs::absolute(b, eb), eb);
  if (ea || eb) return fs::path(a).lexically_normal() == fs::path(b).lexically_normal();
  return ca == cb;
}

// ---- temporaries removed on a signal -----------------------------------------------------------
// Fixed storage: the handler may only call async-signal-safe functions (unlink), no allocation.
constexpr int kSlots = 32;
struct Slot {
  std::atomic<bool> used{false};
  char path[PATH_MAX];
};
std::array<Slot, kSlots> slots;

extern "C" void remove_temporaries_and_reraise(int signal) {
  for (Slot& slot : slots) {
    if (slot.used.load()) ::unlink(slot.path);
  }
  std::signal(signal, SIG_DFL);
  std::raise(signal);
}

/// Installs the handler for the signals that end a run from outside, where nobody else has one
/// (an embedding interpreter, say Python, keeps its own).
void install_signal_cleanup() {
  static std::once_flag once;
  std::call_once(once, [] {
    for (const int signal : {SIGINT, SIGTERM, SIGHUP}) {
      struct sigaction current {};
      if (::sigaction(signal, nullptr, &current) == 0 && current.sa_handler == SIG_DFL) {
        struct sigaction action {};
        action.sa_handler = remove_temporaries_and_reraise;
        sigemptyset(&action.sa_mask);
        ::sigaction(signal, &action, nullptr);
      }
    }
  });
}

int register_temporary(const std::string& path) {
  if (path.size() >= PATH_MAX) return -1;
  for (int i = 0; i < kSlots; ++i) {
    bool expected = false;
    if (slots[i].used.load()) continue;
    std::memcpy(slots[i].path, path.c_str(), path.size() + 1);
    if (slots[i].used.compare_exchange_strong(expected, true)) return i;
  }
  return -1;  // not removed on a signal, still removed on every other exit
}

void release_temporary(int slot) {
  if (slot >= 0) slots[slot].used.store(false);
}

/// The extension of the last component of `path` (".png"), or "".
std::string extension_of(const std::string& path) {
  const std::size_t slash = path.find_last_of('/');
  const std::size_t dot = path.find_last_of('.');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash) ||
      dot == (slash == std::string::npos ? 0 : slash + 1)) {
    return "";
  }
  return path.substr(dot);
}

}  // namespace

void check_input_file(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) {
    throw InputError(path + ": cannot open for reading: " + error_text());
  }
  if (S_ISDIR(st.st_mode)) throw InputError(path + ": is a directory, not a file");
  if (::access(path.c_str(), R_OK) != 0) {
    throw InputError(path + ": cannot open for reading: " + error_text());
  }
  if (!inputs_protected.load()) return;
  std::lock_guard<std::mutex> lock(inputs_mutex());
  if (input_at(path) == nullptr) inputs().push_back({st.st_dev, st.st_ino, path});
}

void protect_inputs() { inputs_protected.store(true); }

void check_distinct_outputs(const std::vector<std::pair<std::string, std::string>>& outputs) {
  for (std::size_t j = 0; j < outputs.size(); ++j) {
    const auto& [option, path] = outputs[j];
    if (path.empty()) continue;
    for (std::size_t i = 0; i < j; ++i) {
      const auto& [first_option, first_path] = outputs[i];
      if (first_path.empty() || !same_output(first_path, path)) continue;
      throw InputError(option + " " + path + ": " +
                       (path == "-" ? std::string("stdout, as ") : "the same file as ") +
                       first_option + " " + first_path +
                       "; each output needs a file of its own (nothing was written)");
    }
  }
}

std::ifstream open_input_file(const std::string& path, std::ios::openmode mode) {
  check_input_file(path);
  std::ifstream in(path, mode | std::ios::in);
  if (!in) throw InputError(path + ": cannot open for reading: " + error_text());
  return in;
}

std::string read_input_file(const std::string& path, std::size_t max_bytes,
                            const std::string& what) {
  std::ifstream in = open_input_file(path);
  std::string text;
  char block[1 << 16];
  while (in) {
    in.read(block, sizeof block);
    text.append(block, static_cast<std::size_t>(in.gcount()));
    if (text.size() > max_bytes) {
      throw InputError(path + ": more than the " + std::to_string(max_bytes >> 20) + " MiB " +
                       what + " can be; is this the right file?");
    }
  }
  if (in.bad()) throw InputError(path + ": read error: " + error_text());
  return text;
}

OutputFile::OutputFile(const std::string& path, Writer writer, const std::string& default_extension)
    : path_(path) {
  if (path.empty() || path == "-") {
    if (writer == Writer::kExternal) throw InputError("this output cannot be stdout ('-')");
    to_stdout_ = true;
    return;
  }
  struct stat target {};
  const bool exists = ::stat(path.c_str(), &target) == 0;
  if (exists && S_ISDIR(target.st_mode)) throw InputError(path + ": is a directory, not a file");
  refuse_input_as_output(path);
  // Inside a transaction, two outputs over one file would leave only the last one's content.
  for (OutputTransaction* t = current_transaction; t != nullptr; t = t->outer_) {
    for (const std::string& other : t->claimed_) {
      if (same_output(other, path)) {
        throw InputError(path + ": the same file as another output of this command (" + other +
                         "); each output needs a file of its own");
      }
    }
  }
  if (current_transaction != nullptr) current_transaction->claimed_.push_back(path);
  // Through a symbolic link, the file it names is replaced and the link stays.
  destination_ = path;
  struct stat link {};
  if (::lstat(path.c_str(), &link) == 0 && S_ISLNK(link.st_mode)) {
    if (char* resolved = ::realpath(path.c_str(), nullptr)) {
      destination_ = resolved;
      std::free(resolved);
    }
  }
  // A unique, hidden name next to the destination, so that rename() stays on one filesystem and
  // no file of the user's is touched; the target's extension last, for writers that go by it.
  const std::size_t slash = destination_.find_last_of('/');
  const std::string directory = slash == std::string::npos ? "" : destination_.substr(0, slash + 1);
  const std::string base =
      slash == std::string::npos ? destination_ : destination_.substr(slash + 1);
  std::string extension = extension_of(path);
  if (extension.empty()) extension = default_extension;
  std::string pattern = directory + "." + base + ".tmp-XXXXXX" + extension;
  std::vector<char> name(pattern.begin(), pattern.end());
  name.push_back('\0');
  install_signal_cleanup();
  const int fd = ::mkstemps(name.data(), static_cast<int>(extension.size()));
  if (fd < 0) {
    throw std::runtime_error(path + ": cannot create a temporary file next to it: " + error_text());
  }
  temp_path_ = name.data();
  slot_ = register_temporary(temp_path_);
  // mkstemp creates the file 0600: give it the existing file's mode, or what open() would.
  mode_t mode = 0;
  if (exists && S_ISREG(target.st_mode)) {
    mode = target.st_mode & 07777;
  } else {
    const mode_t mask = ::umask(0);
    ::umask(mask);
    mode = 0666 & ~mask;
  }
  ::fchmod(fd, mode);
  ::close(fd);
  if (writer == Writer::kStream) {
    file_.open(temp_path_, std::ios::out | std::ios::trunc | std::ios::binary);
    if (!file_) {
      ::unlink(temp_path_.c_str());
      release_temporary(slot_);
      throw std::runtime_error(path + ": cannot open " + temp_path_ + " for writing");
    }
  }
}

OutputFile::~OutputFile() {
  if (!to_stdout_ && !committed_) {
    if (file_.is_open()) file_.close();
    ::unlink(temp_path_.c_str());
  }
  release_temporary(slot_);
}

std::ostream& OutputFile::stream() { return to_stdout_ ? std::cout : file_; }

namespace {

/// Puts a written temporary in place of `path` (which resolves to `destination`).
void put_in_place(const std::string& path, const std::string& destination,
                  const std::string& temp_path) {
  refuse_input_as_output(path);
  struct stat target {};
  if (::stat(path.c_str(), &target) == 0 && !S_ISREG(target.st_mode)) {
    if (S_ISDIR(target.st_mode)) throw InputError(path + ": is a directory, not a file");
    // A device, FIFO or socket: written in place; a rename would replace it by a regular file.
    std::ifstream in(temp_path, std::ios::binary);
    std::ofstream out(path, std::ios::binary | std::ios::out);
    if (!out) throw std::runtime_error(path + ": cannot open for writing: " + error_text());
    out << in.rdbuf();
    out.flush();
    if (!out) throw std::runtime_error(path + ": write error: " + error_text());
    out.close();
    ::unlink(temp_path.c_str());
    return;
  }
  if (std::rename(temp_path.c_str(), destination.c_str()) != 0) {
    throw std::runtime_error(path + ": cannot rename " + temp_path + " over it: " + error_text());
  }
}

}  // namespace

void OutputFile::commit() {
  if (committed_) return;
  if (to_stdout_) {
    std::cout.flush();
    if (!std::cout) throw std::runtime_error("<stdout>: write error");
    committed_ = true;
    return;
  }
  if (file_.is_open()) {
    file_.flush();
    file_.close();
    if (file_.fail()) throw std::runtime_error(path_ + ": write error on " + temp_path_);
  }
  if (current_transaction != nullptr) {
    refuse_input_as_output(path_);  // early: the transaction checks again before it commits
    current_transaction->pending_.push_back({path_, destination_, temp_path_, slot_});
    slot_ = -1;  // the transaction's now
  } else {
    put_in_place(path_, destination_, temp_path_);
    release_temporary(slot_);
    slot_ = -1;
  }
  committed_ = true;
}

OutputTransaction::OutputTransaction() : outer_(current_transaction) { current_transaction = this; }

OutputTransaction::~OutputTransaction() {
  current_transaction = outer_;
  if (committed_) return;
  for (const Pending& file : pending_) {
    ::unlink(file.temp_path.c_str());
    release_temporary(file.slot);
  }
}

void OutputTransaction::commit() {
  if (committed_) return;
  current_transaction = outer_;
  if (outer_ != nullptr) {
    for (Pending& file : pending_) outer_->pending_.push_back(std::move(file));
    pending_.clear();
    for (std::string& path : claimed_) outer_->claimed_.push_back(std::move(path));
    claimed_.clear();
    committed_ = true;
    return;
  }
  // Everything that can be checked first is; then the files go in place.
  for (const Pending& file : pending_) {
    refuse_input_as_output(file.path);
    struct stat target {};
    if (::stat(file.path.c_str(), &target) == 0 && S_ISDIR(target.st_mode)) {
      throw InputError(file.path + ": is a directory, not a file");
    }
  }
  for (std::size_t i = 0; i < pending_.size(); ++i) {
    put_in_place(pending_[i].path, pending_[i].destination, pending_[i].temp_path);
    release_temporary(pending_[i].slot);
    pending_[i].slot = -1;
    pending_[i].temp_path.clear();
  }
  committed_ = true;
}

void write_file_atomically(const std::string& path, const std::string& text) {
  if (path.empty()) throw std::invalid_argument("write_file_atomically: empty path");
  OutputFile out(path);
  out.stream() << text;
  out.commit();
}

}  // namespace pcr
