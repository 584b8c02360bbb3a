// Tasks 4 and 4b: two and three bodies under gravity in the plane (masses 1, G = 1).

#include "physics/nbody.h"

#include "tasks/data/trajectories.h"
#include "tasks/experiments.h"
#include "tasks/field_task.h"

namespace hnn::tasks {

namespace {

struct NBodySettings {
  int bodies, trajectories, points;
  double t_end;
  TrainConfig train;
  // The `lean` preset (docs/speed_accuracy.md, chart 4): lean_depth layers of lean_width. Two
  // ints, not a vector: a second vector in this aggregate set off GCC 12's -Wmaybe-uninitialized.
  int lean_width, lean_depth;
  RolloutConfig rollout;
  PaperRow baseline, hnn;
};

class NBodyTask : public FieldTask {
 public:
  explicit NBodyTask(NBodySettings settings)
      : settings_(std::move(settings)), system_(physics::NBody::equal_masses(settings_.bodies)) {}

  std::string name() const override { return settings_.bodies == 2 ? "two-body" : "three-body"; }
  std::string summary() const override {
    return fmt::format("task {}: {} bodies under gravity, {} trajectories of {} points",
                       settings_.bodies == 2 ? "4" : "4b", settings_.bodies, settings_.trajectories,
                       settings_.points);
  }
  TrainConfig train_config() const override { return settings_.train; }
  std::vector<int> lean_hidden() const override {
    return std::vector<int>(std::size_t(settings_.lean_depth), settings_.lean_width);
  }
  RolloutConfig rollout_config() const override { return settings_.rollout; }
  /// Exact derivatives, no noise; the first 20% of points (whole trajectories) are the test set.
  Dataset build_dataset(const RunSettings& settings) const override {
    std::mt19937_64 rng(settings.seed);
    const Batch x0 = system_.sample_initial_states(settings_.trajectories, rng);
    const TrajectorySamples s =
        sample_trajectories(system_, x0, settings_.t_end, settings_.points, /*rtol=*/1e-9);
    const Eigen::Index cut = s.x.rows() / 5;
    Dataset d;
    std::tie(d.test_x, d.train_x) = split_rows(s.x, cut);
    std::tie(d.test_dxdt, d.train_dxdt) = split_rows(s.dxdt, cut);
    return d;
  }
  const physics::System& truth() const override { return system_; }
  Batch rollout_states(const Dataset&, std::mt19937_64& rng) const override {
    return system_.sample_initial_states(settings_.rollout.trajectories, rng);
  }
  PaperRow paper(nn::ModelKind model) const override {
    return model == nn::ModelKind::kHnn ? settings_.hnn : settings_.baseline;
  }

 private:
  NBodySettings settings_;
  physics::NBody system_;
};

}  // namespace

std::unique_ptr<Task> make_two_body_task() {
  return std::make_unique<NBodyTask>(NBodySettings{
      .bodies = 2,
      .trajectories = 1000,
      .points = 50,
      .t_end = 20.0,
      .train = {.steps = 10000, .batch_size = 200, .weight_decay = 0.0},
      .lean_width = 32,  // 18x faster to train, test loss and energy MSE within the noise
      .lean_depth = 2,
      .rollout = {.trajectories = 15, .t_end = 20.0, .points = 1000},
      .baseline = {{3.2682e-5, 1.2e-6}, {2.9575e-5, 8.9e-7}, {6.3276e-2, 3.4e-2}},
      .hnn = {{2.9959e-6, 6.6e-8}, {2.8218e-6, 4.2e-8}, {3.8751e-5, 5.0e-6}}});
}

std::unique_ptr<Task> make_three_body_task() {
  return std::make_unique<NBodyTask>(NBodySettings{
      .bodies = 3,
      .trajectories = 5000,
      .points = 20,
      .t_end = 5.0,
      .train = {.steps = 10000, .batch_size = 600, .weight_decay = 1e-4},
      // The paper's: every smaller model's energy MSE blew up on some seed of the sweep.
      .lean_width = 200,
      .lean_depth = 2,
      .rollout = {.trajectories = 15, .t_end = 20.0, .points = 100},
      .baseline = {{9.5573e-2, 6.6e-2}, {3.8000e-1, 4.2e-1}, {1.0906e+2, 7.7e+1}},
      .hnn = {{8.0346e-2, 2.1e-2}, {4.8809e-1, 4.8e-1}, {4.1926e-2, 3.4e-2}}});
}

}  // namespace hnn::tasks
