// Task 2: the ideal pendulum, H = 3(1 - cos q) + p^2 (the reference implementation's constants).

#include "physics/oscillators.h"
#include "tasks/data/trajectories.h"
#include "tasks/experiments.h"
#include "tasks/field_task.h"

namespace hnn::tasks {

namespace {

class PendulumTask : public FieldTask {
 public:
  std::string name() const override { return "pendulum"; }
  std::string summary() const override {
    return "task 2: ideal pendulum, H = 3(1 - cos q) + p^2, 50 noisy trajectories";
  }
  TrainConfig train_config() const override {
    return {.steps = 2000, .batch_size = 0, .weight_decay = 1e-4};
  }
  // The `lean` preset (docs/speed_accuracy.md, chart 4): within the noise of 200-200.
  std::vector<int> lean_hidden() const override { return {32, 32}; }
  Dataset build_dataset(const RunSettings& settings) const override {
    return oscillator_dataset(pendulum_, settings.seed, sampling(settings));
  }
  std::vector<std::string> own_setting_names() const override { return {"sample_dt", "t_end"}; }
  // The first half of the trajectories train (oscillator_dataset).
  std::optional<SplitStretches> stretches(const RunSettings& settings,
                                          const Dataset& data) const override {
    const OscillatorSettings o = sampling(settings);
    return SplitStretches{regular_stretches(data.train_x, o.points, o.t_end),
                          regular_stretches(data.test_x, o.points, o.t_end)};
  }
  const physics::System& truth() const override { return pendulum_; }
  Batch rollout_states(const Dataset&, std::mt19937_64& rng) const override {
    return physics::sample_evaluation_states(rollout_config().trajectories, rng);
  }
  PaperRow paper(nn::ModelKind model) const override {
    return model == nn::ModelKind::kHnn
               ? PaperRow{{3.2787e-2, 1.8e-3}, {3.5586e-2, 1.8e-3}, {2.4852e-2, 5.4e-3}}
               : PaperRow{{3.2606e-2, 1.7e-3}, {3.5273e-2, 1.8e-3}, {4.1519e-2, 9.6e-3}};
  }

 private:
  OscillatorSettings sampling(const RunSettings& settings) const {
    return oscillator_settings(settings.task_settings,
                               {.trajectories = 50, .points = 45, .t_end = 3.0}, name());
  }

  physics::Pendulum pendulum_;
};

}  // namespace

std::unique_ptr<Task> make_pendulum_task() { return std::make_unique<PendulumTask>(); }

}  // namespace hnn::tasks
