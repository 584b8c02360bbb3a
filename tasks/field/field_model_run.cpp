#include "tasks/field/field_model_run.h"

#include "tasks/train/field_objective.h"

namespace hnn::tasks {

template <typename T>
TrainResult train_model(nn::DynamicsModel<T>& model, const Dataset& data, const TrainConfig& config,
                        std::uint64_t seed, LoopOptions loop) {
  loop.steps = config.steps;
  loop.lr_schedule = config.lr_schedule;
  loop.record_every = config.record_every;
  FieldObjective<T> objective(model, data, config.batch_size,
                              {.lr = config.learning_rate, .weight_decay = config.weight_decay},
                              seed);
  return train(objective, loop);
}

template TrainResult train_model(nn::DynamicsModel<float>&, const Dataset&, const TrainConfig&,
                                 std::uint64_t, LoopOptions);
template TrainResult train_model(nn::DynamicsModel<double>&, const Dataset&, const TrainConfig&,
                                 std::uint64_t, LoopOptions);

}  // namespace hnn::tasks
