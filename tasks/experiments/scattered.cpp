// The sampled-HNN paper's three protocols (Rahma, Datar & Dietrich 2024; AlphaGergedan/
// Sampling-HNNs: src/*_experiment.py, data/grid.py, hamiltonian/*.py): states drawn uniformly in
// a box with their exact time derivatives, training and test points drawn apart, no
// trajectories. A run is judged on the test points (evaluate_field_points): the field's loss and
// R^2, and the paper's metric, the relative L2 error of H (hamiltonian_rel_l2).

#include <cmath>
#include <numbers>

#include "physics/double_pendulum.h"
#include "physics/henon_heiles.h"
#include "physics/oscillators.h"
#include "tasks/experiments/registry.h"
#include "tasks/field/field_task.h"

namespace hnn::tasks {

namespace {

using nlohmann::json;
using physics::ValueRange;

// A protocol's points and box: every coordinate in q, every momentum in p.
struct Box {
  int train = 0, test = 0;
  ValueRange q, p;
};

constexpr int kMaxPoints = 10'000'000;

int points_setting(const json& s, const char* key, int fallback, int least,
                   const std::string& task) {
  if (!s.contains(key)) return fallback;
  const json& v = s[key];
  HNN_TASKS_CHECK(v.is_number_integer() && v.get<std::int64_t>() >= least &&
                      v.get<std::int64_t>() <= kMaxPoints,
                  "{}: {} must be an integer from {} to {}, got {}", task, key, least, kMaxPoints,
                  v.dump());
  return v.get<int>();
}

ValueRange range_setting(const json& s, const char* key, ValueRange fallback,
                         const std::string& task) {
  if (!s.contains(key)) return fallback;
  const json& v = s[key];
  const bool pair = v.is_array() && v.size() == 2 && v[0].is_number() && v[1].is_number();
  const ValueRange r = pair ? ValueRange{v[0].get<double>(), v[1].get<double>()} : ValueRange{};
  HNN_TASKS_CHECK(pair && std::isfinite(r.lo) && std::isfinite(r.hi) && r.lo < r.hi,
                  "{}: {} must be [LO, HI] with finite LO < HI, got {}", task, key, v.dump());
  return r;
}

class ScatteredTask : public FieldTask {
 public:
  std::string name() const override { return name_; }
  std::string summary() const override { return summary_; }
  // Adam on minibatches of the paper's size (their Adam-trained HNN: batch 2048).
  TrainConfig train_config() const override {
    return {.steps = 5000, .batch_size = 2048, .learning_rate = 1e-3, .hidden = {200, 200}};
  }
  bool scattered() const override { return true; }
  std::vector<std::string> own_setting_names() const override {
    return {"train_points", "test_points", "q_range", "p_range"};
  }

  Dataset build_dataset(const RunSettings& s) const override {
    const Box b = box(s.task_settings);
    const std::unique_ptr<physics::System> system = truth_for(s);
    const auto dof = std::size_t(system->dim() / 2);
    std::vector<ValueRange> ranges(dof, b.q);
    ranges.insert(ranges.end(), dof, b.p);
    std::mt19937_64 rng(s.seed);
    Dataset d;
    d.train_x = physics::sample_box(b.train, ranges, rng);
    d.test_x = physics::sample_box(b.test, ranges, rng);
    system->vector_field(d.train_x, d.train_dxdt);
    system->vector_field(d.test_x, d.test_dxdt);
    return d;
  }
  const physics::System& truth() const override { return *default_truth_; }
  std::unique_ptr<physics::System> truth_for(const RunSettings& s) const override {
    return make_system(s.task_settings);
  }
  // `hnn rollout` and reversibility start from the first test points, over one time unit by
  // default: most states of Hénon-Heiles' box lie far above its escape energy 1/6 and leave
  // within a few.
  RolloutConfig rollout_config() const override { return {.t_end = 1.0, .points = 101}; }
  Batch rollout_states(const Dataset& data, int count, std::mt19937_64&) const override {
    return data.test_x.topRows(std::min<Eigen::Index>(count, data.test_x.rows()));
  }

