#include "tasks/trainer.h"

#include <chrono>
#include <cmath>
#include <sstream>

#include "autodiff/grad.h"
#include "autodiff/tape.h"
#include "nn/loss.h"
#include "nn/optim.h"
#include "tasks/progress.h"
#include "tasks/task_library.h"
#include "tasks/train_checkpoint.h"

namespace hnn::tasks {

namespace {

// Loss curves evaluate at most this many rows of each split: enough for a smooth curve,
// cheap enough to record 100 points on the largest datasets.
constexpr Eigen::Index kCurveRows = 4000;
constexpr Eigen::Index kEvalChunk = 4096;

// The batch of one step: all rows (full batch) or rows drawn uniformly with replacement.
template <typename T>
class BatchSampler {
 public:
  BatchSampler(const Batch& x, const Batch& dxdt, int batch_size, std::uint64_t seed)
      : x_(x.cast<T>()), dxdt_(dxdt.cast<T>()), rng_(seed) {
    const Eigen::Index n = x.rows();
    HNN_TASKS_CHECK(n > 0, "training data is empty");
    HNN_TASKS_CHECK(batch_size >= 0 && batch_size <= n,
                    "batch size {} is out of range: the training set has {} rows", batch_size,
                    n);
    full_ = batch_size == 0 || batch_size == n;
    if (!full_) {
      xb_.resize(batch_size, x.cols());
      dxdtb_.resize(batch_size, x.cols());
    }
  }

  void next() {
    if (full_) return;
    std::uniform_int_distribution<Eigen::Index> pick(0, x_.rows() - 1);
    for (Eigen::Index i = 0; i < xb_.rows(); ++i) {
      const Eigen::Index row = pick(rng_);
      xb_.row(i) = x_.row(row);
      dxdtb_.row(i) = dxdt_.row(row);
    }
  }
  const ad::Matrix<T>& x() const { return full_ ? x_ : xb_; }
  const ad::Matrix<T>& dxdt() const { return full_ ? dxdt_ : dxdtb_; }
  bool full() const { return full_; }
  /// The generator's state, for checkpoints (std::mt19937_64's text form).
  std::string rng_state() const {
    std::ostringstream out;
    out << rng_;
    return out.str();
  }
  void set_rng_state(const std::string& state) {
    std::istringstream in(state);
    in >> rng_;
    HNN_TASKS_CHECK(!in.fail(), "the checkpoint's sampler state is corrupt");
  }

 private:
  ad::Matrix<T> x_, dxdt_, xb_, dxdtb_;
  std::mt19937_64 rng_;
  bool full_;
};

long record_interval(const TrainConfig& config) {
  if (config.record_every > 0) return config.record_every;
  return std::max(1, config.steps / 100);
}

// The checkpoints of one run (TrainHooks::checkpoint_dir): when they are due, writing them and
// restoring from one.
template <typename T>
class Checkpoints {
 public:
  Checkpoints(const TrainHooks& hooks, const TrainConfig& config, const Dataset& data)
      : hooks_(hooks),
        total_(config.steps),
        every_(hooks.checkpoint_every > 0 ? hooks.checkpoint_every
                                          : std::max(1, config.steps / 10)),
        data_hash_(data_fingerprint(data)) {}

  bool enabled() const { return !hooks_.checkpoint_dir.empty(); }
  bool due(long step) const { return enabled() && (step % every_ == 0 || step == total_); }

  void save(long step, const nn::DynamicsModel<T>& model, const nn::Adam<T>& adam,
            const BatchSampler<T>& batches, const TrainResult& so_far) {
    // A checkpoint holds finite parameters only: "the last good checkpoint" stays good.
    for (const ad::Var<T>& p : model.parameters()) {
      if (!p.value().allFinite()) {
        throw TrainingDiverged(fmt::format("training diverged at step {}: the parameters are not "
                                           "finite{}",
                                           step, where()),
                               step);
      }
    }
    TrainState state;
    state.step = step;
    state.total_steps = total_;
    state.sampler_state = batches.rng_state();
    state.data_hash = data_hash_;
    state.curve = so_far.curve;
    state.seconds = so_far.seconds;
    state.run = hooks_.run_settings;
    save_train_checkpoint<T>(hooks_.checkpoint_dir, model, adam, std::move(state));
    last_saved_ = step;
  }

  /// Loads the checkpoint into model, adam and batches; returns its state.
  TrainState restore(nn::DynamicsModel<T>& model, nn::Adam<T>& adam, BatchSampler<T>& batches) {
    const std::string dir = hooks_.checkpoint_dir.string();
    TrainState state = read_train_state(hooks_.checkpoint_dir);
    HNN_TASKS_CHECK(state.total_steps == total_,
                    "the checkpoint in '{}' is of a run of {} steps, not {}", dir,
                    state.total_steps, total_);
    HNN_TASKS_CHECK(state.data_hash == data_hash_,
                    "the training data differ from those of the checkpoint in '{}'", dir);
    load_train_checkpoint<T>(hooks_.checkpoint_dir, state, model, adam);
    batches.set_rng_state(state.sampler_state);
    last_saved_ = state.step;
    return state;
  }

  std::string where() const {
    return last_saved_ > 0 ? fmt::format("; the last good checkpoint (step {}) is kept in {}",
                                         last_saved_, hooks_.checkpoint_dir.string())
                           : "";
  }

