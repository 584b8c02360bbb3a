#pragma once
// Training checkpoints: everything a run needs to continue exactly where it stopped (model
// parameters, the step count and moments of each parameter group's Adam, the minibatch generator's
// state, the loss curve so far), kept in RUN/checkpoint/ so that a kill at any moment leaves one
// complete checkpoint.
//
// Note [Checkpoint commit]: a checkpoint is two files, each written atomically. First
// step-<N>.bin (the parameters and Adam's moments in nn's checksummed parameter format), then
// state.json, which names that .bin and holds the rest. state.json is the commit record: until
// its rename the previous state.json and the .bin it names are untouched, and older .bin files
// are removed only after it. A reader trusts state.json and the file it names, nothing else.

#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <span>
#include <string>
#include <vector>

#include "nn/optim.h"
#include "tasks/report/run_folder.h"

namespace hnn::tasks {

/// The part of a checkpoint that is not matrices.
struct TrainState {
  long step = 0;                    // steps completed
  long total_steps = 0;             // steps the run was asked for
  std::string sampler_state{};      // the sampler's generator (and order), RowSampler::state
  std::uint64_t data_hash = 0;      // fingerprint of the training data (Objective)
  std::vector<CurvePoint> curve{};  // the loss curve up to `step`
  double seconds = 0;               // training time so far
  nlohmann::json run{};             // the run's settings, for `hnn train --resume`
  std::string params_file{};        // the .bin holding the matrices (a name inside the folder)
};

/// Writes a checkpoint of `state.step` into `dir` (creating it), following Note [Checkpoint
/// commit], then removes every other file of `dir` (older checkpoints, leftover temporaries).
template <typename T>
void save_train_checkpoint(const std::filesystem::path& dir, const nn::Module<T>& model,
                           std::span<const nn::Adam<T>> adams, TrainState state);

/// Reads `dir`/state.json; throws Error naming the file and what is missing or wrong.
TrainState read_train_state(const std::filesystem::path& dir);

/// Loads the matrices of the checkpoint `state` (from read_train_state) into `model` and the
/// optimisers `adams` (one per parameter group, whose parameters list the model's in order).
/// Everything is checked first: on any mismatch (kind, scalar type, names, shapes, a truncated or
/// corrupt file) it throws and changes nothing.
template <typename T>
void load_train_checkpoint(const std::filesystem::path& dir, const TrainState& state,
                           nn::Module<T>& model, std::span<nn::Adam<T>> adams);

}  // namespace hnn::tasks
