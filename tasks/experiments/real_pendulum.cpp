// Task 3: the real pendulum of Schmidt & Lipson (2009), from measured angles and velocities.
// It has friction, which an HNN cannot model: its test loss is expected to be worse than the
// baseline's while its energy stays nearly constant.

#include "physics/lipson.h"
#include "physics/oscillators.h"
#include "tasks/data/data_files.h"
#include "tasks/data/trajectories.h"
#include "tasks/experiments/registry.h"
#include "tasks/field/field_task.h"

namespace hnn::tasks {

namespace {

class RealPendulumTask : public FieldTask {
 public:
  std::string name() const override { return "real-pendulum"; }
  std::string summary() const override {
    return "task 3: real pendulum, Schmidt & Lipson (2009) measured data, has friction";
  }
  TrainConfig train_config() const override {
    return {.steps = 2000, .batch_size = 0, .weight_decay = 1e-5};
  }
  // The `lean` preset (docs/speed_accuracy.md, chart 4): within the noise of 200-200.
  std::vector<int> lean_hidden() const override { return {16, 16}; }
  Dataset build_dataset(const RunSettings& settings) const override {
    const physics::LipsonData data = load(settings);
    Batch x, dxdt;
    forward_differences(data, x, dxdt);
    const Eigen::Index cut = x.rows() * 8 / 10;  // order kept: the test set is the run's end
    Dataset d;
    std::tie(d.train_x, d.test_x) = split_rows(x, cut);
    std::tie(d.train_dxdt, d.test_dxdt) = split_rows(dxdt, cut);
    return d;
  }
  // The reference's fit to this data: H = 2.4 (1 - cos q) + p^2.
  const physics::System& truth() const override { return fit_; }
  /// Measured test states, evenly spread over the test run: `count` of them, or every test state
  /// when there are fewer (111 in the shipped file).
  Batch rollout_states(const Dataset& data, int count, std::mt19937_64&) const override {
    const Eigen::Index n = std::min<Eigen::Index>(count, data.test_x.rows());
    Batch states(n, 2);
    for (Eigen::Index i = 0; i < n; ++i)
      states.row(i) = data.test_x.row(i * data.test_x.rows() / n);
    return states;
  }
  bool reads_data_file() const override { return true; }
  // Consecutive rows of one trial on one side of the split, at the file's times.
  std::optional<SplitStretches> stretches(const RunSettings& settings,
                                          const Dataset& data) const override {
    const physics::LipsonData file = load(settings);
    const std::vector<Eigen::Index> rows = sample_rows(file);
    const Eigen::MatrixXd state = file.state().leftCols(2);
    const auto cut = std::size_t(data.train_x.rows());
    SplitStretches out;
    for (std::size_t k = 0; k < rows.size();) {
      std::size_t end = k + 1;
      while (end < rows.size() && end != cut && file.trial(rows[end]) == file.trial(rows[k])) ++end;
      Stretch s{Eigen::VectorXd(Eigen::Index(end - k)), Batch(Eigen::Index(end - k), 2)};
      for (std::size_t i = k; i < end; ++i) {
        s.t(Eigen::Index(i - k)) = file.t(rows[i]);
        s.x.row(Eigen::Index(i - k)) = state.row(rows[i]);
      }
      (k < cut ? out.train : out.test).push_back(std::move(s));
      k = end;
    }
    return out;
  }

 private:
  static physics::LipsonData load(const RunSettings& settings) {
    return physics::load_lipson(settings.data_file.empty() ? default_data_path(kDataFile)
                                                           : settings.data_file);
  }

  // The rows with a successor in their trial: the samples of forward_differences.
  static std::vector<Eigen::Index> sample_rows(const physics::LipsonData& data) {
    std::vector<Eigen::Index> rows;
    for (Eigen::Index i = 0; i + 1 < data.rows(); ++i)
      if (data.trial(i) == data.trial(i + 1)) rows.push_back(i);
    return rows;
  }

  static constexpr std::size_t kMinSamples = 10;

  // x = (angle, angular velocity); dx/dt by forward differences within each trial, the last
  // point of each trial dropped.
  static void forward_differences(const physics::LipsonData& data, Batch& x, Batch& dxdt) {
    HNN_TASKS_CHECK(data.columns.size() >= 2, "{}: expected angle and velocity columns, got {}",
                    data.path, data.columns.size());
    const Eigen::MatrixXd state = data.state().leftCols(2);
    const std::vector<Eigen::Index> rows = sample_rows(data);
    HNN_TASKS_CHECK(rows.size() >= kMinSamples,
                    "{}: {} samples (pairs of consecutive rows in one trial); at least {} are "
                    "needed to train and test",
                    data.path, rows.size(), kMinSamples);
    x.resize(Eigen::Index(rows.size()), 2);
    dxdt.resize(Eigen::Index(rows.size()), 2);
    for (std::size_t k = 0; k < rows.size(); ++k) {
      const Eigen::Index i = rows[k];
      const double dt = data.t(i + 1) - data.t(i);
      HNN_TASKS_CHECK(dt > 0, "{}:{}: time does not increase within trial {} (t = {} then {})",
                      data.path, data.line(i + 1), data.trial(i), data.t(i), data.t(i + 1));
      x.row(Eigen::Index(k)) = state.row(i);
      dxdt.row(Eigen::Index(k)) = (state.row(i + 1) - state.row(i)) / dt;
    }
  }

  static constexpr const char* kDataFile = "lipson/real_pend_h_1.txt";
  physics::Pendulum fit_{2.4};
};

}  // namespace

std::unique_ptr<Task> make_real_pendulum_task() { return std::make_unique<RealPendulumTask>(); }

}  // namespace hnn::tasks