 private:
  const TrainHooks& hooks_;
  long total_, every_;
  std::uint64_t data_hash_;
  long last_saved_ = 0;
};

// Arms a StopSignal for the lifetime of a training loop.
class ArmStop {
 public:
  explicit ArmStop(StopSignal* stop) : stop_(stop) {
    if (stop_) stop_->armed = true;
  }
  ~ArmStop() {
    if (stop_) stop_->armed = false;
  }
  ArmStop(const ArmStop&) = delete;
  ArmStop& operator=(const ArmStop&) = delete;

 private:
  StopSignal* stop_;
};

}  // namespace

template <typename T>
double field_mse(const nn::DynamicsModel<T>& model, const Batch& x, const Batch& dxdt) {
  double total = 0;
  for (Eigen::Index start = 0; start < x.rows(); start += kEvalChunk) {
    const Eigen::Index n = std::min(kEvalChunk, x.rows() - start);
    const ad::Matrix<T> pred = model.field(x.middleRows(start, n).cast<T>());
    total += (pred.template cast<double>() - dxdt.middleRows(start, n)).squaredNorm();
  }
  return total / double(x.size());
}

template <typename T>
TrainResult train_model(nn::DynamicsModel<T>& model, const Dataset& data,
                        const TrainConfig& config, std::uint64_t seed, const TrainHooks& hooks) {
  HNN_TASKS_CHECK(config.steps > 0, "steps must be positive, got {}", config.steps);
  HNN_TASKS_CHECK(config.learning_rate > 0 && std::isfinite(config.learning_rate),
                  "learning rate must be positive, got {}", config.learning_rate);
  BatchSampler<T> batches(data.train_x, data.train_dxdt, config.batch_size, seed);
  const Eigen::Index curve_train = std::min(kCurveRows, data.train_x.rows());
  const Eigen::Index curve_test = std::min(kCurveRows, data.test_x.rows());
  const std::vector<ad::Var<T>> params = model.parameters();
  nn::Adam<T> adam(params, {.lr = config.learning_rate, .weight_decay = config.weight_decay});
  const long interval = record_interval(config);

  TrainResult result;
  Checkpoints<T> checkpoints(hooks, config, data);
  long first = 1;
  double earlier_seconds = 0;  // training time before a resume
  if (hooks.resume) {
    const TrainState state = checkpoints.restore(model, adam, batches);
    first = state.step + 1;
    result.curve = state.curve;
    earlier_seconds = state.seconds;
  }
  Progress progress(hooks.label, config.steps, hooks.quiet);
  const auto start = std::chrono::steady_clock::now();
  double loss_value = 0;
  std::chrono::duration<double> recording{0};  // loss curve and checkpoints, not training
  const auto seconds = [&] {
    return earlier_seconds +
           (std::chrono::duration<double>(std::chrono::steady_clock::now() - start) - recording)
               .count();
  };
  const ArmStop arm(hooks.stop);
  std::vector<ad::Var<T>> grads;  // reused: a step allocates nothing in steady state
  for (long step = first; step <= config.steps; ++step) {
    ad::TapeScope scope;  // everything this step records is recycled at the closing brace
    batches.next();
    const ad::Var<T> loss = nn::mse(model.time_derivative(ad::Var<T>::constant(batches.x())),
                                    ad::Var<T>::constant(batches.dxdt()));
    loss_value = double(loss.item());
    if (!std::isfinite(loss_value)) {
      throw TrainingDiverged(fmt::format("training diverged at step {}: the loss is {}{}", step,
                                         loss_value, checkpoints.where()),
                             step);
    }
    ad::grad_into(loss, params, grads);
    adam.step(grads);
    if (step % interval == 0 || step == config.steps) {
      const auto record_start = std::chrono::steady_clock::now();
      const double train = batches.full() ? loss_value
                                          : field_mse(model, data.train_x.topRows(curve_train),
                                                      data.train_dxdt.topRows(curve_train));
      const double test = curve_test > 0 ? field_mse(model, data.test_x.topRows(curve_test),
                                                     data.test_dxdt.topRows(curve_test))
                                         : NAN;
      result.curve.push_back({step, train, test});
      if (hooks.on_record) hooks.on_record(step);
      recording += std::chrono::steady_clock::now() - record_start;
    }
    const bool stop = hooks.stop && hooks.stop->requested && step < config.steps;
    if (checkpoints.due(step) || (stop && checkpoints.enabled())) {
      result.seconds = seconds();
      const auto save_start = std::chrono::steady_clock::now();
      checkpoints.save(step, model, adam, batches, result);
      recording += std::chrono::steady_clock::now() - save_start;
    }
    progress.update(step, loss_value);
    if (stop) {
      progress.stop(step, loss_value);
      throw TrainingInterrupted(
          fmt::format(
              "training stopped at step {} of {}{}", step, config.steps,
              checkpoints.enabled() ? "; checkpoint in " + hooks.checkpoint_dir.string() : ""),
          step);
    }
  }
  result.seconds = seconds();
  result.steps = config.steps;
  progress.finish(loss_value);
  return result;
}

template TrainResult train_model(nn::DynamicsModel<float>&, const Dataset&, const TrainConfig&,
                                 std::uint64_t, const TrainHooks&);
template TrainResult train_model(nn::DynamicsModel<double>&, const Dataset&, const TrainConfig&,
                                 std::uint64_t, const TrainHooks&);
template double field_mse(const nn::DynamicsModel<float>&, const Batch&, const Batch&);
template double field_mse(const nn::DynamicsModel<double>&, const Batch&, const Batch&);

}  // namespace hnn::tasks
