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
  PaperRow paper(nn::ModelKind model) const override {
    return model == nn::ModelKind::kHnn
               ? PaperRow{{3.6933e-2, 1.9e-3}, {3.5928e-2, 1.8e-3}, {3.8416e-4, 6.5e-5}}
               : PaperRow{{3.7134e-2, 1.9e-3}, {3.6656e-2, 1.9e-3}, {1.7077e-1, 2.1e-2}};
  }

 private:
  physics::Spring spring_;
};

}  // namespace

std::unique_ptr<Task> make_spring_task() { return std::make_unique<SpringTask>(); }

}  // namespace hnn::tasks
