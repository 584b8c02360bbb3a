#include "apps/hnn/commands/comparison.h"

#include <fmt/format.h>

#include <fstream>
#include <stdexcept>

namespace hnn::app {

namespace {

using nlohmann::json;

json metrics_of(const std::filesystem::path& run) {
  const std::filesystem::path path = run / "metrics.json";
  std::ifstream in(path);
  if (!in) throw std::runtime_error(fmt::format("{}: missing (not a finished run)", path.string()));
  try {
    return json::parse(in);
  } catch (const json::exception& e) {
    throw std::runtime_error(fmt::format("{}: not JSON: {}", path.string(), e.what()));
  }
}

json value_or_null(const json& m, const char* key) {
  const auto it = m.find(key);
  return it == m.end() ? json() : *it;
}

struct Row {
  const char* key;
  const char* label;
  bool ratio;  // a ratio OTHER / RUN means something (not for R^2)
};

constexpr Row kRows[] = {
    {"test_loss", "test loss", true},   {"test_loss_standardised", "test loss, standardised", true},
    {"test_r2", "test R²", false},      {"valid_prediction_time", "valid prediction time", true},
    {"energy_mse", "energy MSE", true}, {"energy_relative_mse", "energy MSE, relative", true}};

std::string cell(const json& m, const char* key) {
  const json& v = m.at(key);
  const std::string se_key = std::string(key) + "_se";
  const auto se = m.find(se_key);
  if (se != m.end() && se->is_number())
    return fmt::format("{:.3g} ± {:.2g}", v.get<double>(), se->get<double>());
  return fmt::format("{:.4g}", v.get<double>());
}

}  // namespace

void check_comparable(const std::filesystem::path& run, const std::filesystem::path& other) {
  const json a = metrics_of(run), b = metrics_of(other);
  for (const char* key : {"task", "seed", "task_settings", "data_sha256"}) {
    const json x = value_or_null(a, key), y = value_or_null(b, key);
    if (x != y) {
      throw std::runtime_error(
          fmt::format("--against {}: not comparable with {}: runs of other {} ({}: {} against {})",
                      other.string(), run.string(), key == std::string("task") ? "tasks" : "data",
                      key, x.dump(), y.dump()));
    }
  }
}

std::string comparison_table(const json& run, const std::string& run_name, const json& other,
                             const std::string& other_name) {
  std::string out = fmt::format("  {:<25} {:<22} {:<22} {} / {}\n", "", run_name, other_name,
                                other_name, run_name);
  for (const Row& row : kRows) {
    const auto a = run.find(row.key), b = other.find(row.key);
    if (a == run.end() || b == other.end() || !a->is_number() || !b->is_number()) continue;
    std::string line =
        fmt::format("  {:<25} {:<22} {:<22}", row.label, cell(run, row.key), cell(other, row.key));
    if (row.ratio && a->get<double>() != 0)
      line += fmt::format(" {:.3g}", b->get<double>() / a->get<double>());
    out += line.substr(0, line.find_last_not_of(' ') + 1) + "\n";
  }
  return out;
}

}  // namespace hnn::app