 protected:
  ScatteredTask(std::string name, std::string summary, Box paper)
      : name_(std::move(name)), summary_(std::move(summary)), paper_(paper) {}
  /// The true system under the run's settings (checked here, before a run folder exists).
  virtual std::unique_ptr<physics::System> make_system(const json& settings) const = 0;
  void set_default_truth() { default_truth_ = make_system(json::object()); }

 private:
  Box box(const json& s) const {
    return {.train = points_setting(s, "train_points", paper_.train, 2, name_),
            .test = points_setting(s, "test_points", paper_.test, 1, name_),
            .q = range_setting(s, "q_range", paper_.q, name_),
            .p = range_setting(s, "p_range", paper_.p, name_)};
  }

  std::string name_, summary_;
  Box paper_;
  std::unique_ptr<physics::System> default_truth_;
};

// henon_heiles_experiment.py: alpha = 1 (their sweep runs 0 to 1), [-5, 5]^4, 20k/20k.
class HenonHeilesTask : public ScatteredTask {
 public:
  HenonHeilesTask()
      : ScatteredTask("henon-heiles",
                      "Henon-Heiles, alpha = 1, 20k/20k states uniform in [-5, 5]^4 with exact "
                      "derivatives (the sampled-HNN paper's)",
                      {.train = 20000, .test = 20000, .q = {-5, 5}, .p = {-5, 5}}) {
    set_default_truth();
  }
  std::vector<std::string> own_setting_names() const override {
    std::vector<std::string> names = ScatteredTask::own_setting_names();
    names.push_back("alpha");
    return names;
  }

 protected:
  std::unique_ptr<physics::System> make_system(const json& s) const override {
    const json alpha = s.value("alpha", json(1.0));
    HNN_TASKS_CHECK(
        alpha.is_number() && std::isfinite(alpha.get<double>()) && alpha.get<double>() >= 0,
        "henon-heiles: alpha must be a finite number >= 0, got {}", alpha.dump());
    return std::make_unique<physics::HenonHeiles>(alpha.get<double>());
  }
};

// single_pendulum_experiment.py's first domain: H = p^2/2 + (1 - cos q) (m = l = g = 1).
class PendulumScatteredTask : public ScatteredTask {
 public:
  PendulumScatteredTask()
      : ScatteredTask("pendulum-scattered",
                      "pendulum H = p^2/2 + 1 - cos q, 10k/10k states uniform in [-2 pi, 2 pi] x "
                      "[-1, 1] with exact derivatives (the sampled-HNN paper's)",
                      {.train = 10000,
                       .test = 10000,
                       .q = {-2 * std::numbers::pi, 2 * std::numbers::pi},
                       .p = {-1, 1}}) {
    set_default_truth();
  }

 protected:
  std::unique_ptr<physics::System> make_system(const json&) const override {
    return std::make_unique<physics::Pendulum>(/*potential=*/1.0, /*kinetic=*/0.5);
  }
};

// double_pendulum_experiment.py: m = l = g = 1 in canonical coordinates, the potential zero at
// the pivot as their H has it; q in [-pi, pi]^2, p in [-1, 1]^2, 20k/20k.
class DoublePendulumScatteredTask : public ScatteredTask {
 public:
  DoublePendulumScatteredTask()
      : ScatteredTask("double-pendulum-scattered",
                      "double pendulum, m = l = g = 1, canonical: 20k/20k states uniform in q in "
                      "[-pi, pi]^2, p in [-1, 1]^2 with exact derivatives (the sampled-HNN "
                      "paper's)",
                      {.train = 20000,
                       .test = 20000,
                       .q = {-std::numbers::pi, std::numbers::pi},
                       .p = {-1, 1}}) {
    set_default_truth();
  }

 protected:
  std::unique_ptr<physics::System> make_system(const json&) const override {
    return std::make_unique<physics::DoublePendulum>(
        1.0, 1.0, 1.0, 1.0, 1.0, physics::DoublePendulum::PotentialZero::kAtPivot);
  }
};

}  // namespace

std::unique_ptr<Task> make_henon_heiles_task() { return std::make_unique<HenonHeilesTask>(); }
std::unique_ptr<Task> make_pendulum_scattered_task() {
  return std::make_unique<PendulumScatteredTask>();
}
std::unique_ptr<Task> make_double_pendulum_scattered_task() {
  return std::make_unique<DoublePendulumScatteredTask>();
}

}  // namespace hnn::tasks
