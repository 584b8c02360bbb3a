#pragma once
// Internal to tasks/: what the spring and the pendulum (tasks 1 and 2) share. 50 noisy
// trajectories of one system (oscillator_dataset), settings sample_dt and t_end, stretches for
// the rollout loss, rollouts from the evaluation states of docs/tasks.md.

#include "physics/oscillators.h"
#include "tasks/data/trajectories.h"
#include "tasks/field/field_task.h"

namespace hnn::tasks {

class OscillatorTask : public FieldTask {
 public:
  Dataset build_dataset(const RunSettings& settings) const override {
    return oscillator_dataset(truth(), settings.seed, sampling(settings));
  }
  std::vector<std::string> own_setting_names() const override { return {"sample_dt", "t_end"}; }
  // The first half of the trajectories train (oscillator_dataset).
  std::optional<SplitStretches> stretches(const RunSettings& settings,
                                          const Dataset& data) const override {
    const OscillatorSettings o = sampling(settings);
    return SplitStretches{regular_stretches(data.train_x, o.points, o.t_end),
                          regular_stretches(data.test_x, o.points, o.t_end)};
  }
  Batch rollout_states(const Dataset&, int count, std::mt19937_64& rng) const override {
    return physics::sample_evaluation_states(count, rng);
  }

 protected:
  /// `points` samples per trajectory over t in [0, 3] (the paper's), 50 trajectories.
  explicit OscillatorTask(int points) : points_(points) {}

 private:
  OscillatorSettings sampling(const RunSettings& settings) const {
    return oscillator_settings(settings.task_settings,
                               {.trajectories = 50, .points = points_, .t_end = 3.0}, name());
  }

  int points_;
};

}  // namespace hnn::tasks
