#include "tasks/train/loop.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <numbers>
#include <optional>
#include <stdexcept>
#include <string_view>

#include "autodiff/check.h"
#include "autodiff/float_mode.h"
#include "autodiff/grad.h"
#include "autodiff/parallel.h"
#include "autodiff/tape.h"
#include "nn/row_split.h"
#include "tasks/error.h"
#include "tasks/train/checkpoint.h"
#include "tasks/train/progress.h"

namespace hnn::tasks {

namespace {

using Clock = std::chrono::steady_clock;

long record_interval(const LoopOptions& o) {
  return o.record_every > 0 ? o.record_every : std::max(1L, o.steps / 100);
}

// Each group's options as the loop needs them: a positive learning rate (a schedule scales it)
// and a finite weight decay.
template <typename T>
std::vector<nn::AdamGroup<T>> checked(std::vector<nn::AdamGroup<T>> groups) {
  for (const nn::AdamGroup<T>& group : groups) {
    const nn::AdamOptions& o = group.options;
    HNN_TASKS_CHECK(o.lr > 0 && std::isfinite(o.lr), "learning rate must be positive, got {}",
                    o.lr);
    HNN_TASKS_CHECK(o.weight_decay >= 0 && std::isfinite(o.weight_decay),
                    "weight decay must be a finite number >= 0, got {}", o.weight_decay);
  }
  return groups;
}

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
  /// Runs work off the clock; returns its seconds.
  template <typename F>
  double pause_for(F&& work) {
    const auto start = Clock::now();
    work();
    const auto took = Clock::now() - start;
    paused_ += took;
    return std::chrono::duration<double>(took).count();
  }

 private:
  double earlier_;
  Clock::time_point start_ = Clock::now();
  std::chrono::duration<double> paused_{0};
};

// f(), or TrainingDiverged at `step` when the learned field cannot be evaluated on its rows: its
// motion left the finite numbers within an integration (a solve met a non-finite state), or a
// learned matrix turned singular. The run stops there as on a loss of inf, keeping the last good
// checkpoint (`where` says which).
template <typename F>
auto unless_the_field_fails(long step, const char* on, const std::string& where, const F& f) {
  try {
    return f();
  } catch (const ad::Error& e) {
    throw TrainingDiverged(
        fmt::format("training stopped at step {}: the learned field failed on {}: {}{}", step, on,
                    e.what(), where),
        step);
  }
}

// One step: the batch's loss, its gradients and the optimiser's update. Returns the loss. With
// `split`, the batch's rows are shared among the engine's threads, each with its own replica of
// the model (nn/row_split.h); without, each op splits its own work.
template <typename T>
double train_step(long step, Objective<T>& objective, nn::RowSplit<T>* split, nn::Adam<T>& adam,
                  std::vector<ad::Var<T>>& grads, const std::string& where) {
  ad::TapeScope scope;  // everything this step records is recycled at the closing brace
  objective.sampler().next();
  ad::Var<T> loss;  // of the unsplit step
  const double value = unless_the_field_fails(step, "the batch", where, [&] {
    if (split) {
      const auto rows_loss = [&](const nn::DynamicsModel<T>& model, ad::RowBlock block) {
        return objective.rows_loss(model, block);
      };
      return split->loss_and_gradients(objective.gather_batch(), rows_loss, grads);
    }
    loss = objective.batch_loss();
    return double(loss.item());
  });
  const auto diverged = [&](std::string_view but) {  // formatted only when thrown
    return TrainingDiverged::at(step, fmt::format("the loss is {}{}", value, but), where);
  };
  if (!std::isfinite(value)) throw diverged("");
  if (loss.defined()) ad::grad_into(loss, adam.parameters(), grads);
  // A finite loss can still have a non-finite gradient (a solve near singular, a saturated
  // activation times an overflow): stepping on it would turn every weight into NaN and stop the
  // run later, at whatever evaluates the model next, under another name.
  const auto finite = [](const ad::Var<T>& g) { return !g.defined() || g.value().allFinite(); };
  if (!std::ranges::all_of(grads, finite)) throw diverged(" but its gradient is not finite");
  adam.step(grads);
  return value;
}

// The row split of an objective's steps at the engine's thread count, or nothing when its loss
// does not split by rows or its batches are too small to share.
template <typename T>
std::unique_ptr<nn::RowSplit<T>> row_split(Objective<T>& objective) {
  const nn::DynamicsModel<T>* model = objective.row_model();
  if (model == nullptr) return nullptr;
  const int parts = nn::row_split_parts(objective.sampler().batch_size(), ad::num_threads());
  return parts > 1 ? std::make_unique<nn::RowSplit<T>>(*model, parts) : nullptr;
}

// One run of the loop: the optimiser, the checkpoints, the loss curve so far and the clock.
template <typename T>
class Loop {
 public:
  Loop(Objective<T>& objective, const LoopOptions& o)
      : objective_(objective),
        o_(o),
        adam_(checked(objective.parameter_groups())),
        checkpoints_(o.checkpoint_dir, o.checkpoint_every, o.steps, o.run_settings,
                     objective.data_fingerprint(), o.checkpoint_steps) {
    check_groups(objective, adam_.parameters());
    split_ = row_split(objective);
    for (std::size_t g = 0; g < adam_.group_count(); ++g) base_lr_.push_back(adam_.options(g).lr);
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
    if (o_.lr_schedule != LrSchedule::kConstant) {
      const double factor = lr_factor(o_.lr_schedule, step, o_.steps);
      for (std::size_t g = 0; g < base_lr_.size(); ++g) adam_.set_lr(g, base_lr_[g] * factor);
    }
    return train_step(step, objective_, split_.get(), adam_, grads_, checkpoints_.last_good());
  }

