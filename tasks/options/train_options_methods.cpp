// The rows of `hnn train`'s option table (train_options.h) for the ways a field task trains:
// through an integrator (the rollout loss), without backpropagation (a sampled fit), and what a
// baseline's MLP gives. train_options() puts them after the rows of train_options.cpp.

#include "tasks/integrate/integrator_step.h"
#include "tasks/options/model_settings.h"
#include "tasks/options/train_options.h"
#include "tasks/train/fit_method.h"
#include "tasks/train/rollout_objective.h"

namespace hnn::tasks::detail {

namespace {

constexpr std::string_view kRolloutGroup =
    "Training through an integrator (every task that learns a field)";
constexpr std::string_view kFitGroup =
    "Training without backpropagation (every task that learns a field)";

// In --help's order, after train_options.cpp's rows; sweep ranks as there.
const TrainOption kMethodOptions[] = {
    {.name = "loss",
     .kind = ValueKind::kChoice,
     .help = "derivative (dx/dt targets, the default) or rollout (from states alone: the model's "
             "field integrated over --horizon sampling intervals)",
     .group = kRolloutGroup,
     .sweep_rank = 22,
     .applies_to = AppliesTo::kFieldTasks,
     .key = "loss",
     .choices = loss_names,
     .noun = "loss"},
    {.name = "horizon",
     .kind = ValueKind::kInt,
     .help = "Sampling intervals per rollout window, 1 to 1000 (default 1)",
     .group = kRolloutGroup,
     .sweep_rank = 23,
     .applies_to = AppliesTo::kFieldTasks,
     .key = "horizon",
     .min = 1,
     .max = 1000,
     .range_in_help = true},
    {.name = "integrator",
     .kind = ValueKind::kChoice,
     .help = "The rollout loss's integrator: one of {} (default rk4)",
     .group = kRolloutGroup,
     .sweep_rank = 24,
     .applies_to = AppliesTo::kFieldTasks,
     .key = "integrator",
     .choices = rollout_integrator_names,
     .noun = "integrator"},
    {.name = "dt",
     .kind = ValueKind::kPositiveReal,
     .help = "The rollout loss's step (default: the sampling interval; it must divide it)",
     .group = kRolloutGroup,
     .sweep_rank = 25,
     .applies_to = AppliesTo::kFieldTasks,
     .key = "dt"},
    {.name = "norm",
     .kind = ValueKind::kChoice,
     .help = "The rollout loss's error: l2 (mean squared, the default) or l1 (mean absolute, "
             "Finzi et al.'s; the constrained tasks' default)",
     .group = kRolloutGroup,
     .sweep_rank = 33,
     .applies_to = AppliesTo::kFieldTasks,
     .key = "norm",
     .choices = rollout_norm_names,
     .noun = "norm"},
    {.name = "minibatches",
     .kind = ValueKind::kChoice,
     .help = "How the rollout loss's batches draw windows: independent (uniform, with "
             "replacement; the default) or epochs (shuffled epochs; the constrained tasks')",
     .group = kRolloutGroup,
     .sweep_rank = 36,
     .applies_to = AppliesTo::kFieldTasks,
     .key = "minibatches",
     .choices = minibatch_draw_names,
     .noun = "minibatch draw"},
    {.name = "fit",
     .kind = ValueKind::kChoice,
     .help = "adam, sampled (hidden layers sampled from the data, the last layer by least "
             "squares: no steps) or sampled+adam (sampled, then every weight fine-tuned by Adam "
             "for --steps) (default adam)",
     .group = kFitGroup,
     .sweep_rank = 26,
     .applies_to = AppliesTo::kFieldTasks,
     .key = "fit",
     .choices = fit_method_names,
     .noun = "fit method"},
    {.name = "sampler",
     .kind = ValueKind::kChoice,
     .help = "How a sampled fit draws hidden weights: elm (at random), uswim (each neuron from a "
             "pair of data points) or aswim (pairs weighted by how fast dx/dt changes) (default "
             "uswim)",
     .group = kFitGroup,
     .sweep_rank = 27,
     .applies_to = AppliesTo::kFieldTasks,
     .key = "sampler",
     .choices = sampler_names,
     .noun = "sampler"},
    {.name = "swim-scale",
     .kind = ValueKind::kAutoOrPositive,
     .help = "How steep uswim's and aswim's tanh or sigmoid neurons are: each neuron's "
             "pre-activation runs from -s to +s between its two data points, s a number > 0 (the "
             "peer's atanh(1/2) = 0.549; smaller, smoother neurons), or auto: the scale of "
             "0.549 * 2^k (k = -5 ... 2), walked from 0.549 while the field error on a held-out "
             "tenth of the points falls at least 1.5-fold a step, then refitted on all (default "
             "auto)",
     .group = kFitGroup,
     .sweep_rank = 38,
     .applies_to = AppliesTo::kFieldTasks,
     .key = "swim_scale"},
    {.name = "rcond",
     .kind = ValueKind::kAutoOrFraction,
     .help = "qr's, ridge's and sketch's least-squares cutoff: singular values below rcond times "
             "the largest do not shape the last layer (qr drops them, ridge and sketch damp "
             "them), a number in "
             "(0, 1) (the peer's 1e-13 suits exact dx/dt), or "
             "auto: the cutoff of 1e-14 ... 1e-1 with the smallest field error on a held-out "
             "tenth of the points, then refitted on all (default auto)",
     .group = kFitGroup,
     .sweep_rank = 28,
     .applies_to = AppliesTo::kFieldTasks,
     .key = "rcond"},
    {.name = "solver",
     .kind = ValueKind::kChoice,
     .help = "The last layer's least-squares solver: lsqr (preconditioned iterations), cholesky "
             "(regularised normal equations), qr (LAPACK's dgelsd, like numpy's lstsq), ridge "
             "(qr's reduction, then Tikhonov at rcond on its triangle) or sketch (ridge's problem "
             "by LSQR preconditioned with the QR of a sparse sketch: the sketch's QR instead of "
             "the whole data's) (default qr)",
     .group = kFitGroup,
     .sweep_rank = 29,
     .applies_to = AppliesTo::kFieldTasks,
     .key = "solver",
     .choices = solver_names,
     .noun = "solver"},
    {.name = "regularization",
     .kind = ValueKind::kPositiveReal,
     .help = "lambda added to the diagonal of A^T A (columns scaled to unit norm) by cholesky and "
             "lsqr's preconditioner, raised tenfold while the factorisation fails (default 1e-13)",
     .group = kFitGroup,
     .sweep_rank = 30,
     .applies_to = AppliesTo::kFieldTasks,
     .key = "regularization"},
    {.name = "solver-tolerance",
     .kind = ValueKind::kFraction,
     .help = "lsqr and sketch stop when |(A M)^T r| < this * |A M| |r| (M their "
             "preconditioner), in (0, 1) (default 1e-14)",
     .group = kFitGroup,
     .sweep_rank = 31,
     .applies_to = AppliesTo::kFieldTasks,
     .key = "solver_tolerance"},
    {.name = "solver-iterations",
     .kind = ValueKind::kInt,
     .help = "lsqr's and sketch's iteration cap, 1 to 100000 (default 200)",
     .group = kFitGroup,
     .sweep_rank = 32,
     .applies_to = AppliesTo::kFieldTasks,
     .key = "solver_iterations",
     .min = 1,
     .max = 100000,
     .range_in_help = true},
    {.name = "baseline-output",
     .kind = ValueKind::kChoice,
     .help = "What the baseline's MLP gives: field (all of dx/dt, the default) or accelerations "
             "(dv/dt alone, dq/dt = v given, as the LNN paper's baseline; tasks whose state is "
             "(q, dq/dt): double-pendulum, real-double-pendulum)",
     .sweep_rank = 34,
     .applies_to = AppliesTo::kFieldTasks,
     .key = "baseline_output",
     .choices = baseline_output_names,
     .noun = "baseline output"},
    {.name = "masses",
     .kind = ValueKind::kChoice,
     .help = "Whether a chnn or clnn takes its system's masses as known (the default) or learns "
             "them, each body's mass and moments, as Finzi et al.'s models do (learned)",
     .sweep_rank = 37,
     .applies_to = AppliesTo::kFieldTasks,
     .key = "masses",
     .choices = masses_names,
     .noun = "masses"},
};

}  // namespace

std::span<const TrainOption> training_method_options() { return kMethodOptions; }

}  // namespace hnn::tasks::detail
