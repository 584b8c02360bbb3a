// hnn compare's peers (peers.h).

#include "apps/hnn/compare/peers.h"

#include <fmt/format.h>

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <stdexcept>

#include "apps/hnn/sweep/launch.h"
#include "tasks/experiments/registry.h"
#include "tasks/task.h"

namespace hnn::app {

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

constexpr const char* kTable1Protocol =
    "the HNN paper's settings (each task's defaults); train and test loss: MSE of dx/dt over the "
    "split; energy: MSE of the true energy along true and learned rollouts";

}  // namespace

fs::path peers_path() { return sweep::shared_file("HNN_PEERS", "peers.json", HNN_PEERS_SOURCE); }

json read_peers(const fs::path& file) {
  std::ifstream in(file);
  const auto bad = [&](const std::string& what) {
    return std::invalid_argument(fmt::format("peers file {}: {}", file.string(), what));
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
  }
  return doc;
}

json table1_peers(const std::vector<std::string>& names) {
  json out = json::array();
  const std::vector<std::string> paper_tasks = tasks::paper_task_names();
  for (const std::string& name : names) {
    if (std::find(paper_tasks.begin(), paper_tasks.end(), name) == paper_tasks.end()) continue;
    const auto task = tasks::make_task(name);
    for (const nn::ModelKind model : {nn::ModelKind::kBaseline, nn::ModelKind::kHnn}) {
      const tasks::PaperRow paper = task->paper(model);
      const std::pair<const char*, tasks::PaperValue> values[] = {{"train_loss", paper.train_loss},
                                                                  {"test_loss", paper.test_loss},
                                                                  {"energy_mse", paper.energy_mse}};
      for (const auto& [metric, v] : values) {
        out.push_back({{"peer", "HNN (Greydanus et al. 2019)"},
                       {"source", "the HNN paper's Table 1 (hnn: Task::paper() of tasks/" + name +
                                      ", as hnn reproduce's table1.md)"},
                       {"task", name},
                       {"model", nn::to_string(model)},
                       {"loss", "derivative"},
                       {"peer_model", model == nn::ModelKind::kHnn ? "HNN" : "baseline MLP"},
                       {"metric", metric},
                       {"value", v.mean},
                       {"se", v.se},
                       {"n", "the paper's seeds"},
                       {"protocol", kTable1Protocol},
                       {"task_defaults_only", true}});
      }
    }
  }
  return out;
}

}  // namespace hnn::app
