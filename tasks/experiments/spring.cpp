// Task 1: the ideal mass-spring, H = q^2 + p^2 (the reference implementation's constants).

#include "physics/oscillators.h"
#include "tasks/experiments/oscillator_task.h"
#include "tasks/experiments/registry.h"

namespace hnn::tasks {

namespace {

class SpringTask : public OscillatorTask {
 public:
  SpringTask() : OscillatorTask(30) {}
  std::string name() const override { return "spring"; }
  std::string summary() const override {
    return "task 1: ideal mass-spring, H = q^2 + p^2, 50 noisy trajectories";
  }
  TrainConfig train_config() const override {
    return {.steps = 2000, .batch_size = 0, .weight_decay = 1e-4};
  }
  // The `lean` preset (docs/speed_accuracy.md, chart 4): within the noise of 200-200.
  std::vector<int> lean_hidden() const override { return {16, 16}; }
  const physics::System& truth() const override { return spring_; }

 private:
  physics::Spring spring_;
};

}  // namespace

std::unique_ptr<Task> make_spring_task() { return std::make_unique<SpringTask>(); }

}  // namespace hnn::tasks
