#pragma once
// Input and output files of the tools, compiled in pcr::io. The rules every command follows:
// - an input is opened through open_input_file / check_input_file, which refuse a directory or an
//   unreadable file with the file's name and the reason, and remember the file;
// - an output is an OutputFile: written to a temporary with a unique name next to it and renamed
//   over it by commit(), so a failed run leaves the old file as it was and no half-written one.
//   A target that is not a regular file (/dev/null, a FIFO, a terminal) is written in place
//   instead (a rename would replace the device by a regular file); a symbolic link is followed
//   (the link stays); "-" or "" is stdout, whose write errors commit() reports;
// - in a tool (after protect_inputs()), an output is never one of the process's inputs (compared by
//   device and inode, not by name);
// - the temporaries are removed on every exit: an exception, a dropped OutputFile, SIGINT, SIGTERM
//   or SIGHUP.
// Commands with several outputs check first that no two of them name the same file
// (check_distinct_outputs), then open an OutputTransaction: their files are put in place together
// when all were written, or none is; within one, a second OutputFile over the same file is refused.

#include <cstddef>
#include <fstream>
#include <ios>
#include <string>
#include <utility>
#include <vector>

namespace pcr {

/// From now on, this process remembers the files it reads and refuses to write an output over any
/// of them. For the command-line tools, whose run reads its inputs then writes its outputs; a
/// library user (a Python session that loads, edits and saves a robot) writes over what it read.
void protect_inputs();

/// Opens `path` for reading (InputError naming it when it is a directory, missing or unreadable)
/// and, after protect_inputs(), remembers it.
std::ifstream open_input_file(const std::string& path,
                              std::ios::openmode mode = std::ios::in | std::ios::binary);

/// The checks and the record of open_input_file, for readers that open the file themselves
/// (OpenCV's imread and FileStorage).
void check_input_file(const std::string& path);

/// The whole content of the input `path` (opened by open_input_file), read up to `max_bytes`: a
/// larger input (a wrong file, or an endless one such as /dev/zero or a FIFO that never closes)
/// is an InputError naming the file, `what` it should have been ("a robot description") and the
/// limit, after at most max_bytes + 1 bytes were read.
std::string read_input_file(const std::string& path, std::size_t max_bytes,
                            const std::string& what);

/// The size limit of each kind of input file (docs/formats.md): JSON descriptions (robot, mount
/// layout, stages) hold a few kB.
inline constexpr std::size_t kMaxJsonFileBytes = std::size_t{16} << 20;

/// The outputs a command is about to write, as (option, path) pairs such as
/// {{"--output", output}, {"--truth", truth}}, checked before anything is computed or written:
/// throws InputError naming both options and paths when two are the same file, by the same name or
/// by another (`./sub/../d.csv`, a symbolic or a hard link: compared by device and inode when both
/// exist, else as std::filesystem::weakly_canonical paths), or are both stdout ("-"). An empty path
/// (an output not asked for) is skipped; a character device (/dev/null) may take several. The rule
/// of every command with several outputs.
void check_distinct_outputs(const std::vector<std::pair<std::string, std::string>>& outputs);

class OutputFile {
 public:
  /// How the content reaches the temporary: through stream(), or written by another library to
  /// temp_path() (OpenCV's imwrite, which picks the format from the extension: the temporary's
  /// name ends with the target's extension).
  enum class Writer { kStream, kExternal };

  /// Creates the temporary (InputError when `path` is a directory or one of the inputs read so
  /// far; std::runtime_error when the directory is not writable). `default_extension` names the
  /// temporary of a target without one (/dev/null, say), for a writer that goes by it.
  explicit OutputFile(const std::string& path, Writer writer = Writer::kStream,
                      const std::string& default_extension = "");
  ~OutputFile();
  OutputFile(const OutputFile&) = delete;
  OutputFile& operator=(const OutputFile&) = delete;

  std::ostream& stream();
  /// The temporary's name (Writer::kExternal); empty for stdout.
  const std::string& temp_path() const { return temp_path_; }
  const std::string& path() const { return path_; }
  /// Puts the content in place: renamed over a regular file, copied into a special one, flushed
  /// to stdout. Throws std::runtime_error on a write error, InputError when the target has become
  /// one of the inputs.
  void commit();

 private:
  std::string path_;
  std::string destination_;  ///< path_, or the file it links to
  std::string temp_path_;
  std::ofstream file_;
  int slot_ = -1;  ///< in the registry of temporaries removed on a signal
  bool to_stdout_ = false;
  bool committed_ = false;
};

/// While one is alive (on this thread), OutputFile::commit() only hands its temporary over; the
/// transaction's commit() puts them all in place, and dropped uncommitted (an exception), it
/// removes them, leaving every target as it was. Transactions nest: an inner one hands its files
/// to the outer one on commit.
class OutputTransaction {
 public:
  OutputTransaction();
  ~OutputTransaction();
  OutputTransaction(const OutputTransaction&) = delete;
  OutputTransaction& operator=(const OutputTransaction&) = delete;
  void commit();

 private:
  friend class OutputFile;
  struct Pending {
    std::string path, destination, temp_path;
    int slot;
  };
  std::vector<Pending> pending_;
  std::vector<std::string> claimed_;  ///< the targets of the OutputFiles opened inside it
  OutputTransaction* outer_;
  bool committed_ = false;
};

/// Writes `text` to `path` as an OutputFile.
void write_file_atomically(const std::string& path, const std::string& text);

}  // namespace pcr
