#include "tasks/train/loop.h"

#include <chrono>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include "autodiff/grad.h"
#include "autodiff/tape.h"
#include "tasks/error.h"
#include "tasks/train/checkpoint.h"
#include "tasks/train/progress.h"

namespace hnn::tasks {

namespace {

using Clock = std::chrono::steady_clock;

long record_interval(const LoopOptions& o) {
  return o.record_every > 0 ? o.record_every : std::max(1L, o.steps / 100);
}

// An Adam per parameter group, each stepped with its slice of the gradients of all parameters.
template <typename T>
class GroupedAdam {
 public:
  explicit GroupedAdam(const std::vector<ParameterGroup<T>>& groups) {
    adams_.reserve(groups.size());  // no reallocation: the Adams stay where they are built
    for (const ParameterGroup<T>& group : groups) {
      check(group.adam);
      adams_.emplace_back(group.parameters, group.adam);
      base_lr_.push_back(group.adam.lr);
      slices_.emplace_back().reserve(group.parameters.size());
      all_.insert(all_.end(), group.parameters.begin(), group.parameters.end());
    }
  }
  const std::vector<ad::Var<T>>& parameters() const { return all_; }
  std::vector<nn::Adam<T>>& adams() { return adams_; }
  /// Each group's learning rate becomes its configured one times `factor`.
  void scale_lr(double factor) {
    for (std::size_t i = 0; i < adams_.size(); ++i) adams_[i].set_lr(base_lr_[i] * factor);
  }

  static void check(const nn::AdamOptions& o) {
    HNN_TASKS_CHECK(o.lr > 0 && std::isfinite(o.lr), "learning rate must be positive, got {}",
                    o.lr);
    HNN_TASKS_CHECK(o.weight_decay >= 0 && std::isfinite(o.weight_decay),
                    "weight decay must be a finite number >= 0, got {}", o.weight_decay);
  }

  void step(const std::vector<ad::Var<T>>& grads) {
    auto first = grads.begin();
    for (std::size_t i = 0; i < adams_.size(); ++i) {
      const auto count = std::ptrdiff_t(adams_[i].parameters().size());
      slices_[i].assign(first, first + count);  // within capacity: no allocation
      adams_[i].step(slices_[i]);
      first += count;
    }
  }

 private:
  std::vector<nn::Adam<T>> adams_;
  std::vector<double> base_lr_;
  std::vector<std::vector<ad::Var<T>>> slices_;
  std::vector<ad::Var<T>> all_;
};

// The groups must cover the model's parameters in order: checkpoints name Adam's moments after
// them.
template <typename T>
void check_groups(Objective<T>& objective, const std::vector<ad::Var<T>>& grouped) {
  const std::vector<ad::Var<T>> params = objective.model().parameters();
  bool same = params.size() == grouped.size();
  for (std::size_t i = 0; same && i < params.size(); ++i)
    same = &params[i].value() == &grouped[i].value();
  HNN_TASKS_CHECK(same,
                  "the objective's parameter groups do not list the model's parameters in "
                  "order");
}

// The checkpoints of one run (LoopOptions::checkpoint_dir): when they are due, writing them and
// restoring from one.
template <typename T>
class Checkpoints {
 public:
  Checkpoints(const LoopOptions& o, std::uint64_t data_hash)
      : o_(o),
        every_(o.checkpoint_every > 0 ? o.checkpoint_every : std::max(1L, o.steps / 10)),
        data_hash_(data_hash) {}

  bool enabled() const { return !o_.checkpoint_dir.empty(); }
  bool due(long step) const { return enabled() && (step % every_ == 0 || step == o_.steps); }

  void save(long step, Objective<T>& objective, GroupedAdam<T>& adam, const TrainResult& so_far) {
    // A checkpoint holds finite parameters only: "the last good checkpoint" stays good.
    for (const ad::Var<T>& p : adam.parameters()) {
      if (!p.value().allFinite()) {
        throw TrainingDiverged(
            fmt::format("training diverged at step {}: the parameters are not finite{}", step,
                        where()),
            step);
      }
    }
    TrainState state{.step = step,
                     .total_steps = o_.steps,
                     .sampler_state = objective.sampler().state(),
                     .data_hash = data_hash_,
                     .curve = so_far.curve,
                     .seconds = so_far.seconds,
                     .run = o_.run_settings};
    save_train_checkpoint<T>(o_.checkpoint_dir, objective.model(), adam.adams(), std::move(state));
    last_saved_ = step;
  }

  /// Loads the checkpoint into the model, the optimisers and the sampler; returns its state.
  TrainState restore(Objective<T>& objective, GroupedAdam<T>& adam) {
    const std::string dir = o_.checkpoint_dir.string();
    TrainState state = read_train_state(o_.checkpoint_dir);
    HNN_TASKS_CHECK(state.total_steps == o_.steps,
                    "the checkpoint in '{}' is of a run of {} steps, not {}", dir,
                    state.total_steps, o_.steps);
    HNN_TASKS_CHECK(state.data_hash == data_hash_,
                    "the training data differ from those of the checkpoint in '{}'", dir);
    load_train_checkpoint<T>(o_.checkpoint_dir, state, objective.model(), adam.adams());
    objective.sampler().set_state(state.sampler_state);
    last_saved_ = state.step;
    return state;
  }

  std::string where() const {
    return last_saved_ > 0 ? fmt::format("; the last good checkpoint (step {}) is kept in {}",
                                         last_saved_, o_.checkpoint_dir.string())
                           : "";
  }

