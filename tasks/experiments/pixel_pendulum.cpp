// Task 5, the pixel pendulum: frames of the Gym pendulum scene, an autoencoder with an HNN (or a
// baseline MLP) on its 2-D latent space (tasks/pixel/), as a task among the others.

#include "tasks/experiments/pixel_pendulum.h"

#include <fmt/ranges.h>

#include <algorithm>

#include "nn/parameter_file.h"
#include "tasks/experiments/registry.h"
#include "tasks/pixel/evaluation.h"
#include "tasks/pixel/objective.h"
#include "tasks/train/fit_method.h"
#include "tasks/trained_model.h"

namespace hnn::tasks {

namespace {

using pixel::PixelConfig;
using pixel::PixelModel;

// The settings every task has are the training settings; the task's own are the rest.
constexpr const char* kTrainKeys[] = {"steps", "batch_size", "learning_rate", "weight_decay",
                                      "hidden"};

// PixelConfig's keys but the training settings.
std::vector<std::string> task_setting_names() {
  std::vector<std::string> names;
  const nlohmann::json defaults = PixelConfig{}.to_json();  // items() refers to it
  for (const auto& [key, value] : defaults.items()) {
    if (std::find(std::begin(kTrainKeys), std::end(kTrainKeys), key) == std::end(kTrainKeys))
      names.push_back(key);
  }
  return names;
}

PixelConfig pixel_config(const RunSettings& s) {
  nlohmann::json j = PixelConfig{}.to_json();
  for (const auto& [key, value] : s.task_settings.items()) j[key] = value;
  PixelConfig c;
  try {
    c = PixelConfig::from_json(j);
  } catch (const nlohmann::json::exception& e) {
    throw Error(
        fmt::format("pixel-pendulum: bad task settings {}: {}", s.task_settings.dump(), e.what()));
  }
  c.steps = s.train.steps;
  c.batch_size = s.train.batch_size;
  c.learning_rate = s.train.learning_rate;
  c.weight_decay = s.train.weight_decay;
  HNN_TASKS_CHECK(s.train.optimizer == OptimizerKind::kAdam,
                  "pixel-pendulum: --optimizer {} does not apply: its autoencoder and latent HNN "
                  "train with Adam's L2 weight decay on the autoencoder only (task settings "
                  "weight_decay, dynamics_weight_decay)",
                  to_string(s.train.optimizer));
  c.hidden = s.train.hidden;
  c.record_every = s.train.record_every;
  pixel::validate(c);
  return c;
}

class PixelRun : public TaskRun {
 public:
  explicit PixelRun(RunSettings settings)
      : s_(std::move(settings)),
        config_(pixel_config(s_)),
        data_(pixel::build_pixel_data(config_, s_.seed)) {}

  TrainResult train(const LoopOptions& loop) override {
    return with_scalar(s_.dtype, [&]<typename T>() {
      auto model = fresh_model<T>();
      pixel::PixelObjective<T> objective(*model, data_, config_, s_.seed);
      const TrainResult result = tasks::train(objective, with_train_config(loop, s_.train));
      keep(std::move(model));
      return result;
    });
  }

  void save(const std::filesystem::path& params) const override { model_.save(params); }

  void load(const std::filesystem::path& params) override {
    with_scalar(s_.dtype, [&]<typename T>() {
      auto model = fresh_model<T>();
      nn::load_parameters(params, *model);
      keep(std::move(model));
    });
  }

  nlohmann::json evaluate(const RunFolder* folder) const override {
    nlohmann::json m = pixel::evaluate_pixel_model(model(), data_, config_, folder);
    m["pixel"] = config_.to_json();
    return m;
  }

  RolloutOutput rollout(const RolloutRequest& r) const override {
    HNN_TASKS_CHECK(!r.t_end,
                    "pixel-pendulum rollouts are counted in frames: give --points "
                    "(frames + 1), not --t-end");
    HNN_TASKS_CHECK(r.initial_states.rows() == 0,
                    "pixel-pendulum rollouts start from the test trials' frames: --state and "
                    "--states give states of the tasks that learn in phase space");
    const int n = trajectories_to_write(r, data_.test_trials(), "test trials");
    return {.csv = pixel::pixel_rollout_csv(model(), data_, nn::to_string(s_.model),
                                            {.integrator = r.integrator,
                                             .dt = r.dt,
                                             .rtol = r.rtol,
                                             .frames = r.points - 1,
                                             .trajectories = n}),
            .trajectories = n};
  }

