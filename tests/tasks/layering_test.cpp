// tasks/ is one library per concern with dependencies one way only (tasks/CMakeLists.txt): a
// folder includes only its own headers and those of the folders it links. This test reads every
// source of tasks/ and holds the includes to that order, so an include back up the chain (which
// the linker might still resolve) fails here first.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <string>

namespace {

namespace fs = std::filesystem;

// Each folder of tasks/ ("" is the root: the Task interface, experiments, runs) and the tasks/
// folders its library may include. tasks/error.h is shared by all.
const std::map<std::string, std::set<std::string>>& allowed() {
  static const std::map<std::string, std::set<std::string>> folders = {
      {"report", {"report"}},
      {"data", {"data"}},
      {"train", {"train", "data", "report"}},
      {"evaluate", {"evaluate", "data", "report"}},
      {"pixel", {"pixel", "train", "evaluate", "data", "report"}},
      {"", {"", "pixel", "train", "evaluate", "data", "report"}}};
  return folders;
}

// "tasks/train/loop.h" -> "train"; "tasks/run.h" -> "".
std::string folder_of(const std::string& include) {
  const fs::path path = fs::path(include).lexically_relative("tasks");
  return std::distance(path.begin(), path.end()) > 1 ? path.begin()->string() : "";
}

TEST(Layering, EveryTasksFolderIncludesOnlyWhatItLinks) {
  const fs::path root = fs::path(HNN_SOURCE_DIR) / "tasks";
  const std::regex include(R"(^#include "(tasks/[^"]+)\")");
  int files = 0;
  for (const fs::directory_entry& entry : fs::recursive_directory_iterator(root)) {
    const std::string ext = entry.path().extension().string();
    if (ext != ".h" && ext != ".cpp") continue;
    ++files;
    const std::string folder = folder_of("tasks" / entry.path().lexically_relative(root));
    ASSERT_TRUE(allowed().count(folder)) << "a folder the layering does not know: " << folder;
    std::ifstream in(entry.path());
    for (std::string line; std::getline(in, line);) {
      std::smatch m;
      if (!std::regex_search(line, m, include) || m[1] == "tasks/error.h") continue;
      EXPECT_TRUE(allowed().at(folder).count(folder_of(m[1])))
          << entry.path() << " includes " << m[1];
    }
  }
  EXPECT_GT(files, 30);
}

}  // namespace
