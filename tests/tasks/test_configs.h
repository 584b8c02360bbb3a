#pragma once
// Shared helpers of the tasks and apps tests: temporary run folders, small run settings, and
// readers for the files a run writes.

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "tasks/run.h"

namespace hnn::tasks::testing {

// Tests call the library single-threaded, as `hnn train` does by default: on a shared 2-core
// machine, Eigen's OpenMP workers mostly spin (a 40,000-row evaluation took 3x longer).
inline const bool kEigenSingleThreaded = [] {
  Eigen::setNbThreads(1);
  return true;
}();

/// A fresh folder under the build tree, removed when the test ends.
class TempDir {
 public:
  explicit TempDir(const std::string& name) {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    std::string test = info ? std::string(info->test_suite_name()) + "." + info->name() : "x";
    path_ = std::filesystem::path(HNN_BINARY_DIR) / "test_tmp" / (test + "." + name);
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::filesystem::path& path() const { return path_; }
  std::filesystem::path operator/(const std::string& leaf) const { return path_ / leaf; }

 private:
  std::filesystem::path path_;
};

/// The tasks on phase-space states (1-4b); the pixel pendulum has tests of its own.
inline const std::vector<std::string>& state_tasks() {
  static const std::vector<std::string> names = {"spring", "pendulum", "real-pendulum", "two-body",
                                                 "three-body"};
  return names;
}

/// Tiny settings: narrow network, few steps, quiet, 15 rollouts (the paper's count; the default
/// is 100). Minibatch tasks keep their batch size.
inline RunOptions small_run(const std::string& task, const std::string& model,
                            const std::filesystem::path& out, int steps = 10) {
  RunOptions o;
  o.task = task;
  if (task != "pixel-pendulum") o.task_settings = {{"rollouts", 15}};
  o.model = parse_model(model);
  o.steps = steps;
  o.hidden = std::vector<int>{16, 16};
  o.out = out;
  o.quiet = true;
  return o;
}

inline std::string read_text(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

inline nlohmann::json read_json(const std::filesystem::path& path) {
  return nlohmann::json::parse(read_text(path));
}

/// The lines of a text file (no line ends).
inline std::vector<std::string> read_lines(const std::filesystem::path& path) {
  std::vector<std::string> lines;
  std::istringstream in(read_text(path));
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

/// Splits a CSV line on commas, keeping empty cells.
inline std::vector<std::string> split_csv(const std::string& line) {
  std::vector<std::string> cells;
  std::string cell;
  std::istringstream in(line);
  while (std::getline(in, cell, ',')) cells.push_back(cell);
  if (!line.empty() && line.back() == ',') cells.emplace_back();
  return cells;
}

/// The metrics every run reports with a number (tasks: issue 5).
inline const std::vector<std::string>& numeric_metric_keys() {
  static const std::vector<std::string> keys = {"seed",          "steps",         "train_loss",
                                                "train_loss_se", "test_loss",     "test_loss_se",
                                                "energy_mse",    "energy_mse_se", "train_seconds"};
  return keys;
}

}  // namespace hnn::tasks::testing
