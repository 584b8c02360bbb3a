// The published numbers of data/peers.json (tasks/studies/published.h): the HNN paper's Table 1
// as hnn reproduce and hnn compare read it, and the checks of the file.

#include "tasks/studies/published.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>

#include "tasks/error.h"
#include "tasks/experiments/registry.h"
#include "tests/tasks/test_configs.h"

namespace hnn::tasks {
namespace {

using nlohmann::json;
using testing::TempDir;

TEST(Published, TheHnnPapersTable1HasBothModelsOfEveryPaperTask) {
  const json published = read_published(published_path());
  for (const std::string& task : paper_task_names()) {
    const PaperRow base = paper_row(published, task, nn::ModelKind::kBaseline);
    const PaperRow hnn = paper_row(published, task, nn::ModelKind::kHnn);
    for (const PaperRow* row : {&base, &hnn}) {
      for (const PaperValue& v : {row->train_loss, row->test_loss, row->energy_mse}) {
        EXPECT_GT(v.mean, 0) << task;
        EXPECT_GT(v.se, 0) << task;
      }
    }
    // The paper's HNN conserves energy better than its baseline on every task.
    EXPECT_LT(hnn.energy_mse.mean, base.energy_mse.mean) << task;
  }
  // The paper's numbers as it prints them.
  const PaperRow spring = paper_row(published, "spring", nn::ModelKind::kHnn);
  EXPECT_EQ(spring.energy_mse.mean, 3.8416e-4);
  EXPECT_EQ(spring.energy_mse.se, 6.5e-5);
  const PaperRow three = paper_row(published, "three-body", nn::ModelKind::kBaseline);
  EXPECT_EQ(three.energy_mse.mean, 1.0906e+2);
  EXPECT_EQ(three.test_loss.se, 4.2e-1);
  EXPECT_EQ(paper_row(published, "two-body", nn::ModelKind::kHnn).train_loss.mean, 2.9959e-6);
}

TEST(Published, ANumberTheFileLacksIsNamed) {
  const json empty = {{"peers", json::array()}};
  try {
    paper_row(empty, "spring", nn::ModelKind::kHnn);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("spring hnn train_loss"), std::string::npos) << e.what();
  }
}

TEST(Published, ABadEntryIsOneLineNamingTheFileAndTheEntry) {
  TempDir dir("published");
  const std::filesystem::path file = dir / "peers.json";
  std::ofstream(file) << R"({"peers": [{"peer": "x", "source": "y", "task": "spring",
    "peer_model": "m", "value": 1, "task_defaults_only": "yes"}]})";
  try {
    read_published(file);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()), "peers file " + file.string() +
                                         ": entry 1: 'task_defaults_only' must be true or "
                                         "false");
  }
  EXPECT_THROW(read_published(dir / "none.json"), Error);
  // $HNN_PEERS names another file.
  ASSERT_EQ(::setenv("HNN_PEERS", file.c_str(), 1), 0);
  EXPECT_EQ(published_path(), file);
  ::unsetenv("HNN_PEERS");
}

}  // namespace
}  // namespace hnn::tasks