 private:
  const LoopOptions& o_;
  long every_;
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

// Training time: the wall time since the start, less what recording and checkpoints took, plus
// the time before a resume.
class TrainClock {
 public:
  explicit TrainClock(double earlier) : earlier_(earlier) {}
  double seconds() const {
    return earlier_ + (std::chrono::duration<double>(Clock::now() - start_) - paused_).count();
  }
  template <typename F>
  void pause_for(F&& work) {
    const auto start = Clock::now();
    work();
    paused_ += Clock::now() - start;
  }

 private:
  double earlier_;
  Clock::time_point start_ = Clock::now();
  std::chrono::duration<double> paused_{0};
};

// One step: the batch's loss, its gradients and the optimisers' update. Returns the loss.
template <typename T>
double train_step(long step, Objective<T>& objective, GroupedAdam<T>& adam,
                  std::vector<ad::Var<T>>& grads, const std::string& where) {
  ad::TapeScope scope;  // everything this step records is recycled at the closing brace
  objective.sampler().next();
  const ad::Var<T> loss = objective.batch_loss();
  const double value = double(loss.item());
  if (!std::isfinite(value)) {
    throw TrainingDiverged(
        fmt::format("training diverged at step {}: the loss is {}{}", step, value, where), step);
  }
  ad::grad_into(loss, adam.parameters(), grads);
  adam.step(grads);
  return value;
}

// One run of the loop: the optimisers, the checkpoints, the loss curve so far and the clock.
template <typename T>
class Loop {
 public:
  Loop(Objective<T>& objective, const LoopOptions& o)
      : objective_(objective),
        o_(o),
        adam_(objective.parameter_groups()),
        checkpoints_(o, objective.data_fingerprint()) {
    check_groups(objective, adam_.parameters());
  }

  /// The first step to take: 1, or the one after the checkpoint when resuming.
  long start() {
    long first = 1;
    double earlier = 0;  // training time before the checkpoint
    if (o_.resume) {
      const TrainState state = checkpoints_.restore(objective_, adam_);
      result_.curve = state.curve;
      earlier = state.seconds;
      first = state.step + 1;
    }
    clock_ = TrainClock(earlier);  // from now: restoring is not training
    return first;
  }

  double step(long step) {
    if (o_.lr_schedule != LrSchedule::kConstant)
      adam_.scale_lr(lr_factor(o_.lr_schedule, step, o_.steps));
    return train_step(step, objective_, adam_, grads_, checkpoints_.where());
  }

  void record(long step, double loss) {
    if (step % interval_ != 0 && step != o_.steps) return;
    clock_.pause_for([&] {
      result_.curve.push_back(objective_.curve_point(step, loss));
      if (o_.on_record) o_.on_record(step);
    });
  }

  void checkpoint(long step, bool stopping) {
    if (!checkpoints_.due(step) && !(stopping && checkpoints_.enabled())) return;
    result_.seconds = clock_.seconds();
    clock_.pause_for([&] { checkpoints_.save(step, objective_, adam_, result_); });
  }

  [[noreturn]] void stopped(long step) const {
    throw TrainingInterrupted(
        fmt::format("training stopped at step {} of {}{}", step, o_.steps,
                    checkpoints_.enabled() ? "; checkpoint in " + o_.checkpoint_dir.string() : ""),
        step);
  }

  TrainResult finish() {
    result_.seconds = clock_.seconds();
    result_.steps = o_.steps;
    return std::move(result_);
  }

 private:
  Objective<T>& objective_;
  const LoopOptions& o_;
  GroupedAdam<T> adam_;
  Checkpoints<T> checkpoints_;
  const long interval_ = record_interval(o_);
  TrainResult result_;
  TrainClock clock_{0};
  std::vector<ad::Var<T>> grads_;  // reused: a step allocates nothing in steady state
};

}  // namespace

std::string_view to_string(LrSchedule schedule) {
  return schedule == LrSchedule::kCosine ? "cosine" : "constant";
}

LrSchedule parse_lr_schedule(std::string_view name) {
  if (name == "constant") return LrSchedule::kConstant;
  if (name == "cosine") return LrSchedule::kCosine;
  throw std::invalid_argument(
      fmt::format("unknown learning-rate schedule '{}' (expected constant or cosine)", name));
}

double lr_factor(LrSchedule schedule, long step, long steps) {
  if (schedule == LrSchedule::kConstant || steps < 1) return 1.0;
  return 0.5 * (1.0 + std::cos(std::numbers::pi * double(step - 1) / double(steps)));
}

template <typename T>
TrainResult train(Objective<T>& objective, const LoopOptions& o) {
  HNN_TASKS_CHECK(o.steps > 0, "steps must be positive, got {}", o.steps);
  Loop<T> loop(objective, o);
  const long first = loop.start();
  Progress progress(o.label, o.steps, o.quiet);
  const ArmStop arm(o.stop);
  double loss = 0;
  for (long step = first; step <= o.steps; ++step) {
    loss = loop.step(step);
    loop.record(step, loss);
    const bool stop = o.stop && o.stop->requested && step < o.steps;
    loop.checkpoint(step, stop);
    progress.update(step, loss);
    if (stop) {
      progress.stop(step, loss);
      loop.stopped(step);
    }
  }
  progress.finish(loss);
  return loop.finish();
}

template TrainResult train(Objective<float>&, const LoopOptions&);
template TrainResult train(Objective<double>&, const LoopOptions&);

}  // namespace hnn::tasks
