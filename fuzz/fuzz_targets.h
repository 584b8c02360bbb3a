#pragma once
// What the fuzzers feed their bytes to, as plain functions: fuzz/*_fuzz.cpp call them from
// libFuzzer, and tests/reliability/fuzz_corpus_test.cpp replays fuzz/corpus/ and
// fuzz/regressions/ through them in every test build. Each reader may refuse an input only with
// its documented error; anything else escaping, a sanitizer report, or a broken invariant of
// what it returns (FUZZ_CHECK, which aborts) is a finding.

#include <sys/mman.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <random>
#include <string>

#include "nn/hnn.h"
#include "nn/parameter_file.h"
#include "physics/lipson.h"
#include "physics/types.h"
#include "tasks/data/table.h"
#include "tasks/experiments/registry.h"
#include "tasks/field/field_task.h"
#include "tasks/report/run_folder.h"
#include "tasks/run.h"
#include "tasks/train/checkpoint.h"

#define FUZZ_CHECK(cond)                                                                \
  do {                                                                                  \
    if (!(cond)) {                                                                      \
      std::fprintf(stderr, "%s:%d: invariant broken: %s\n", __FILE__, __LINE__, #cond); \
      std::abort();                                                                     \
    }                                                                                   \
  } while (false)

namespace hnn::fuzz {

/// An in-memory file (memfd) whose contents each input replaces; loaders open it by path.
class MemoryFile {
 public:
  MemoryFile() : fd_(::memfd_create("hnn-fuzz", 0)) { FUZZ_CHECK(fd_ >= 0); }
  ~MemoryFile() { ::close(fd_); }
  MemoryFile(const MemoryFile&) = delete;
  MemoryFile& operator=(const MemoryFile&) = delete;

  void set(const std::uint8_t* data, std::size_t size) {
    FUZZ_CHECK(::ftruncate(fd_, 0) == 0);
    FUZZ_CHECK(::pwrite(fd_, data, size, 0) == ssize_t(size));
  }
  std::string path() const { return "/proc/self/fd/" + std::to_string(fd_); }

 private:
  int fd_;
};

/// physics::load_lipson, then the real pendulum's dataset built from what it loaded.
inline void lipson_input(const std::string& path) {
  physics::LipsonData data;
  try {
    data = physics::load_lipson(path);
  } catch (const physics::DataError&) {
    return;
  }
  const Eigen::Index rows = data.rows();
  FUZZ_CHECK(rows > 0 && !data.columns.empty());
  FUZZ_CHECK(data.trial.size() == rows && data.line.size() == rows);
  FUZZ_CHECK(data.values.rows() == rows && data.values.cols() >= Eigen::Index(data.columns.size()));
  FUZZ_CHECK(data.values.allFinite() && data.t.allFinite());
  for (Eigen::Index i = 1; i < rows; ++i) FUZZ_CHECK(data.line(i) > data.line(i - 1));
  FUZZ_CHECK(data.select_trial(data.trial(0)).rows() >= 1);
  const auto task = tasks::make_field_task("real-pendulum");
  tasks::RunSettings settings;
  settings.task = task->name();
  settings.data_file = path;
  try {
    const tasks::Dataset d = task->build_dataset(settings);
    FUZZ_CHECK(d.train_x.rows() > 0 && d.test_x.rows() > 0);
    FUZZ_CHECK(d.train_x.allFinite() && d.train_dxdt.allFinite());
  } catch (const tasks::Error&) {
  }
}

/// nn::read_parameter_file_info, then nn::load_parameters into an HNN 2-8-1 (double and float):
/// refused inputs must leave the model unchanged.
inline void parameters_input(const std::string& path) {
  nn::ParameterFileInfo info;
  try {
    info = nn::read_parameter_file_info(path);
  } catch (const nn::ParameterFileError&) {
  }
  FUZZ_CHECK(info.entries.size() < (1u << 20));
  nn::DynamicsConfig config;
  config.hidden = {8};
  std::mt19937_64 rng(1);
  for (int scalar = 0; scalar < 2; ++scalar) {
    const auto check = [&](auto& model) {
      const auto before = model->parameters().front().value();
      try {
        nn::load_parameters(path, *model);
      } catch (const nn::ParameterFileError&) {
        FUZZ_CHECK(model->parameters().front().value() == before);
      }
    };
    if (scalar == 0) {
      auto model = nn::make_model<double>(config, rng);
      check(model);
    } else {
      auto model = nn::make_model<float>(config, rng);
      check(model);
    }
  }
}

/// tasks::read_train_state on `run_dir`/checkpoint/state.json, then the run settings that
/// `hnn train --resume` takes from it, checked as the program checks them.
inline void train_state_input(const std::filesystem::path& run_dir) {
  try {
    const tasks::TrainState state =
        tasks::read_train_state(tasks::RunFolder(run_dir).checkpoint_dir());
    FUZZ_CHECK(state.step >= 0 && state.step <= state.total_steps);
    FUZZ_CHECK(state.params_file.find('/') == std::string::npos);
    const tasks::RunOptions options = tasks::resume_options(run_dir);
    tasks::validate(options);
    FUZZ_CHECK(options.resume && options.out == run_dir);
  } catch (const tasks::Error&) {
  } catch (const std::invalid_argument&) {  // validate: an unknown model kind
  }
}

/// The readers of measured-data tables (tasks/data/table.h) on the same bytes as CSV, NumPy .npy
/// and .npz and the Lipson text: each returns a table whose invariants hold, or refuses with
/// tasks::Error.
inline void table_input(const std::string& path) {
  using Reader = tasks::Table (*)(const std::string&);
  for (const Reader read : {Reader(tasks::read_csv), Reader(tasks::read_npy),
                            Reader(tasks::read_npz), Reader(tasks::read_lipson)}) {
    tasks::Table table;
    try {
      table = read(path);
    } catch (const tasks::Error&) {
      continue;
    }
    FUZZ_CHECK(table.columns() == Eigen::Index(table.names.size()) && table.rows() > 0);
    FUZZ_CHECK(table.values.allFinite());
    FUZZ_CHECK(table.lines.empty() || Eigen::Index(table.lines.size()) == table.rows());
    for (std::size_t c = 0; c < table.names.size(); ++c)
      FUZZ_CHECK(table.find(table.names[c]) == Eigen::Index(c));  // names are unique
  }
}

}  // namespace hnn::fuzz
