// docs/inputs.md, "Saved parameters" and "metrics.json": `hnn evaluate` and `hnn rollout` refuse
// a truncated, foreign, corrupt or mismatched run folder with one line naming the file, and the
// parameter reader never loads a file half-way.

#include <gtest/gtest.h>

#include <random>

#include "nn/hnn.h"
#include "nn/parameter_file.h"
#include "reliability_util.h"

namespace hnn::reliability {
namespace {

class RunFiles : public ::testing::Test {
 protected:
  // One small trained run, made once and copied by each case.
  // Once per process, in SetUp (not SetUpTestSuite, whose failures ctest reports as skips).
  void SetUp() override {
    if (good_) return;
    good_ = new TempDir("RunFiles.good");
    const Result r = run_hnn({"train", "spring", "--steps", "20", "--hidden", "8", "--quiet",
                              "--out", (*good_ / "run").string()},
                             good_->path());
    ASSERT_EQ(r.code, 0) << r.err;
  }
  static void TearDownTestSuite() {
    delete good_;
    good_ = nullptr;
  }

  // A copy of the good run, changed by `edit`.
  fs::path variant(const std::string& name, const std::function<void(const fs::path&)>& edit) {
    const fs::path run = dir_ / name;
    fs::copy(*good_ / "run", run, fs::copy_options::recursive);
    edit(run);
    return run;
  }

