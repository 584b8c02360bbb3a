// `hnn train --preset` and `hnn reproduce --preset` (issue 7, chart 4): lean trains each task's
// lean widths, --hidden overrides the preset, paper stays the default, and a bad preset gets
// one line on stderr, exit 1 and no run folder.

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "tasks/experiments/registry.h"
#include "tasks/task.h"

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

struct Result {
  int exit_code;
  std::string out, err;
};

std::string read_text(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// A folder under the build tree for this test, removed before and after.
fs::path temp_dir(const std::string& name) {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  const fs::path dir = fs::path(HNN_BINARY_DIR) / "test_tmp" /
                       (std::string("apps.") + info->test_suite_name() + "." + info->name());
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir / name;
}

// Runs `hnn ARGS` with stdout and stderr captured (stderr through a file of its own).
Result hnn(const std::string& args) {
  static int calls = 0;
  const fs::path err =
      fs::path(HNN_BINARY_DIR) / "test_tmp" /
      ("apps.CliPreset.stderr." + std::to_string(::getpid()) + "." + std::to_string(calls++));
  fs::create_directories(err.parent_path());
  const std::string command =
      std::string("'") + HNN_EXE + "' " + args + " 2>'" + err.string() + "'";
  FILE* pipe = popen(command.c_str(), "r");
  if (pipe == nullptr) return {-1, "", ""};
  std::string out;
  char buffer[4096];
  for (std::size_t n; (n = fread(buffer, 1, sizeof buffer, pipe)) > 0;) out.append(buffer, n);
  const int status = pclose(pipe);
  Result r{WIFEXITED(status) ? WEXITSTATUS(status) : -1, out, read_text(err)};
  fs::remove(err);
  return r;
}

std::string widths(const std::vector<int>& hidden) {
  std::string s;
  for (int w : hidden) s += (s.empty() ? "" : "-") + std::to_string(w);
  return s;
}

std::string lean_widths(const std::string& task) {
  return widths(hnn::tasks::make_task(task)->lean_hidden());
}

TEST(CliPreset, LeanTrainsTheTasksLeanWidths) {
  const fs::path run = temp_dir("run");
  const Result r = hnn("train spring --preset lean --steps 3 --quiet --out '" + run.string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json m = json::parse(read_text(run / "metrics.json"));
  EXPECT_EQ(m["hidden"], lean_widths("spring"));
  EXPECT_NE(m["hidden"], "200-200");
  EXPECT_EQ(m["preset"], "lean");
}

TEST(CliPreset, HiddenOverridesThePreset) {
  const fs::path run = temp_dir("run");
  const Result r = hnn("train two-body --preset lean --hidden 8 8 --steps 2 --quiet --out '" +
                       run.string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json m = json::parse(read_text(run / "metrics.json"));
  EXPECT_EQ(m["hidden"], "8-8");
  EXPECT_EQ(m["preset"], "lean");
}

TEST(CliPreset, PaperIsTheDefault) {
  const Result help = hnn("train --help");
  EXPECT_NE(help.out.find("--preset"), std::string::npos) << help.out;
  EXPECT_NE(help.out.find("--preset NAME"), std::string::npos) << help.out;
  EXPECT_NE(help.out.find("(default: paper)"), std::string::npos) << help.out;
  const fs::path run = temp_dir("run");
  const Result r = hnn("train real-pendulum --steps 2 --quiet --out '" + run.string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json m = json::parse(read_text(run / "metrics.json"));
  EXPECT_EQ(m["hidden"], "200-200");
  EXPECT_EQ(m["preset"], "paper");
}

TEST(CliPreset, UnknownPresetGetsOneLineAndNoRunFolder) {
  for (const std::string preset : {"tiny", "Lean", "''"}) {
    const fs::path run = temp_dir("run");
    for (const std::string& command :
         {"train spring --steps 2 --preset " + preset + " --out '" + run.string() + "'",
          "reproduce --tasks spring --steps 2 --preset " + preset + " --out '" + run.string() +
              "'"}) {
      const Result r = hnn(command);
      EXPECT_EQ(r.exit_code, 1) << command;
      const std::string shown = preset == "''" ? "" : preset;
      EXPECT_EQ(r.err, "hnn: error: --preset: " + shown + " not in {paper,lean} (see --help)\n")
          << command;
      EXPECT_FALSE(fs::exists(run)) << command;
    }
  }
}

TEST(CliPreset, CannotBeCombinedWithResume) {
  const fs::path run = temp_dir("run");
  ASSERT_EQ(hnn("train spring --steps 2 --hidden 8 --quiet --out '" + run.string() + "'").exit_code,
            0);
  const Result r = hnn("train --resume '" + run.string() + "' --preset lean");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(r.err,
            "hnn: error: --preset cannot be combined with --resume: a resumed run keeps its own "
            "settings\n");
}

TEST(CliPreset, ReproduceTrainsEveryRunWithThePreset) {
  const fs::path out = temp_dir("results");
  const Result r =
      hnn("reproduce --tasks spring --steps 3 --preset lean --jobs 1 --out '" + out.string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json table = json::parse(read_text(out / "table1.json"));
  ASSERT_EQ(table.size(), 2u);  // baseline and HNN
  for (const json& row : table) {
    EXPECT_EQ(row["hidden"], lean_widths("spring")) << row.dump();
    EXPECT_EQ(row["preset"], "lean") << row.dump();
  }
  const std::string md = read_text(out / "table1.md");
  EXPECT_NE(md.find("double, lean " + lean_widths("spring")), std::string::npos) << md;
}

}  // namespace
