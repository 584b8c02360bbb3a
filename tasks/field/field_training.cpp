#include "tasks/field/field_training.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "autodiff/tape.h"
#include "nn/sampled/sampled_fit.h"
#include "tasks/task.h"
#include "tasks/train/field_objective.h"

namespace hnn::tasks {

template <typename T>
TrainResult train_model(nn::DynamicsModel<T>& model, const Dataset& data, const TrainConfig& config,
                        std::uint64_t seed, LoopOptions loop) {
  FieldObjective<T> objective(model, data, config.batch_size, adam_options(config), seed);
  return train(objective, with_train_config(std::move(loop), config));
}

template TrainResult train_model(nn::DynamicsModel<float>&, const Dataset&, const TrainConfig&,
                                 std::uint64_t, LoopOptions);
template TrainResult train_model(nn::DynamicsModel<double>&, const Dataset&, const TrainConfig&,
                                 std::uint64_t, LoopOptions);

FieldTraining::FieldTraining(const RolloutLossConfig& loss, const SplitStretches* stretches,
                             const TrainConfig& train, const std::string& task, double time_unit)
    : loss_(loss) {
  if (!loss_.rollout) return;
  HNN_TASKS_CHECK(stretches != nullptr,
                  "{}: the rollout loss needs trajectories, and this task's data are states "
                  "without them (use --loss derivative)",
                  task);
  train_windows_ = rollout_windows(stretches->train, loss_.horizon);
  const bool any_test = std::any_of(stretches->test.begin(), stretches->test.end(),
                                    [&](const Stretch& t) { return t.x.rows() > loss_.horizon; });
  if (any_test) test_windows_ = rollout_windows(stretches->test, loss_.horizon);
  substeps_ = rollout_substeps(train_windows_, loss_.dt / time_unit);
  HNN_TASKS_CHECK(train.batch_size <= train_windows_.count(),
                  "--batch {} is larger than the {} rollout windows of the training set",
                  train.batch_size, train_windows_.count());
}

double FieldTraining::truth_loss(const physics::System& truth) const {
  if (!loss_.rollout || loss_.integrator == RolloutIntegrator::kMidpoint) return NAN;
  const KnownField field = [&](const Batch& z, Batch& dzdt) { truth.vector_field(z, dzdt); };
  const RolloutWindows& w = train_windows_;
  ad::TapeScope scope;
  ad::NoGradGuard values_only;
  Batch z = w.start;
  double total = 0;
  for (std::size_t j = 0; j < w.next.size(); ++j) {
    const Batch h = w.step[j] / double(substeps_);
    for (int s = 0; s < substeps_; ++s) z = known_field_step(field, z, h, loss_.integrator);
    total += rollout_error(loss_.norm, ad::Var<double>::constant(z),
                           ad::Var<double>::constant(w.next[j]))
                 .item();
  }
  return total / double(w.next.size());
}

namespace {

// Samples the hidden layers of `model` and solves its last layer on the training split's dx/dt:
// what the fit did, with its wall time, and no loss curve.
template <typename T>
TrainResult fit_by_sampling(nn::DynamicsModel<T>& model, const Dataset& data,
                            const RunSettings& s) {
  const auto start = std::chrono::steady_clock::now();
  nn::SampledFitConfig config = s.fit.sampled;
  config.seed = s.seed;
  nn::SampledFitReport report;
  try {
    report = nn::fit_sampled(model, data.train_x, data.train_dxdt, config);
  } catch (const std::invalid_argument& e) {
    throw Error(fmt::format("{}: {}", s.task, e.what()));
  }
  return {
      .seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(),
      .fit = fit_report_json(s.fit, report)};
}

}  // namespace

template <typename T>
TrainResult FieldTraining::train(nn::DynamicsModel<T>& model, const Dataset& data,
                                 const RunSettings& s, const LoopOptions& loop) const {
  // Resumed, the checkpoint holds the weights: sampled + Adam samples only when it starts.
  if (!s.fit.samples() || loop.resume) return train_steps(model, data, s, loop);
  TrainResult sampled = fit_by_sampling(model, data, s);
  if (loop.before_steps) loop.before_steps();
  if (!s.fit.steps()) return sampled;
  LoopOptions adam = loop;
  adam.run_settings["fit"] = sampled.fit;  // its checkpoints carry the report
  TrainResult trained = train_steps(model, data, s, adam);
  trained.seconds += sampled.seconds;
  trained.curve_seconds += sampled.curve_seconds;
  trained.fit = std::move(sampled.fit);
  return trained;
}

template <typename T>
TrainResult FieldTraining::train_steps(nn::DynamicsModel<T>& model, const Dataset& data,
                                       const RunSettings& s, const LoopOptions& loop) const {
  return loss_.rollout ? train_through_integrator(model, s, loop)
                       : train_model(model, data, s.train, s.seed, loop);
}

template <typename T>
TrainResult FieldTraining::train_through_integrator(nn::DynamicsModel<T>& model,
                                                    const RunSettings& s,
                                                    const LoopOptions& loop) const {
  RolloutObjective<T> objective(model, train_windows_, test_windows_, s.train.batch_size,
                                adam_options(s.train), s.seed, loss_.integrator, substeps_,
                                loss_.norm, loss_.minibatches);
  return tasks::train(objective, with_train_config(loop, s.train));
}

template TrainResult FieldTraining::train(nn::DynamicsModel<float>&, const Dataset&,
                                          const RunSettings&, const LoopOptions&) const;
template TrainResult FieldTraining::train(nn::DynamicsModel<double>&, const Dataset&,
                                          const RunSettings&, const LoopOptions&) const;

}  // namespace hnn::tasks
