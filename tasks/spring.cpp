// Task 1: the ideal mass-spring, H = q^2 + p^2 (the reference implementation's constants).

#include "physics/oscillators.h"
#include "tasks/data/trajectories.h"
#include "tasks/experiments.h"
#include "tasks/field_task.h"

namespace hnn::tasks {

namespace {

class SpringTask : public FieldTask {
 public:
  std::string name() const override { return "spring"; }
  std::string summary() const override {
    return "task 1: ideal mass-spring, H = q^2 + p^2, 50 noisy trajectories";
  }
  TrainConfig train_config() const override {
    return {.steps = 2000, .batch_size = 0, .weight_decay = 1e-4};
  }
  // The `lean` preset (docs/speed_accuracy.md, chart 4): within the noise of 200-200.
  std::vector<int> lean_hidden() const override { return {16, 16}; }
  Dataset build_dataset(const RunSettings& settings) const override {
    return oscillator_dataset(spring_, settings.seed, sampling(settings));
  }
  std::vector<std::string> own_setting_names() const override { return {"sample_dt", "t_end"}; }
  // The first half of the trajectories train (oscillator_dataset).
  std::optional<SplitStretches> stretches(const RunSettings& settings,
                                          const Dataset& data) const override {
    const OscillatorSettings o = sampling(settings);
    return SplitStretches{regular_stretches(data.train_x, o.points, o.t_end),
                          regular_stretches(data.test_x, o.points, o.t_end)};
  }
  const physics::System& truth() const override { return spring_; }
  Batch rollout_states(const Dataset&, std::mt19937_64& rng) const override {
    return physics::sample_evaluation_states(rollout_config().trajectories, rng);
  }
  PaperRow paper(nn::ModelKind model) const override {
    return model == nn::ModelKind::kHnn
               ? PaperRow{{3.6933e-2, 1.9e-3}, {3.5928e-2, 1.8e-3}, {3.8416e-4, 6.5e-5}}
               : PaperRow{{3.7134e-2, 1.9e-3}, {3.6656e-2, 1.9e-3}, {1.7077e-1, 2.1e-2}};
  }

 private:
  OscillatorSettings sampling(const RunSettings& settings) const {
    return oscillator_settings(settings.task_settings,
                               {.trajectories = 50, .points = 30, .t_end = 3.0}, name());
  }

  physics::Spring spring_;
};

}  // namespace

std::unique_ptr<Task> make_spring_task() { return std::make_unique<SpringTask>(); }

}  // namespace hnn::tasks
