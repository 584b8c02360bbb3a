// Training checkpoints: the matrices through nn's parameter files, the rest as JSON, committed
// in the order of Note [Checkpoint commit] (tasks/train/checkpoint.h).

#include "tasks/train/checkpoint.h"

#include <algorithm>
#include <cmath>
#include <fstream>

#include "nn/atomic_file.h"
#include "nn/parameter_file.h"
#include "tasks/error.h"
#include "tasks/report/json_values.h"
#include "tasks/train/stop.h"

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
void save_train_checkpoint(const fs::path& dir, const nn::Module<T>& model, const nn::Adam<T>& adam,
                           TrainState state) {
  fs::create_directories(dir);
  state.params_file = fmt::format("step-{:09d}.bin", state.step);
  const nn::AdamState<T> moments = adam.state();
  nn::save_parameters(dir / state.params_file, matrices_kind(model),
                      matrices(model, moments.m, moments.v));
  nn::write_file_atomic(dir / kStateFile, to_json(state).dump() + "\n");
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
                           nn::Adam<T>& adam) {
  nn::AdamState<T> moments = adam.state();
  std::vector<nn::NamedParameter<T>> list = matrices(model, moments.m, moments.v);
  nn::load_parameters(dir / state.params_file, matrices_kind(model), list);
  // The moment leaves were filled by the load; the model's own leaves are list[0, n).
  const std::size_t n = moments.m.size();
  for (std::size_t i = 0; i < n; ++i) {
    moments.m[i] = list[n + i].var.value();
    moments.v[i] = list[2 * n + i].var.value();
  }
  moments.steps = state.step;
  adam.load_state(std::move(moments));
}

template <typename T>
RunCheckpoints<T>::RunCheckpoints(fs::path dir, long every, long total_steps, json run,
                                  std::uint64_t data_hash, long restored_steps)
    : dir_(std::move(dir)),
      every_(every > 0 ? every : std::max(1L, total_steps / 10)),
      total_steps_(total_steps),
      restored_steps_(restored_steps > 0 ? restored_steps : total_steps),
      run_(std::move(run)),
      data_hash_(data_hash) {}

template <typename T>
void RunCheckpoints<T>::save(long step, Objective<T>& objective, const nn::Adam<T>& adam,
                             const std::vector<CurvePoint>& curve, double seconds) {
  const auto finite = [](const ad::Var<T>& p) { return p.value().allFinite(); };
  if (!std::ranges::all_of(adam.parameters(), finite))
    throw TrainingDiverged::at(step, "the parameters are not finite", last_good());
  TrainState state{.step = step,
                   .total_steps = total_steps_,
                   .sampler_state = objective.sampler().state(),
                   .data_hash = data_hash_,
                   .curve = curve,
                   .seconds = seconds,
                   .run = run_};
  save_train_checkpoint<T>(dir_, objective.model(), adam, std::move(state));
  last_saved_ = step;
}

template <typename T>
TrainState RunCheckpoints<T>::restore(Objective<T>& objective, nn::Adam<T>& adam) {
  TrainState state = read_train_state(dir_);
  HNN_TASKS_CHECK(state.total_steps == restored_steps_,
                  "the checkpoint in '{}' is of a run of {} steps, not {}", dir_.string(),
                  state.total_steps, restored_steps_);
  HNN_TASKS_CHECK(state.data_hash == data_hash_,
                  "the training data differ from those of the checkpoint in '{}'", dir_.string());
  load_train_checkpoint<T>(dir_, state, objective.model(), adam);
  objective.sampler().set_state(state.sampler_state);
  last_saved_ = state.step;
  return state;
}

template <typename T>
std::string RunCheckpoints<T>::last_good() const {
  return last_saved_ > 0 ? fmt::format("; the last good checkpoint (step {}) is kept in {}",
                                       last_saved_, dir_.string())
                         : "";
}

template void save_train_checkpoint(const fs::path&, const nn::Module<float>&,
                                    const nn::Adam<float>&, TrainState);
template void save_train_checkpoint(const fs::path&, const nn::Module<double>&,
                                    const nn::Adam<double>&, TrainState);
template void load_train_checkpoint(const fs::path&, const TrainState&, nn::Module<float>&,
                                    nn::Adam<float>&);
template void load_train_checkpoint(const fs::path&, const TrainState&, nn::Module<double>&,
                                    nn::Adam<double>&);
template class RunCheckpoints<float>;
template class RunCheckpoints<double>;

}  // namespace hnn::tasks
