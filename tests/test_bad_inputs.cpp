// The corpus of bad inputs (tests/bad_inputs/<case>/): each case is a command a lab engineer could
// type on messy files, the exit status it must give and a fragment of the message that must name
// the culprit. The case's files are copied to a scratch directory and the command runs there; the
// files listed as `keep` must come out byte for byte, and no temporary may be left behind.
//
// case.txt: `# comment`, `run: ARGS` (after `pcr`; may redirect stdout), `exit: N`,
// `message: TEXT` (in stderr), `keep: FILE` (any number), `nest: FILE DEPTH` (writes FILE as
// DEPTH nested JSON arrays: too big to keep in the repository), `tool: NAME` (run another tool
// built next to `pcr`, e.g. pcr_calibrate, instead of `pcr`).
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "scratch_directory.hpp"

namespace {

namespace fs = std::filesystem;

const fs::path kCorpus = fs::path(PCR_SOURCE_DIR) / "tests" / "bad_inputs";

std::string slurp(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

struct Case {
  std::string run, message, tool;
  int exit = -1;
  std::vector<std::string> keep;
  std::vector<std::pair<std::string, int>> nest;
};

Case read_case(const fs::path& file) {
  Case c;
  std::ifstream in(file);
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    const std::size_t colon = line.find(": ");
    if (colon == std::string::npos) ADD_FAILURE() << file << ": bad line '" << line << "'";
    if (colon == std::string::npos) continue;
    const std::string key = line.substr(0, colon), value = line.substr(colon + 2);
    if (key == "run") c.run = value;
    if (key == "exit") c.exit = std::stoi(value);
    if (key == "message") c.message = value;
    if (key == "tool") c.tool = value;
    if (key == "keep") c.keep.push_back(value);
    if (key == "nest") {
      std::istringstream words(value);
      std::string name;
      int depth = 0;
      words >> name >> depth;
      c.nest.emplace_back(name, depth);
    }
  }
  return c;
}

std::vector<std::string> case_names() {
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(kCorpus)) {
    if (fs::exists(entry.path() / "case.txt")) names.push_back(entry.path().filename().string());
  }
  std::sort(names.begin(), names.end());
  return names;
}

class BadInput : public ::testing::TestWithParam<std::string> {};

TEST_P(BadInput, RefusedByNameWithoutHarm) {
  const fs::path source = kCorpus / GetParam();
  const Case c = read_case(source / "case.txt");
  ASSERT_FALSE(c.run.empty()) << "no run: line";
  const fs::path tool =
      c.tool.empty() ? fs::path(PCR_CLI_PATH) : fs::path(PCR_CLI_PATH).parent_path() / c.tool;
  if (!fs::exists(tool)) GTEST_SKIP() << tool << " is not built";
  const pcr::test::ScratchDirectory scratch("bad_inputs");
  const fs::path dir = scratch.path() / "work";
  fs::create_directories(dir / "sub");
  std::map<std::string, std::string> before;
  for (const auto& entry : fs::directory_iterator(source)) {
    if (entry.path().filename() == "case.txt") continue;
    fs::copy_file(entry.path(), dir / entry.path().filename());
    before[entry.path().filename().string()] = slurp(entry.path());
  }
  for (const auto& [name, depth] : c.nest) {
    std::ofstream(dir / name) << std::string(depth, '[') << std::string(depth, ']') << "\n";
  }
  const fs::path err = scratch.path() / "stderr.txt";
  const bool redirects_stdout = c.run.find('>') != std::string::npos;
  const std::string command = "cd '" + dir.string() + "' && '" + tool.string() + "' " + c.run +
                              (redirects_stdout ? "" : " > /dev/null") + " 2> '" + err.string() +
                              "' < /dev/null";
  const int raw = std::system(command.c_str());
  const std::string message = slurp(err);
  ASSERT_TRUE(WIFEXITED(raw)) << "killed by a signal: " << message;
  EXPECT_EQ(WEXITSTATUS(raw), c.exit) << message;
  EXPECT_NE(message.find(c.message), std::string::npos)
      << "expected '" << c.message << "' in: " << message;
  for (const std::string& name : c.keep) {
    EXPECT_EQ(slurp(dir / name), before[name]) << name << " was changed";
  }
  for (const auto& entry : fs::recursive_directory_iterator(dir)) {
    EXPECT_EQ(entry.path().filename().string().find(".tmp"), std::string::npos)
        << "temporary left: " << entry.path();
  }
}

INSTANTIATE_TEST_SUITE_P(Corpus, BadInput, ::testing::ValuesIn(case_names()),
                         [](const ::testing::TestParamInfo<std::string>& info) {
                           return info.param;
                         });

}  // namespace
