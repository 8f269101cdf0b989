// The tools' input and output files (pcr/files.hpp): no clobbered input, no replaced device, no
// temporary left, all or nothing.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>

#include "pcr/files.hpp"
#include "pcr/robot_io.hpp"
#include "scratch_directory.hpp"

namespace {

namespace fs = std::filesystem;

std::string read(const std::string& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

void write(const std::string& path, const std::string& text) { std::ofstream(path) << text; }

int count_entries(const fs::path& directory) {
  int count = 0;
  for (const auto& entry : fs::directory_iterator(directory)) {
    (void)entry;
    ++count;
  }
  return count;
}

TEST(Files, TemporaryNamesLeaveTheUsersFilesAlone) {
  const pcr::test::ScratchDirectory scratch("files");
  const std::string path = scratch.file("out.csv");
  // The names earlier versions used for their temporaries.
  write(path + ".tmp", "mine\n");
  write(path + ".tmp.png", "mine too\n");
  pcr::write_file_atomically(path, "new\n");
  EXPECT_EQ(read(path), "new\n");
  EXPECT_EQ(read(path + ".tmp"), "mine\n");
  EXPECT_EQ(read(path + ".tmp.png"), "mine too\n");
  EXPECT_EQ(count_entries(scratch.path()), 3);
}

TEST(Files, ExistingFileKeepsItsPermissions) {
  const pcr::test::ScratchDirectory scratch("files");
  const std::string path = scratch.file("script.sh");
  write(path, "old\n");
  ::chmod(path.c_str(), 0750);
  pcr::write_file_atomically(path, "new\n");
  struct stat st {};
  ASSERT_EQ(::stat(path.c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 07777, 0750u);
}

TEST(Files, SpecialFilesAreWrittenInPlaceNotReplaced) {
  pcr::write_file_atomically("/dev/null", "nothing\n");
  struct stat st {};
  ASSERT_EQ(::stat("/dev/null", &st), 0);
  EXPECT_TRUE(S_ISCHR(st.st_mode));
  // A device that fails every write: the error is reported, the device stays.
  if (::access("/dev/full", W_OK) == 0) {
    EXPECT_THROW(pcr::write_file_atomically("/dev/full", "x\n"), std::runtime_error);
    ASSERT_EQ(::stat("/dev/full", &st), 0);
    EXPECT_TRUE(S_ISCHR(st.st_mode));
  }
}

TEST(Files, SymbolicLinkStaysAndItsTargetIsWritten) {
  const pcr::test::ScratchDirectory scratch("files");
  const fs::path target = scratch.path() / "target.csv", link = scratch.path() / "link.csv";
  write(target.string(), "old\n");
  fs::create_symlink(target, link);
  pcr::write_file_atomically(link.string(), "new\n");
  EXPECT_TRUE(fs::is_symlink(link));
  EXPECT_EQ(read(target.string()), "new\n");
  EXPECT_EQ(count_entries(scratch.path()), 2);
}

TEST(Files, DirectoriesAreRefusedByName) {
  const pcr::test::ScratchDirectory scratch("files");
  const std::string directory = scratch.path().string();
  for (const auto& attempt : {+[](const std::string& p) { pcr::open_input_file(p); },
                              +[](const std::string& p) { pcr::OutputFile out(p); }}) {
    try {
      attempt(directory);
      FAIL() << "no error";
    } catch (const pcr::InputError& e) {
      EXPECT_NE(std::string(e.what()).find(directory + ": is a directory"), std::string::npos)
          << e.what();
    }
  }
  EXPECT_THROW(pcr::open_input_file(scratch.file("missing.json")), pcr::InputError);
}

TEST(Files, TransactionPutsAllOrNothingInPlace) {
  const pcr::test::ScratchDirectory scratch("files");
  const std::string a = scratch.file("a.csv"), b = scratch.file("b.json");
  write(a, "old a\n");
  write(b, "old b\n");
  try {
    pcr::OutputTransaction outputs;
    pcr::write_file_atomically(a, "new a\n");
    EXPECT_EQ(read(a), "old a\n");  // written, not yet in place
    throw std::runtime_error("the second output fails");
  } catch (const std::runtime_error&) {
  }
  EXPECT_EQ(read(a), "old a\n");
  EXPECT_EQ(read(b), "old b\n");
  EXPECT_EQ(count_entries(scratch.path()), 2);  // no temporary left
  {
    pcr::OutputTransaction outputs;
    pcr::write_file_atomically(a, "new a\n");
    {
      pcr::OutputTransaction inner;  // hands its file to the outer one
      pcr::write_file_atomically(b, "new b\n");
      inner.commit();
    }
    EXPECT_EQ(read(b), "old b\n");
    outputs.commit();
  }
  EXPECT_EQ(read(a), "new a\n");
  EXPECT_EQ(read(b), "new b\n");
  EXPECT_EQ(count_entries(scratch.path()), 2);
}

// Two outputs of one command never share a file, whatever its name: refused before anything is
// written, naming both options.
TEST(Files, TwoOutputsOnOneFileAreRefusedByOption) {
  const pcr::test::ScratchDirectory scratch("files");
  const std::string d = scratch.file("d.csv"), other = scratch.file("e.csv");
  write(d, "old\n");
  const std::string hard_link = scratch.file("alias.csv");
  fs::create_hard_link(d, hard_link);
  const std::string symbolic_link = scratch.file("link.csv");
  fs::create_symlink(d, symbolic_link);
  const std::string detour = scratch.path().string() + "/sub/../d.csv";
  fs::create_directory(scratch.path() / "sub");
  const std::string not_yet = scratch.file("new.csv");
  const std::string not_yet_detour = scratch.path().string() + "/sub/../new.csv";
  const std::pair<std::string, std::string> same[] = {
      {d, d},    {d, hard_link}, {d, symbolic_link}, {detour, d}, {not_yet, not_yet_detour},
      {"-", "-"}};
  for (const auto& [first, second] : same) {
    try {
      pcr::check_distinct_outputs({{"--output", first}, {"--report", ""}, {"--truth", second}});
      ADD_FAILURE() << first << " and " << second << " accepted";
    } catch (const pcr::InputError& e) {
      const std::string message = e.what();
      EXPECT_NE(message.find("--truth " + second + ": "), std::string::npos) << message;
      EXPECT_NE(message.find("--output " + first), std::string::npos) << message;
    }
  }
  EXPECT_NO_THROW(pcr::check_distinct_outputs({{"--output", d}, {"--truth", other}}));
  EXPECT_NO_THROW(pcr::check_distinct_outputs({{"--output", d}, {"--truth", "-"}}));
  EXPECT_NO_THROW(pcr::check_distinct_outputs({{"--output", ""}, {"--truth", ""}}));
  EXPECT_NO_THROW(
      pcr::check_distinct_outputs({{"--output", "/dev/null"}, {"--truth", "/dev/null"}}));
  // Inside a transaction, a second output over the same file is refused too, and the first one
  // is not put in place.
  try {
    pcr::OutputTransaction outputs;
    pcr::write_file_atomically(d, "first\n");
    pcr::write_file_atomically(hard_link, "second\n");
    outputs.commit();
    ADD_FAILURE() << "two outputs on one file in a transaction";
  } catch (const pcr::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("the same file as another output"), std::string::npos)
        << e.what();
  }
  EXPECT_EQ(read(d), "old\n");
  EXPECT_EQ(count_entries(scratch.path()), 4);  // d, alias, link, sub: no temporary left
}

// Last: protect_inputs() holds for the rest of the process.
TEST(Files, ProtectedInputsAreNeverOutputsComparedByFileNotName) {
  const pcr::test::ScratchDirectory scratch("files");
  const std::string input = scratch.file("q.csv"), other = scratch.file("out.csv");
  write(input, "q1\n0.001\n");
  pcr::protect_inputs();
  pcr::open_input_file(input);
  // The same file under another name: a hard link, and a path with a detour.
  const std::string hard_link = scratch.file("alias.csv");
  fs::create_hard_link(input, hard_link);
  const std::string detour = scratch.path().string() + "/./q.csv";
  for (const std::string& output : {input, hard_link, detour}) {
    try {
      pcr::write_file_atomically(output, "overwritten\n");
      FAIL() << output << ": written over the input";
    } catch (const pcr::InputError& e) {
      EXPECT_NE(std::string(e.what()).find("is also an input"), std::string::npos) << e.what();
    }
  }
  EXPECT_EQ(read(input), "q1\n0.001\n");
  pcr::write_file_atomically(other, "fine\n");
  EXPECT_EQ(read(other), "fine\n");
  EXPECT_EQ(count_entries(scratch.path()), 3);
}

}  // namespace
