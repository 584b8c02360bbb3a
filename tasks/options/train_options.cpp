// The table of `hnn train`'s options (train_options.h): the run, the model, the optimiser and
// the data task's columns here, the field tasks' training methods in train_options_methods.cpp;
// apply(), where each lands, and the lookups are in train_options_apply.cpp.

#include "tasks/options/train_options.h"

#include <fmt/format.h>

#include <limits>

#include "nn/enum_names.h"
#include "tasks/data/measured_dataset.h"
#include "tasks/error.h"

namespace hnn::tasks {

using nlohmann::json;

namespace {

constexpr long long kIntMax = std::numeric_limits<int>::max();
constexpr std::string_view kDataGroup = "The data task (hnn train data --data FILE)";

std::vector<std::string> split_names() { return nn::names_of(kSplitByNames); }

// In --help's order. A sweep key's rank is its place in run folder names (spring/hnn/seed=1,
// steps=200): fixed, so that sweeps written before keep their folders.
const TrainOption kOptions[] = {
    {.name = "task",
     .kind = ValueKind::kTask,
     .help = "Task: {} (required unless --resume)",
     .sweep_rank = 0,
     .lands = Lands::kTask,
     .key = "task"},
    {.name = "model",
     .kind = ValueKind::kChoice,
     .help = "hnn, baseline, dhnn (the dissipative HNN: H and a dissipation potential D) or lnn "
             "(the Lagrangian NN: L(q, dq/dt)); on the constrained tasks (chain-pendulum-N, "
             "coupled-pendulums, magnet-pendulum, gyroscope, rotor) also chnn and clnn (Finzi "
             "et al.'s constrained HNN and LNN: a learned V(x) in Cartesian coordinates) and "
             "hnn-mass (their HNN: a learned V(q) and M(q) in angles)",
     .default_shown = "hnn",
     .sweep_rank = 1,
     .lands = Lands::kModel,
     .key = "model",
     .choices = model_names,
     .noun = "model"},
    {.name = "steps",
     .kind = ValueKind::kInt,
     .help = "Training steps; with --resume, more than a finished "
             "run's: continue it to this many",
     .continues_resume = true,
     .sweep_rank = 6,
     .lands = Lands::kSteps,
     .key = "steps",
     .min = 1,
     .max = kIntMax,
     .default_by_task = true},
    {.name = "seed",
     .kind = ValueKind::kSeed,
     .help = "Seed of the data, initialisation and batches",
     .default_shown = "0",
     .sweep_rank = 2,
     .lands = Lands::kSeed,
     .key = "seed"},
    {.name = "dtype",
     .kind = ValueKind::kChoice,
     .help = "float or double",
     .sweep_rank = 3,
     .lands = Lands::kDtype,
     .key = "dtype",
     .choices = dtype_names,
     .noun = "dtype",
     .default_by_task = true},
    {.name = "threads",
     .kind = ValueKind::kInt,
     .help = "Threads for a step (a block of its batch each) and the rollouts of an evaluation",
     .default_shown = "2",
     .with_resume = true,
     .sweep_owned = "set by hnn sweep for every run (--threads-per-run)",
     .lands = Lands::kThreads,
     .key = "threads",
     .recorded_default = "2",
     .min = 1,
     .max = 256},
    {.name = "preset",
     .kind = ValueKind::kChoice,
     .help = "Model widths: paper (the paper's 200-200) or lean (the smallest within the noise of "
             "paper's accuracy); --hidden overrides either",
     .default_shown = "paper",
     .sweep_rank = 4,
     .lands = Lands::kPreset,
     .key = "preset",
     .recorded_default = R"("paper")",  // runs from before the presets
     .choices = preset_names,
     .noun = "preset"},
    {.name = "batch",
     .kind = ValueKind::kInt,
     .help = "Minibatch size (0: the full training set)",
     .sweep_rank = 7,
     .lands = Lands::kBatchSize,
     .key = "batch_size",
     .min = 0,
     .max = kIntMax,
     .default_by_task = true},
    {.name = "hidden",
     .kind = ValueKind::kHidden,
     .help = "Hidden widths, e.g. --hidden 200 200 (overrides --preset; --fit sampled with the "
             "paper preset takes one layer of 400)",
     .sweep_rank = 5,
     .lands = Lands::kHidden,
     .key = "hidden",
     .default_by_task = true},
    {.name = "lr",
     .kind = ValueKind::kPositiveReal,
     .help = "Adam learning rate",
     .sweep_rank = 8,
     .lands = Lands::kLearningRate,
     .key = "learning_rate",
     .default_by_task = true},
    {.name = "lr-schedule",
     .kind = ValueKind::kChoice,
     .help = "constant or cosine: decay from --lr towards 0 at the last step",
     .sweep_rank = 9,
     .lands = Lands::kLrSchedule,
     .key = "lr_schedule",
     .recorded_default = R"("constant")",  // runs from before the schedules
     .choices = lr_schedule_names,
     .noun = "learning-rate schedule",
     .default_by_task = true},
    {.name = "optimizer",
     .kind = ValueKind::kChoice,
     .help = "adam (weight decay as an L2 term in the gradient, torch.optim.Adam) or adamw "
             "(decoupled, torch.optim.AdamW); the weight decay itself is each task's",
     .sweep_rank = 35,
     .lands = Lands::kOptimizer,
     .key = "optimizer",
     .recorded_default = R"("adam")",  // runs from before the choice
     .choices = optimizer_names,
     .noun = "optimizer",
     .default_by_task = true},
    {.name = "data",
     .kind = ValueKind::kFile,
     .help = "The data task's file, or real-pendulum's measured data in its format; with "
             "--resume, the run's own file at a new place (another file is refused)",
     .with_resume = true,
     .sweep_rank = 10,
     .lands = Lands::kDataFile,
     .key = "data_file",
     .recorded_default = R"("")"},
    {.name = "out",
     .kind = ValueKind::kFolder,
     .help = "Run folder (default runs/TASK/MODEL, or runs/TASK/STEM/MODEL with --data STEM.EXT)",
     .sweep_owned = "set by hnn sweep (OUT/runs/<run>)",
     .lands = Lands::kOut},
    {.name = "force",
     .kind = ValueKind::kFlag,
     .help = "Replace the run already in the --out folder (all its files are removed once the "
             "new run's data are read); without it a folder that is not empty is refused",
     .sweep_owned = "hnn sweep trains each run into a folder of its own that holds no run",
     .lands = Lands::kForce},
    {.name = "quiet",
     .kind = ValueKind::kFlag,
     .help = "No progress output",
     .with_resume = true,
     .sweep_owned = "hnn sweep runs quietly",
     .lands = Lands::kQuiet},
    {.name = "json",
     .kind = ValueKind::kFlag,
     .help = "Print metrics.json's content on stdout instead of the summary",
     .with_resume = true,
     .sweep_owned = "hnn sweep reads each run's metrics.json",
     .lands = Lands::kPrintJson},
    {.name = "settings",
     .kind = ValueKind::kJsonObject,
     .help = "The task's own settings as a JSON object, e.g. pixel-pendulum's '{\"trials\": 20, "
             "\"ae_hidden\": 64}' (see its metrics.json's \"pixel\")",
     .sweep_rank = 11,
     .lands = Lands::kTaskSettings,
     .key = "task_settings",
     .recorded_default = "{}"},
    {.name = "checkpoint-every",
     .kind = ValueKind::kInt,
     .help = "Steps between checkpoints in OUT/checkpoint (default: a tenth of the steps)",
     .with_resume = true,
     .sweep_rank = 12,
     .lands = Lands::kCheckpointEvery,
     .min = 1,
     .max = kIntMax},
    {.name = "resume",
     .kind = ValueKind::kRunFolder,
     .help = "Continue the run in this folder from its last checkpoint: an interrupted run "
             "to its end, a finished one to a larger --steps",
     .with_resume = true,
     .sweep_owned = "hnn sweep resumes interrupted runs by itself",
     .lands = Lands::kResume},
    {.name = "coords",
     .kind = ValueKind::kColumns,
     .help = "Coordinate columns q (names or 0-based indices, comma-separated)",
     .group = kDataGroup,
     .sweep_rank = 13,
     .applies_to = AppliesTo::kDataTask,
     .key = "coords"},
    {.name = "momenta",
     .kind = ValueKind::kColumns,
     .help = "Momentum columns p, one per coordinate",
     .group = kDataGroup,
     .sweep_rank = 14,
     .applies_to = AppliesTo::kDataTask,
     .key = "momenta"},
    {.name = "velocities",
     .kind = ValueKind::kColumns,
     .help = "Velocity columns dq/dt instead of momenta (unit masses assumed)",
     .group = kDataGroup,
     .sweep_rank = 15,
     .applies_to = AppliesTo::kDataTask,
     .key = "velocities"},
    {.name = "derivatives",
     .kind = ValueKind::kColumns,
     .help = "Columns of dx/dt, one per state column (default: those named d<x>/dt, d<x>dt or "
             "<x>_dot when the file has them, else finite differences; none: finite differences)",
     .group = kDataGroup,
     .sweep_rank = 16,
     .applies_to = AppliesTo::kDataTask,
     .key = "derivatives"},
    {.name = "time",
     .kind = ValueKind::kText,
     .help = "Time column (default: t, else time, else times)",
     .group = kDataGroup,
     .sweep_rank = 17,
     .applies_to = AppliesTo::kDataTask,
     .key = "time"},
    {.name = "trajectory",
     .kind = ValueKind::kText,
     .help = "Trajectory id column (default: trajectory, else trial; none: one trajectory)",
     .group = kDataGroup,
     .sweep_rank = 18,
     .applies_to = AppliesTo::kDataTask,
     .key = "trajectory"},
    {.name = "split",
     .kind = ValueKind::kChoice,
     .help = "Test split: trajectories (the last --test-fraction of the trajectories held out), "
             "time (the last --test-fraction of each trajectory's rows) or auto (the default: "
             "by trajectories when the file has more than one, else by time)",
     .group = kDataGroup,
     .sweep_rank = 19,
     .applies_to = AppliesTo::kDataTask,
     .key = "split",
     .choices = split_names,
     .noun = "split"},
    {.name = "test-fraction",
     .kind = ValueKind::kFraction,
     .help = "Share of the trajectories (or of each one's rows) held out, in (0, 1) (default "
             "0.2)",
     .group = kDataGroup,
     .sweep_rank = 20,
     .applies_to = AppliesTo::kDataTask,
     .key = "test_fraction"},
    {.name = "hamiltonian",
     .kind = ValueKind::kText,
     .help = "A known H over the state's column names, for the energy metric",
     .group = kDataGroup,
     .sweep_rank = 21,
     .applies_to = AppliesTo::kDataTask,
     .key = "hamiltonian"},
};

}  // namespace

// The core rows, then the field tasks' training methods (train_options_methods.cpp).
std::span<const TrainOption> train_options() {
  static const std::vector<TrainOption> all = [] {
    std::vector<TrainOption> rows(std::begin(kOptions), std::end(kOptions));
    const std::span<const TrainOption> methods = detail::training_method_options();
    rows.insert(rows.end(), methods.begin(), methods.end());
    return rows;
  }();
  return all;
}

}  // namespace hnn::tasks
