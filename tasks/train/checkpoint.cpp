// Training checkpoints: the matrices through nn's parameter files, the rest as JSON, committed
// in the order of Note [Checkpoint commit] (tasks/train/checkpoint.h).

#include "tasks/train/checkpoint.h"

#include <cmath>
#include <fstream>

#include "nn/checkpoint.h"
#include "tasks/error.h"
#include "tasks/report/atomic_file.h"
#include "tasks/report/json_values.h"

namespace hnn::tasks {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr int kStateVersion = 1;
constexpr const char* kStateFile = "state.json";

// The .bin's entries: the model's parameters, then Adam's first and second moments.
template <typename T>
std::vector<nn::NamedParameter<T>> matrices(const nn::Module<T>& model,
                                            const std::vector<nn::Matrix<T>>& m,
                                            const std::vector<nn::Matrix<T>>& v) {
  std::vector<nn::NamedParameter<T>> list = model.named_parameters();
  const std::size_t n = list.size();
  for (std::size_t i = 0; i < n; ++i) {
    list.push_back({"adam.m/" + list[i].name, ad::Var<T>::leaf(m.at(i), false)});
  }
  for (std::size_t i = 0; i < n; ++i) {
    list.push_back({"adam.v/" + list[i].name, ad::Var<T>::leaf(v.at(i), false)});
  }
  for (std::size_t i = 0; i < n; ++i) list[i].name = "model/" + list[i].name;
  return list;
}

template <typename T>
std::string matrices_kind(const nn::Module<T>& model) {
  return "train-checkpoint+adam:" + model.kind();
}

// Every group's moments end to end: the groups list the model's parameters in order.
template <typename T>
nn::AdamState<T> joined_state(std::span<const nn::Adam<T>> adams) {
  nn::AdamState<T> all;
  for (const nn::Adam<T>& adam : adams) {
    nn::AdamState<T> s = adam.state();
    all.steps = s.steps;
    all.m.insert(all.m.end(), s.m.begin(), s.m.end());
    all.v.insert(all.v.end(), s.v.begin(), s.v.end());
  }
  return all;
}

json to_json(const TrainState& s) {
  json curve = json::array();
  for (const CurvePoint& p : s.curve) {
    curve.push_back({p.step, number(p.train_loss), number(p.test_loss)});
  }
  return {{"format", "hnn training checkpoint"},
          {"version", kStateVersion},
          {"step", s.step},
          {"total_steps", s.total_steps},
          {"params_file", s.params_file},
          {"sampler_state", s.sampler_state},
          {"data_hash", s.data_hash},
          {"seconds", s.seconds},
          {"curve", curve},
          {"run", s.run}};
}

// Throws Error or json::exception saying what is wrong (read_train_state adds the file).
TrainState from_json(const json& j) {
  HNN_TASKS_CHECK(j.is_object() && j.contains("format") && j["format"] == "hnn training checkpoint",
                  "it is not an hnn training checkpoint");
  const int version = json_integer<int>(j.at("version"), "version");
  HNN_TASKS_CHECK(version == kStateVersion, "format version {}, but this build reads version {}",
                  version, kStateVersion);
  TrainState s;
  s.step = json_integer<long>(j.at("step"), "step");
  s.total_steps = json_integer<long>(j.at("total_steps"), "total_steps");
  s.params_file = j.at("params_file");
  s.sampler_state = j.at("sampler_state");
  s.data_hash = json_integer<std::uint64_t>(j.at("data_hash"), "data_hash");
  s.seconds = j.at("seconds");
  s.run = j.at("run");
  for (const json& p : j.at("curve")) {
    s.curve.push_back({json_integer<long>(p.at(0), "a curve step"), number_or_nan(p.at(1)),
                       number_or_nan(p.at(2))});
  }
  HNN_TASKS_CHECK(s.step >= 0 && s.step <= s.total_steps && s.total_steps > 0,
                  "step {} of {} is out of range", s.step, s.total_steps);
  // The .bin must be a plain name inside the folder, as written.
  HNN_TASKS_CHECK(
      fs::path(s.params_file).filename() == s.params_file && s.params_file.starts_with("step-"),
      "params_file '{}' is not a checkpoint of this folder", s.params_file);
  return s;
}

}  // namespace

template <typename T>
void save_train_checkpoint(const fs::path& dir, const nn::Module<T>& model,
                           std::span<const nn::Adam<T>> adams, TrainState state) {
  fs::create_directories(dir);
  state.params_file = fmt::format("step-{:09d}.bin", state.step);
  const nn::AdamState<T> moments = joined_state(adams);
  nn::save_parameters(dir / state.params_file, matrices_kind(model),
                      matrices(model, moments.m, moments.v));
  write_file_atomic(dir / kStateFile, to_json(state).dump() + "\n");
  for (const fs::directory_entry& entry : fs::directory_iterator(dir)) {
    const std::string name = entry.path().filename().string();
    if (name != kStateFile && name != state.params_file) fs::remove_all(entry.path());
  }
}

TrainState read_train_state(const fs::path& dir) {
  const fs::path file = dir / kStateFile;
  std::ifstream in(file);
  HNN_TASKS_CHECK(in.good(), "no checkpoint in '{}' (cannot read '{}')", dir.string(),
                  file.string());
  try {
    return from_json(json::parse(in));
  } catch (const json::exception& e) {
    throw Error(fmt::format("'{}' is not a readable checkpoint: {}", file.string(), e.what()));
  } catch (const Error& e) {
    throw Error(fmt::format("'{}' is not a readable checkpoint: {}", file.string(), e.what()));
  }
}

template <typename T>
void load_train_checkpoint(const fs::path& dir, const TrainState& state, nn::Module<T>& model,
                           std::span<nn::Adam<T>> adams) {
  nn::AdamState<T> moments = joined_state<T>(adams);
  std::vector<nn::NamedParameter<T>> list = matrices(model, moments.m, moments.v);
  nn::load_parameters(dir / state.params_file, matrices_kind(model), list);
  // The moment leaves were filled by the load; the model's own leaves are list[0, n).
  const std::size_t n = moments.m.size();
  std::size_t first = 0;
  for (nn::Adam<T>& adam : adams) {
    nn::AdamState<T> group = adam.state();
    for (std::size_t i = 0; i < group.m.size(); ++i) {
      group.m[i] = list[n + first + i].var.value();
      group.v[i] = list[2 * n + first + i].var.value();
    }
    first += group.m.size();
    group.steps = state.step;
    adam.load_state(std::move(group));
  }
}

template void save_train_checkpoint(const fs::path&, const nn::Module<float>&,
                                    std::span<const nn::Adam<float>>, TrainState);
template void save_train_checkpoint(const fs::path&, const nn::Module<double>&,
                                    std::span<const nn::Adam<double>>, TrainState);
template void load_train_checkpoint(const fs::path&, const TrainState&, nn::Module<float>&,
                                    std::span<nn::Adam<float>>);
template void load_train_checkpoint(const fs::path&, const TrainState&, nn::Module<double>&,
                                    std::span<nn::Adam<double>>);

}  // namespace hnn::tasks
