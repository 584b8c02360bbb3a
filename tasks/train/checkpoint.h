#pragma once
// Training checkpoints: everything a run needs to continue exactly where it stopped (model
// parameters, Adam's step count and moments, the minibatch generator's state, the loss curve so
// far), kept in RUN/checkpoint/ so that a kill at any moment leaves one complete checkpoint; and
// RunCheckpoints, the training loop's use of them.
//
// Note [Checkpoint commit]: a checkpoint is two files, each written atomically. First
// step-<N>.bin (the parameters and Adam's moments in nn's checksummed parameter file), then
// state.json, which names that .bin and holds the rest. state.json is the commit record: until
// its rename the previous state.json and the .bin it names are untouched, and older .bin files
// are removed only after it. A reader trusts state.json and the file it names, nothing else.

#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "nn/optim.h"
#include "tasks/report/run_folder.h"
#include "tasks/train/objective.h"

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
                           const nn::Adam<T>& adam, TrainState state);

/// Reads `dir`/state.json; throws Error naming the file and what is missing or wrong.
TrainState read_train_state(const std::filesystem::path& dir);

/// Loads the matrices of the checkpoint `state` (from read_train_state) into `model` and `adam`
/// (whose parameters, over all its groups, list the model's in order). Everything is checked
/// first: on any mismatch (kind, scalar type, names, shapes, a truncated or corrupt file) it
/// throws and changes nothing.
template <typename T>
void load_train_checkpoint(const std::filesystem::path& dir, const TrainState& state,
                           nn::Module<T>& model, nn::Adam<T>& adam);

/// The checkpoints of one training run (LoopOptions::checkpoint_dir in train/loop.h): when one is
/// due, writing it, and restoring the run from one.
template <typename T>
class RunCheckpoints {
 public:
  /// None when `dir` is empty; every `every` steps (0: a tenth of `total_steps`) and at the last.
  /// `run` (the run's settings) and `data_hash` (Objective::data_fingerprint) go in every one.
  /// `restored_steps`: the step count of the run restore() expects (0: `total_steps`); another
  /// when a finished run is continued to `total_steps`.
  RunCheckpoints(std::filesystem::path dir, long every, long total_steps, nlohmann::json run,
                 std::uint64_t data_hash, long restored_steps = 0);

  bool enabled() const { return !dir_.empty(); }
  bool due(long step) const { return enabled() && (step % every_ == 0 || step == total_steps_); }

  /// Writes the checkpoint of `step`; throws TrainingDiverged (train/stop.h) instead if the
  /// parameters are not finite, so that the last checkpoint stays a good one.
  void save(long step, Objective<T>& objective, const nn::Adam<T>& adam,
            const std::vector<CurvePoint>& curve, double seconds);
  /// Loads the checkpoint into the model, the optimiser and the sampler, after checking that it
  /// is of this run (step count, data); returns its state.
  TrainState restore(Objective<T>& objective, nn::Adam<T>& adam);
  /// "; the last good checkpoint (step N) is kept in DIR", or "" before the first: the end of a
  /// message saying that training diverged.
  std::string last_good() const;

 private:
  std::filesystem::path dir_;
  long every_;
  long total_steps_;
  long restored_steps_;
  nlohmann::json run_;
  std::uint64_t data_hash_;
  long last_saved_ = 0;
};

}  // namespace hnn::tasks
