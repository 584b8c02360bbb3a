// The damped spring of the dissipative-HNN paper (Sosanya & Greydanus 2022, their synthetic
// experiment): the exact field of H = q^2 + p^2 with damping rho = 2 on a 25 x 25 grid over
// [-1.2, 1.2]^2, shuffled, 85% for training (their analysis notebook's settings). Their metric
// is the state MSE of one rollout from (0.85, 0.25) over t in [0, 4] against the truth: the
// first of the evaluation's rollouts, reported as dhnn_paper_state_mse.

#include <algorithm>
#include <numeric>

#include "physics/oscillators.h"
#include "tasks/experiments/registry.h"
#include "tasks/field/field_task.h"
#include "tasks/report/json_values.h"

namespace hnn::tasks {

namespace {

constexpr int kGrid = 25;
constexpr double kRange = 1.2, kTrainShare = 0.85;

class DampedSpringTask : public FieldTask {
 public:
  std::string name() const override { return "damped-spring"; }
  std::string summary() const override {
    return "damped spring of the D-HNN paper: H = q^2 + p^2, damping 2, a 25 x 25 grid";
  }
  // Their notebook: width 256, batch 128, 5000 steps at learning rate 1e-3, no weight decay.
  TrainConfig train_config() const override {
    return {.steps = 5000, .batch_size = 128, .learning_rate = 1e-3, .hidden = {256, 256}};
  }
  std::string table_note() const override {
    return "Damped spring: energy is H = q^2 + p^2 of the conservative part, which the true "
           "flow dissipates; dhnn_paper_state_mse is the D-HNN paper's metric (one rollout from "
           "(0.85, 0.25)), state_mse the mean over all the rollouts.";
  }
  Dataset build_dataset(const RunSettings& settings) const override {
    Batch x(kGrid * kGrid, 2);
    for (int i = 0; i < kGrid; ++i) {
      for (int j = 0; j < kGrid; ++j) {
        x(i * kGrid + j, 0) = -kRange + 2 * kRange * j / (kGrid - 1);
        x(i * kGrid + j, 1) = -kRange + 2 * kRange * i / (kGrid - 1);
      }
    }
    std::vector<Eigen::Index> order(std::size_t(x.rows()));
    std::iota(order.begin(), order.end(), 0);
    std::mt19937_64 rng(settings.seed);
    std::shuffle(order.begin(), order.end(), rng);
    const auto train = Eigen::Index(kTrainShare * double(x.rows()));
    Batch shuffled(x.rows(), 2), dxdt;
    for (Eigen::Index k = 0; k < x.rows(); ++k) shuffled.row(k) = x.row(order[std::size_t(k)]);
    spring_.vector_field(shuffled, dxdt);
    return {shuffled.topRows(train), dxdt.topRows(train), shuffled.bottomRows(x.rows() - train),
            dxdt.bottomRows(x.rows() - train)};
  }
  const physics::System& truth() const override { return spring_; }
  // The D-HNN paper's (0.85, 0.25), then states uniform over the grid's square.
  Batch rollout_states(const Dataset&, int count, std::mt19937_64& rng) const override {
    Batch x0(count, 2);
    x0.row(0) << 0.85, 0.25;
    if (count > 1) x0.bottomRows(count - 1) = spring_.sample_initial_states(count - 1, rng);
    return x0;
  }
  RolloutConfig rollout_config() const override {
    return {.t_end = 4.0, .points = 1000, .rtol = 1e-12, .atol = 1e-14};
  }
  void add_metrics(const Rollouts& r, nlohmann::json& metrics) const override {
    const bool ran = !r.failed.empty() && !r.failed[0];
    metrics["dhnn_paper_state_mse"] =
        number(ran ? (r.pred[0] - r.truth[0]).squaredNorm() / double(r.truth[0].size()) : NAN);
  }

 private:
  physics::DampedSpring spring_;
};

}  // namespace

std::unique_ptr<Task> make_damped_spring_task() { return std::make_unique<DampedSpringTask>(); }

}  // namespace hnn::tasks
