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

// Each layer of tasks/ and the layers its files may include. The root holds two layers: the
// Task interface with the typed options ("", every root file but run.h, run.cpp and
// run_outputs.cpp), which the frameworks and experiments build on, and the run end to end
// ("run"), which looks experiments up by name. tasks/error.h is shared by all.
const std::map<std::string, std::set<std::string>>& allowed() {
  static const std::map<std::string, std::set<std::string>> layers = {
      {"report", {"report"}},
      {"data", {"data"}},
      {"integrate", {"integrate"}},
      {"train", {"train", "integrate", "data", "report"}},
      {"evaluate", {"evaluate", "integrate", "data", "report"}},
      {"pixel", {"pixel", "train", "evaluate", "integrate", "data", "report"}},
      {"", {"", "train", "evaluate", "integrate", "data", "report"}},
      {"field", {"field", "", "train", "evaluate", "integrate", "data", "report"}},
      {"experiments",
       {"experiments", "field", "", "pixel", "train", "evaluate", "integrate", "data", "report"}},
      {"run",
       {"run", "experiments", "field", "", "pixel", "train", "evaluate", "integrate", "data",
        "report"}},
      {"studies",
       {"studies", "run", "experiments", "field", "", "pixel", "train", "evaluate", "integrate",
        "data", "report"}}};
  return layers;
}

// "tasks/train/loop.h" -> "train"; "tasks/run.h" and "tasks/run_outputs.cpp" -> "run";
// "tasks/task.h" and
// "tasks/options/train_options.h" -> "".
std::string folder_of(const std::string& include) {
  const fs::path path = fs::path(include).lexically_relative("tasks");
  // options/ (the table of `hnn train`'s options) is the root's interface layer in a folder.
  if (std::distance(path.begin(), path.end()) > 1)
    return path.begin()->string() == "options" ? "" : path.begin()->string();
  return path.stem() == "run" || path.stem() == "run_outputs" ? "run" : "";
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

// The root holds only the interface, the options and the run: experiments, frameworks and
// studies each have their folder.
TEST(Layering, TheRootHoldsOnlyTheInterfaceTheOptionsAndTheRun) {
  const std::set<std::string> root_files = {
      "error.h", "task.h",  "task.cpp",        "options.h",       "options.cpp",
      "run.h",   "run.cpp", "run_outputs.cpp", "trained_model.h", "CMakeLists.txt"};
  for (const fs::directory_entry& entry :
       fs::directory_iterator(fs::path(HNN_SOURCE_DIR) / "tasks")) {
    if (entry.is_directory()) continue;
    EXPECT_TRUE(root_files.count(entry.path().filename().string()))
        << entry.path() << " belongs in a folder of tasks/";
  }
}

}  // namespace
