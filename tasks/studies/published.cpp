// The published numbers (published.h).

#include "tasks/studies/published.h"

#include <cmath>
#include <cstdlib>
#include <fstream>

#include "tasks/data/data_files.h"
#include "tasks/error.h"

namespace hnn::tasks {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

// The `peer` of the HNN paper's entries (Greydanus et al. 2019, the paper hnn reproduces).
constexpr const char* kHnnPaper = "HNN (Greydanus et al. 2019)";

}  // namespace

fs::path published_path() {
  if (const char* path = std::getenv("HNN_PEERS")) return path;
  return default_data_path("peers.json");
}

json read_published(const fs::path& file) {
  std::ifstream in(file);
  const auto bad = [&](const std::string& what) {
    return Error(fmt::format("peers file {}: {}", file.string(), what));
  };
  if (!in) throw bad("cannot be read (HNN_PEERS names another)");
  const json doc = json::parse(in, nullptr, /*allow_exceptions=*/false);
  if (!doc.is_object() || !doc.contains("peers") || !doc["peers"].is_array())
    throw bad("expected an object with a \"peers\" list");
  for (std::size_t i = 0; i < doc["peers"].size(); ++i) {
    const json& p = doc["peers"][i];
    const auto need = [&](const char* key, bool ok, const char* what) {
      if (!ok) throw bad(fmt::format("entry {}: '{}' must be {}", i + 1, key, what));
    };
    need("peer", p.contains("peer") && p["peer"].is_string(), "a string");
    need("source", p.contains("source") && p["source"].is_string(), "a string");
    need("task", p.contains("task") && p["task"].is_string(), "a string");
    need("peer_model", p.contains("peer_model") && p["peer_model"].is_string(), "a string");
    need("value", p.contains("value") && p["value"].is_number(), "a number");
    need("model", !p.contains("model") || p["model"].is_null() || p["model"].is_string(),
         "an hnn model family or null");
    need("metric", !p.contains("metric") || p["metric"].is_null() || p["metric"].is_string(),
         "a metrics.json key or null");
    need("se", !p.contains("se") || p["se"].is_null() || p["se"].is_number(), "a number");
    need("settings", !p.contains("settings") || p["settings"].is_object(),
         "an object (the run settings of their protocol)");
    need("keys", !p.contains("keys") || p["keys"].is_object(),
         "an object (hnn train options of their protocol)");
    need("task_defaults_only",
         !p.contains("task_defaults_only") || p["task_defaults_only"].is_boolean(),
         "true or false");
  }
  return doc;
}

PaperRow paper_row(const json& published, const std::string& task, nn::ModelKind model) {
  const std::string family(nn::to_string(model));
  const auto value = [&](const char* metric) {
    for (const json& p : published["peers"]) {
      if (p["peer"] == kHnnPaper && p["task"] == task && p.value("model", json()) == family &&
          p.value("metric", json()) == metric) {
        return PaperValue{p["value"].get<double>(),
                          p.value("se", json()).is_number() ? p["se"].get<double>() : NAN};
      }
    }
    throw Error(
        fmt::format("the peers file has no entry of the HNN paper's Table 1 for {} {} {} "
                    "(peer \"{}\")",
                    task, family, metric, kHnnPaper));
  };
  return {value("train_loss"), value("test_loss"), value("energy_mse")};
}

}  // namespace hnn::tasks