  void record(long step, double loss) {
    if (step % interval_ != 0 && step != o_.steps) return;
    result_.curve_seconds += clock_.pause_for([&] {
      result_.curve.push_back(
          unless_the_field_fails(step, "the loss curve's splits", checkpoints_.last_good(),
                                 [&] { return objective_.curve_point(step, loss); }));
      if (o_.on_record) o_.on_record(step);
    });
  }

  void checkpoint(long step, bool stopping) {
    if (!checkpoints_.due(step) && !(stopping && checkpoints_.enabled())) return;
    result_.seconds = clock_.seconds();
    clock_.pause_for(
        [&] { checkpoints_.save(step, objective_, adam_, result_.curve, result_.seconds); });
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
  nn::Adam<T> adam_;
  std::unique_ptr<nn::RowSplit<T>> split_;  // null: each op splits its own work
  std::vector<double> base_lr_;             // each group's configured rate, which a schedule scales
  RunCheckpoints<T> checkpoints_;
  const long interval_ = record_interval(o_);
  TrainResult result_;
  TrainClock clock_{0};
  std::vector<ad::Var<T>> grads_;  // reused: a step allocates nothing in steady state
};

}  // namespace

std::string_view to_string(LrSchedule schedule) { return nn::name_of(kLrScheduleNames, schedule); }

LrSchedule parse_lr_schedule(std::string_view name) {
  if (const std::optional<LrSchedule> schedule = nn::find_name(kLrScheduleNames, name)) {
    return *schedule;
  }
  throw std::invalid_argument(fmt::format("unknown learning-rate schedule '{}' (expected {})", name,
                                          nn::join_names(kLrScheduleNames, " or ")));
}

double lr_factor(LrSchedule schedule, long step, long steps) {
  if (schedule == LrSchedule::kConstant || steps < 1) return 1.0;
  return 0.5 * (1.0 + std::cos(std::numbers::pi * double(step - 1) / double(steps)));
}

template <typename T>
TrainResult train(Objective<T>& objective, const LoopOptions& o) {
  HNN_TASKS_CHECK(o.steps > 0, "steps must be positive, got {}", o.steps);
  const ad::FlushDenormals flush;  // Note [Denormals flushed] in autodiff/float_mode.h
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
