#pragma once
// Test helpers for the data readers: files written into a fresh folder per test, the NumPy
// fixtures of tests/tasks/fixtures/ (make_numpy_fixtures.py), and the message an action throws.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <string>

#include "tasks/error.h"

namespace hnn::tasks::testing {

/// tests/tasks/fixtures/<name>.
inline std::string fixture(const std::string& name) {
  return (std::filesystem::path(HNN_SOURCE_DIR) / "tests/tasks/fixtures" / name).string();
}

/// The tasks::Error message `action` throws, or "no error".
inline std::string error_of(const std::function<void()>& action) {
  try {
    action();
  } catch (const Error& e) {
    return e.what();
  }
  return "no error";
}

/// LF line ends turned into CRLF.
inline std::string crlf(const std::string& text) {
  std::string out;
  for (char c : text) out += c == '\n' ? std::string("\r\n") : std::string(1, c);
  return out;
}

class DataFilesTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = std::filesystem::temp_directory_path() /
           (std::string("hnn_data_") + info->test_suite_name() + "_" + info->name());
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  std::string write(const std::string& name, const std::string& bytes) const {
    const std::string path = (dir_ / name).string();
    std::ofstream(path, std::ios::binary) << bytes;
    return path;
  }

  /// A copy of a fixture cut to its first `bytes` bytes, named "<bytes>_<its name>".
  std::string cut_copy(const std::string& fixture_name, std::size_t bytes) const {
    std::ifstream in(fixture(fixture_name), std::ios::binary);
    const std::string all((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    return write(
        std::to_string(bytes) + "_" + std::filesystem::path(fixture_name).filename().string(),
        all.substr(0, bytes));
  }

  std::filesystem::path dir_;
};

}  // namespace hnn::tasks::testing
