// Task 2: the ideal pendulum, H = 3(1 - cos q) + p^2 (the reference implementation's constants).

#include "physics/oscillators.h"
#include "tasks/experiments/oscillator_task.h"
#include "tasks/experiments/registry.h"

namespace hnn::tasks {

namespace {

class PendulumTask : public OscillatorTask {
 public:
  PendulumTask() : OscillatorTask(45) {}
  std::string name() const override { return "pendulum"; }
  std::string summary() const override {
    return "task 2: ideal pendulum, H = 3(1 - cos q) + p^2, 50 noisy trajectories";
  }
  TrainConfig train_config() const override {
    return {.steps = 2000, .batch_size = 0, .weight_decay = 1e-4};
  }
  // The `lean` preset (docs/speed_accuracy.md, chart 4): within the noise of 200-200.
  std::vector<int> lean_hidden() const override { return {32, 32}; }
  const physics::System& truth() const override { return pendulum_; }

 private:
  physics::Pendulum pendulum_;
};

}  // namespace

std::unique_ptr<Task> make_pendulum_task() { return std::make_unique<PendulumTask>(); }

}  // namespace hnn::tasks
