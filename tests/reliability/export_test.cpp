// `hnn export` (issue 17): the exported C file, compiled by the system C compiler, and the JSON
// file, read back, give the library's H, dH/dx and field to 1e-13 relative; bad inputs get one
// line and no file.

#include "nn/export.h"

#include <dlfcn.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <random>

#include "nn/hnn.h"
#include "reliability_util.h"
#include "tasks/run.h"

namespace hnn::reliability {
namespace {

using nn::Index;
using nn::Matrix;
using Energy = double (*)(const double*);
using Vector = void (*)(const double*, double*);

/// The exported C file compiled into a shared library and opened.
class CompiledExport {
 public:
  CompiledExport(const std::string& source, const TempDir& dir) {
    write_text(dir / "h.c", source);
    const std::string so = (dir / "h.so").string();
    const std::string cmd = "cc -std=c99 -O2 -shared -fPIC -Wall -Wextra -Werror -o " + so + " " +
                            (dir / "h.c").string() + " -lm";
    if (std::system(cmd.c_str()) != 0) throw std::runtime_error("cc failed: " + cmd);
    handle_ = ::dlopen(so.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (!handle_) throw std::runtime_error(::dlerror());
    energy = reinterpret_cast<Energy>(::dlsym(handle_, "hnn_energy"));
    gradient = reinterpret_cast<Vector>(::dlsym(handle_, "hnn_gradient"));
    field = reinterpret_cast<Vector>(::dlsym(handle_, "hnn_field"));
  }
  ~CompiledExport() { ::dlclose(handle_); }
  CompiledExport(const CompiledExport&) = delete;
  CompiledExport& operator=(const CompiledExport&) = delete;

  Energy energy = nullptr;
  Vector gradient = nullptr, field = nullptr;

 private:
  void* handle_ = nullptr;
};

Matrix<double> random_states(Index rows, Index dim, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.5);
  Matrix<double> x(rows, dim);
  for (Index i = 0; i < x.size(); ++i) x.data()[i] = normal(rng);
  return x;
}

/// |got - want| <= 1e-13 relative to max(|want|, the batch's RMS of want).
void expect_close(const Matrix<double>& got, const Matrix<double>& want, const char* what) {
  ASSERT_EQ(got.rows(), want.rows());
  ASSERT_EQ(got.cols(), want.cols());
  const double rms = std::sqrt(want.squaredNorm() / double(want.size()));
  for (Index i = 0; i < want.size(); ++i) {
    const double scale = std::max(std::abs(want.data()[i]), rms);
    ASSERT_LE(std::abs(got.data()[i] - want.data()[i]), 1e-13 * scale)
        << what << " entry " << i << ": " << got.data()[i] << " vs " << want.data()[i];
  }
}

/// The compiled export's H, dH/dx and field against the library's on `x`.
void expect_matches_library(const CompiledExport& c, const nn::DynamicsModel<double>& model,
                            const Matrix<double>& x) {
  const auto& hnn = dynamic_cast<const nn::Hnn<double>&>(model);
  const Index dim = x.cols(), n = dim / 2;
  Matrix<double> energy(x.rows(), 1), grad(x.rows(), dim), field(x.rows(), dim);
  for (Index r = 0; r < x.rows(); ++r) {
    const Eigen::RowVectorXd row = x.row(r);
    Eigen::RowVectorXd g(dim), f(dim);
    energy(r, 0) = c.energy(row.data());
    c.gradient(row.data(), g.data());
    c.field(row.data(), f.data());
    grad.row(r) = g;
    field.row(r) = f;
  }
  const Matrix<double> want_field = hnn.field(x);
  Matrix<double> want_grad(x.rows(), dim);
  want_grad << -want_field.rightCols(n), want_field.leftCols(n);  // dH/dq = -ṗ, dH/dp = q̇
  expect_close(energy, hnn.energy(x), "H");
  expect_close(grad, want_grad, "dH/dx");
  expect_close(field, want_field, "field");
}

std::unique_ptr<nn::DynamicsModel<double>> random_hnn(Index dim, std::vector<Index> hidden) {
  nn::DynamicsConfig config;
  config.dim = dim;
  config.hidden = std::move(hidden);
  std::mt19937_64 rng(7);
  return nn::make_model<double>(config, rng);
}

TEST(Export, CompiledCMatchesTheLibrarysEnergyGradientAndField) {
  TempDir dir;
  const auto model = random_hnn(4, {32, 24});
  const CompiledExport c(nn::export_model(*model, nn::ExportFormat::kC, "a test"), dir);
  expect_matches_library(c, *model, random_states(3000, 4, 11));
}

/// Seconds per call of `f` (best of 5 runs of `reps` calls).
template <typename F>
double seconds_per_call(F f, int reps) {
  double best = 1e300;
  for (int run = 0; run < 5; ++run) {
    const auto start = std::chrono::steady_clock::now();
    for (int i = 0; i < reps; ++i) f();
    const std::chrono::duration<double> took = std::chrono::steady_clock::now() - start;
    best = std::min(best, took.count() / reps);
  }
  return best;
}

// The paper's model (2-200-200-1): exact on 1000 states, and the speed of both fields printed.
TEST(Export, PaperSizeModelMatchesAndItsSpeedIsPrinted) {
  TempDir dir;
  const auto model = random_hnn(2, {200, 200});
  const CompiledExport c(nn::export_model(*model, nn::ExportFormat::kC, "a test"), dir);
  const Matrix<double> x = random_states(1000, 2, 13);
  expect_matches_library(c, *model, x);
  Matrix<double> out(x.rows(), 2);
  const double exported = seconds_per_call(
      [&] {
        for (Index r = 0; r < x.rows(); ++r) c.field(x.row(r).data(), out.row(r).data());
      },
      3);
  const double library = seconds_per_call([&] { out = model->field(x); }, 3);
  std::printf("field on 1000 states: exported C %.3g states/s, library %.3g states/s\n",
              1000 / exported, 1000 / library);
}

/// H from the JSON file's layers, computed here with Eigen.
Matrix<double> energy_from_json(const nlohmann::json& j, const Matrix<double>& x) {
  Matrix<double> h = x;
  const auto& layers = j.at("layers");
  for (std::size_t l = 0; l < layers.size(); ++l) {
    const auto& rows = layers[l].at("weight");
    Matrix<double> w(rows.size(), rows[0].size());
    for (Index i = 0; i < w.rows(); ++i)
      for (Index k = 0; k < w.cols(); ++k) w(i, k) = rows[i][k].get<double>();
    h = h * w;
    if (!layers[l].at("bias").is_null()) {
      const std::vector<double> b = layers[l].at("bias").get<std::vector<double>>();
      h.rowwise() += Eigen::Map<const Eigen::RowVectorXd>(b.data(), Index(b.size()));
    }
    if (l + 1 < layers.size()) h = h.array().tanh().matrix();
  }
  return h;
}

TEST(Export, JsonRoundTripGivesTheWeightsExactlyAndTheLibrarysEnergy) {
  const auto model = random_hnn(2, {16, 8});
  const auto j = nlohmann::json::parse(nn::export_model(*model, nn::ExportFormat::kJson, "t"));
  EXPECT_EQ(j.at("field"), "solenoidal");
  EXPECT_EQ(j.at("activation"), "tanh");
  EXPECT_EQ(j.at("input"), nlohmann::json({"q1", "p1"}));
  ASSERT_EQ(j.at("layers").size(), 3U);
  EXPECT_TRUE(j["layers"][2]["bias"].is_null());
  const Matrix<double> w0 = model->mlp().layers()[0].weight().value();
  EXPECT_EQ(j["layers"][0]["weight"][1][3].get<double>(), w0(1, 3));  // bit for bit
  const Matrix<double> x = random_states(2000, 2, 5);
  const auto& hnn = dynamic_cast<const nn::Hnn<double>&>(*model);
  expect_close(energy_from_json(j, x), hnn.energy(x), "H from JSON");
}

TEST(Export, RefusesBaselinesAndOtherFieldTypesAndActivations) {
  nn::DynamicsConfig config;
  config.hidden = {8};
  std::mt19937_64 rng(1);
  config.model = nn::ModelKind::kBaseline;
  EXPECT_THROW(nn::check_exportable(*nn::make_model<double>(config, rng)), std::invalid_argument);
  config.model = nn::ModelKind::kHnn;
  config.field = nn::FieldType::kBoth;
  EXPECT_THROW(nn::check_exportable(*nn::make_model<double>(config, rng)), std::invalid_argument);
  config.field = nn::FieldType::kSolenoidal;
  config.activation = nn::Activation::kRelu;
  EXPECT_THROW(nn::check_exportable(*nn::make_model<double>(config, rng)), std::invalid_argument);
  EXPECT_THROW(nn::parse_export_format("onnx"), std::invalid_argument);
}

/// A tiny trained spring run (hnn or baseline) in dir/name.
fs::path train_spring(const TempDir& dir, const std::string& model) {
  const fs::path run = dir / model;
  const Result r = run_hnn({"train", "spring", "--model", model, "--steps", "5", "--hidden", "8",
                            "--quiet", "--out", run.string()},
                           dir.path());
  EXPECT_EQ(r.code, 0) << r.err;
  return run;
}

TEST(ExportCli, ATrainedSpringRunExportsCAndJsonThatMatchTheRun) {
  TempDir dir;
  const fs::path run = train_spring(dir, "hnn");
  for (const std::string format : {"c", "json"}) {
    const Result r = run_hnn(
        {"export", run.string(), "--format", format, "--out", (dir / ("h." + format)).string()},
        dir.path());
    ASSERT_EQ(r.code, 0) << r.err;
  }
  const tasks::LoadedRun loaded = tasks::load_run(run);
  const CompiledExport c(read_text(dir / "h.c"), dir);
  const Matrix<double> x = random_states(500, 2, 3);
  expect_matches_library(c, loaded.run->dynamics(), x);
  const auto& hnn = dynamic_cast<const nn::Hnn<double>&>(loaded.run->dynamics());
  expect_close(energy_from_json(read_json(dir / "h.json"), x), hnn.energy(x), "H from JSON");
}

TEST(ExportCli, BadInputsGetOneLineAndNoFile) {
  TempDir dir;
  const fs::path baseline = train_spring(dir, "baseline");
  const fs::path out = dir / "h.c";
  const std::vector<std::pair<std::vector<std::string>, std::string>> cases = {
      {{baseline.string(), "--format", "c"},
       "hnn: error: cannot export a baseline model: it has no learned H"},
      {{baseline.string(), "--format", "onnx"},
       "hnn: error: unknown export format 'onnx' (known: c, json)"},
      {{(dir / "nope").string(), "--format", "c"},
       "hnn: error: run: Directory does not exist: " + (dir / "nope").string() + " (see --help)"},
  };
  for (const auto& [args, message] : cases) {
    std::vector<std::string> all = {"export"};
    all.insert(all.end(), args.begin(), args.end());
    all.insert(all.end(), {"--out", out.string()});
    const Result r = run_hnn(all, dir.path());
    EXPECT_EQ(r.code, 1) << message;
    EXPECT_EQ(r.err, message + "\n");
    EXPECT_FALSE(fs::exists(out)) << message;
  }
}

}  // namespace
}  // namespace hnn::reliability
