// Replays the fuzzers' corpus (fuzz/corpus/) and every crasher they found (fuzz/regressions/)
// through the same checks as the harnesses, so each is a regression test in every build,
// sanitizers included. scripts/fuzz.sh grows the corpus.

#include <gtest/gtest.h>

#include "fuzz/fuzz_targets.h"
#include "reliability_util.h"

namespace hnn::reliability {
namespace {

// The files of fuzz/corpus/<name> and fuzz/regressions/<name> (which may not exist).
std::vector<fs::path> inputs(const std::string& name) {
  std::vector<fs::path> files;
  for (const char* kind : {"corpus", "regressions"}) {
    const fs::path dir = fs::path(HNN_SOURCE_DIR) / "fuzz" / kind / name;
    if (!fs::is_directory(dir)) continue;
    for (const auto& entry : fs::directory_iterator(dir)) {
      if (entry.is_regular_file()) files.push_back(entry.path());
    }
  }
  std::sort(files.begin(), files.end());
  return files;
}

TEST(FuzzCorpus, LipsonInputs) {
  const std::vector<fs::path> files = inputs("lipson");
  EXPECT_GE(files.size(), 5u);
  for (const fs::path& file : files) {
    SCOPED_TRACE(file.string());
    fuzz::lipson_input(file.string());
  }
}

TEST(FuzzCorpus, ParameterFileInputs) {
  const std::vector<fs::path> files = inputs("params");
  EXPECT_GE(files.size(), 3u);
  for (const fs::path& file : files) {
    SCOPED_TRACE(file.string());
    fuzz::parameters_input(file.string());
  }
}

TEST(FuzzCorpus, TableInputs) {
  const std::vector<fs::path> files = inputs("table");
  EXPECT_GE(files.size(), 10u);
  for (const fs::path& file : files) {
    SCOPED_TRACE(file.string());
    fuzz::table_input(file.string());
  }
}

TEST(FuzzCorpus, TrainStateInputs) {
  const TempDir dir;
  const std::vector<fs::path> files = inputs("train_state");
  EXPECT_GE(files.size(), 1u);
  for (const fs::path& file : files) {
    SCOPED_TRACE(file.string());
    fs::create_directories(dir / "checkpoint");
    fs::copy_file(file, dir / "checkpoint" / "state.json", fs::copy_options::overwrite_existing);
    fuzz::train_state_input(dir.path());
  }
}

}  // namespace
}  // namespace hnn::reliability