  const nn::DynamicsModel<double>& dynamics() const override { return model().dynamics(); }

  // The encoded first pairs of the test trials.
  physics::Batch rollout_states(int count) const override {
    std::vector<Eigen::Index> rows;
    for (int i = 0; i < std::min(count, data_.test_trials()); ++i)
      rows.push_back(Eigen::Index(i) * data_.pairs_per_trial());
    return model().encode(data_.pairs_of<double>(rows, false));
  }

  double rollout_span() const override { return config_.rollout_frames; }
  std::string space() const override { return "latent"; }

  pixel::PixelParts parts() const { return {config_, data_, model(), s_.seed}; }

 private:
  template <typename T>
  std::unique_ptr<PixelModel<T>> fresh_model() const {
    std::mt19937_64 rng(s_.seed);  // the autoencoder first, then the latent MLP
    return std::make_unique<PixelModel<T>>(config_, s_.model, rng);
  }

  template <typename T>
  void keep(std::unique_ptr<PixelModel<T>> model) {
    auto in_double = std::make_unique<PixelModel<double>>(model->template cast<double>());
    model_.keep(std::move(model), std::move(in_double));
  }
  const PixelModel<double>& model() const { return model_.in_double(); }

  RunSettings s_;
  PixelConfig config_;
  pixel::PixelData data_;
  TrainedModel<PixelModel> model_;
};

class PixelPendulumTask : public Task {
 public:
  std::string name() const override { return kPixelPendulum; }
  std::string summary() const override {
    return "task 5: pixel pendulum, autoencoder + latent HNN on 28x28 Gym pendulum frames";
  }
  TrainConfig train_config() const override {
    const PixelConfig c;
    return {.steps = c.steps,
            .batch_size = c.batch_size,
            .learning_rate = c.learning_rate,
            .weight_decay = c.weight_decay,
            .hidden = c.hidden};
  }
  std::string table_note() const override {
    return "Pixel pendulum: losses are the combined ae + cc + 0.1 hnn per frame pair; energy MSE "
           "is between the true Gym state's energy and the energy of the angle and velocity "
           "recovered from the decoded frames of 200-frame latent rollouts (dopri5) from the test "
           "trials (see energy_mse_frames_floor in its metrics.json for the recovery's own error).";
  }
  // Its latent dynamics are an HNN or a baseline (the paper's); no dissipation in the Gym scene.
  std::vector<nn::ModelKind> models() const override {
    return {nn::ModelKind::kHnn, nn::ModelKind::kBaseline};
  }
  void check_task_settings(const nlohmann::json& settings) const override {
    const std::vector<std::string> known = task_setting_names();
    for (const auto& [key, value] : settings.items()) {
      for (const char* train_key : kTrainKeys) {
        HNN_TASKS_CHECK(key != train_key,
                        "pixel-pendulum: '{}' is a training setting: give it as an option "
                        "(--steps, --batch, --lr, --hidden), not a task setting",
                        key);
      }
      const std::vector<std::string>& fit = fit_setting_names();
      HNN_TASKS_CHECK(std::find(fit.begin(), fit.end(), key) == fit.end(),
                      "pixel-pendulum: --{} does not apply: its model is an autoencoder and an HNN "
                      "of its latent space trained together on frames, by Adam only (a sampled "
                      "fit solves a field model's last layer on dx/dt targets, which frames do "
                      "not give)",
                      fit_option_name(key));
      HNN_TASKS_CHECK(std::find(known.begin(), known.end(), key) != known.end(),
                      "pixel-pendulum has no setting '{}' (known: {})", key,
                      fmt::join(known, ", "));
    }
  }
  std::unique_ptr<TaskRun> open(const RunSettings& settings) const override {
    return std::make_unique<PixelRun>(settings);
  }
  // Figure 4: truth, baseline and HNN rollouts side by side.
  bool has_comparison() const override { return true; }
  void write_comparison(const TaskRun& baseline, const TaskRun& hnn,
                        const std::filesystem::path& out) const override {
    pixel::write_comparison(pixel_parts(baseline), pixel_parts(hnn), out);
  }
};

}  // namespace

pixel::PixelParts pixel_parts(const TaskRun& run) {
  const auto* pixel_run = dynamic_cast<const PixelRun*>(&run);
  HNN_TASKS_CHECK(pixel_run != nullptr, "this command needs a pixel-pendulum run");
  return pixel_run->parts();
}

std::unique_ptr<Task> make_pixel_pendulum_task() { return std::make_unique<PixelPendulumTask>(); }

}  // namespace hnn::tasks