  static TempDir* good_;
  TempDir dir_;
};
TempDir* RunFiles::good_ = nullptr;

void truncate_to(const fs::path& file, std::size_t size) {
  write_text(file, read_text(file).substr(0, size));
}

void set_metric(const fs::path& run, const std::string& key, const nlohmann::json& value) {
  nlohmann::json m = read_json(run / "metrics.json");
  m[key] = value;
  write_text(run / "metrics.json", m.dump(2));
}

TEST_F(RunFiles, BadParameterFilesAreRefusedByEvaluateAndRollout) {
  const std::size_t size = fs::file_size(*good_ / "run" / "params.bin");
  struct Case {
    std::string name;
    std::function<void(const fs::path&)> edit;
    std::string reason;  // after "parameter file 'RUN/params.bin': "
  };
  const std::vector<Case> cases = {
      {"empty", [](const fs::path& r) { truncate_to(r / "params.bin", 0); },
       "not an hnn parameter file (bad magic bytes)"},
      {"cut-header", [](const fs::path& r) { truncate_to(r / "params.bin", 14); },
       "truncated: the reserved bytes needs 3 bytes at offset 13 but the file has 14 bytes"},
      {"cut-values", [](const fs::path& r) { truncate_to(r / "params.bin", 100); },
       "truncated: parameter 'mlp.layers.0.weight' is 2x8 but only 29 bytes remain at offset 71"},
      {"cut-checksum", [size](const fs::path& r) { truncate_to(r / "params.bin", size - 1); },
       fmt::format("truncated: the checksum needs 8 bytes at offset {} but the file has {} bytes",
                   size - 8, size - 1)},
      {"foreign",
       [](const fs::path& r) {
         fs::copy_file(r / "loss_curve.csv", r / "params.bin",
                       fs::copy_options::overwrite_existing);
       },
       "not an hnn parameter file (bad magic bytes)"},
      {"flipped-bit",
       [](const fs::path& r) {
         std::string bytes = read_text(r / "params.bin");
         bytes[bytes.size() / 2] ^= 0x10;
         write_text(r / "params.bin", bytes);
       },
       "corrupt: the checksum does not match the contents"},
      {"trailing",
       [](const fs::path& r) { write_text(r / "params.bin", read_text(r / "params.bin") + "x"); },
       fmt::format("1 unexpected bytes after the checksum at offset {}", size)},
      {"missing", [](const fs::path& r) { fs::remove(r / "params.bin"); },
       "cannot open for reading: No such file or directory"},
      {"directory",
       [](const fs::path& r) {
         fs::remove(r / "params.bin");
         fs::create_directory(r / "params.bin");
       },
       "is a directory, not a file"},
      {"other-width", [](const fs::path& r) { set_metric(r, "hidden", "16"); },
       "parameter 'mlp.layers.0.weight' is 2x8 in the file but 2x16 in the model"},
      {"other-dtype", [](const fs::path& r) { set_metric(r, "dtype", "float"); },
       "holds float64 parameters but the model is float32 (load into a model of the file's "
       "type, then cast)"},
      {"other-model", [](const fs::path& r) { set_metric(r, "model", "baseline"); },
       "holds a 'hnn:tanh' model but the model is 'baseline:tanh'"},
  };
  for (const Case& c : cases) {
    const fs::path run = variant(c.name, c.edit);
    const std::string line =
        "hnn: error: parameter file '" + (run / "params.bin").string() + "': " + c.reason + "\n";
    for (const char* command : {"evaluate", "rollout"}) {
      const Result r = run_hnn({command, run.string()}, dir_.path());
      EXPECT_EQ(r.code, 1) << c.name << " " << command;
      EXPECT_EQ(r.err, line) << c.name << " " << command;
    }
    EXPECT_FALSE(fs::exists(run / "rollout_dopri5.csv")) << c.name;
  }
}

TEST_F(RunFiles, BadMetricsFilesAreRefused) {
  struct Case {
    std::string name;
    std::function<void(const fs::path&)> edit;
    std::string message;  // after "hnn: error: ", with RUN for the run folder
  };
  const std::vector<Case> cases = {
      {"missing", [](const fs::path& r) { fs::remove(r / "metrics.json"); },
       "cannot read 'RUN/metrics.json': is 'RUN' a run folder of `hnn train`?"},
      {"cut", [](const fs::path& r) { truncate_to(r / "metrics.json", 10); },
       "'RUN/metrics.json' is not valid JSON: [json.exception.parse_error.101] parse error at "
       "line 2"},
      {"no-model",
       [](const fs::path& r) { write_text(r / "metrics.json", R"({"task": "spring"})"); },
       "'RUN/metrics.json' does not hold a run's settings: [json.exception.out_of_range.403] key "
       "'model' not found"},
      {"negative-seed", [](const fs::path& r) { set_metric(r, "seed", -5); },
       "'RUN/metrics.json' does not hold a run's settings: seed is -5, not an integer from 0 to "
       "18446744073709551615"},
      {"text-seed", [](const fs::path& r) { set_metric(r, "seed", "7"); },
       "'RUN/metrics.json' does not hold a run's settings: seed is \"7\", not an integer from 0 "
       "to 18446744073709551615"},
      {"bad-hidden", [](const fs::path& r) { set_metric(r, "hidden", "8-x"); },
       "'RUN/metrics.json' does not hold a run's settings: hidden '8-x' is not widths of 1..8192 "
       "joined by '-' (like 200-200)"},
      {"huge-hidden", [](const fs::path& r) { set_metric(r, "hidden", "99999999999"); },
       "'RUN/metrics.json' does not hold a run's settings: hidden '99999999999' is not widths "
       "of 1..8192 joined by '-' (like 200-200)"},
      // Widths that are integers but not 1..8192 are the file's fault too, not an option's.
      {"wide-hidden", [](const fs::path& r) { set_metric(r, "hidden", "8-9000"); },
       "'RUN/metrics.json' does not hold a run's settings: hidden '8-9000' is not widths of "
       "1..8192 joined by '-' (like 200-200)"},
      {"zero-hidden", [](const fs::path& r) { set_metric(r, "hidden", "0"); },
       "'RUN/metrics.json' does not hold a run's settings: hidden '0' is not widths of 1..8192 "
       "joined by '-' (like 200-200)"},
      {"unknown-task", [](const fs::path& r) { set_metric(r, "task", "nope"); },
       "unknown task 'nope' (known: spring, pendulum, real-pendulum, two-body, three-body"},
  };
  for (const Case& c : cases) {
    const fs::path run = variant(c.name, c.edit);
    std::string message = c.message;
    for (std::size_t at; (at = message.find("RUN")) != std::string::npos;) {
      message.replace(at, 3, run.string());
    }
    const Result r = run_hnn({"evaluate", run.string()}, dir_.path());
    expect_one_line_error_starting(r, message, c.name);
  }
}

TEST_F(RunFiles, UnknownIntegratorWritesNothing) {
  const fs::path run = variant("integrator", [](const fs::path&) {});
  const Result r = run_hnn({"rollout", run.string(), "--integrator", "rk5"}, dir_.path());
  EXPECT_EQ(r.code, 1);
  EXPECT_EQ(r.err,
            "hnn: error: unknown integrator 'rk5'; known: euler, rk4, dopri5, leapfrog, yoshida4, "
            "symplectic_euler, midpoint\n");
  EXPECT_FALSE(fs::exists(run / "rollout_rk5.csv"));
}

// The reader itself, on every prefix of a file and on single-bit flips: always a ParameterFileError
// naming the file, and the model untouched.
TEST(ParameterReader, EveryTruncationAndBitFlipIsRefusedWithoutChangingTheModel) {
  const TempDir dir;
  std::mt19937_64 rng(3);
  nn::DynamicsConfig config;
  config.hidden = {4};
  const auto saved = nn::make_model<double>(config, rng);
  const auto target = nn::make_model<double>(config, rng);
  const fs::path good = dir / "good.bin", bad = dir / "bad.bin";
  nn::save_parameters(good, *saved);
  const std::string bytes = read_text(good);
  const std::vector<ad::Var<double>> before = target->parameters();
  std::vector<nn::Matrix<double>> values;
  for (const auto& p : before) values.push_back(p.value());
  const auto expect_refused = [&](const std::string& what) {
    EXPECT_THROW(nn::read_parameter_file_info(bad), nn::ParameterFileError) << what;
    try {
      nn::load_parameters(bad, *target);
      ADD_FAILURE() << what << ": loaded";
    } catch (const nn::ParameterFileError& e) {
      EXPECT_EQ(e.path(), bad) << what;
    }
    for (std::size_t i = 0; i < before.size(); ++i) ASSERT_EQ(before[i].value(), values[i]) << what;
  };
  for (std::size_t size = 0; size < bytes.size(); ++size) {
    write_text(bad, bytes.substr(0, size));
    expect_refused(fmt::format("cut to {} bytes", size));
  }
  for (std::size_t at = 0; at < bytes.size(); at += 3) {
    std::string flipped = bytes;
    flipped[at] ^= char(1 << (at % 8));
    write_text(bad, flipped);
    expect_refused(fmt::format("bit flipped at byte {}", at));
  }
  nn::load_parameters(good, *target);  // and the good file loads
  EXPECT_EQ(target->parameters()[0].value(), saved->parameters()[0].value());
}

}  // namespace
}  // namespace hnn::reliability
