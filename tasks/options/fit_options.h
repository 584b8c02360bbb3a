#pragma once
// Which of a run's options meet its fit (tasks/train/fit_method.h): a sampled fit takes no
// training steps, so the options of Adam's steps are refused with it, and an LNN cannot be
// fitted by a least-squares solve.

#include <filesystem>
#include <string>

#include "tasks/options.h"

namespace hnn::tasks {

/// Throws Error for a sampled fit of an LNN, with the reason.
void check_fit_model(const FitConfig& fit, nn::ModelKind model, const std::string& task);

/// The first option of Adam's steps given in `o` (below), or nullptr.
const char* adam_option_given(const RunOptions& o);

/// Throws Error naming the first option of Adam's steps given in `o` (--steps, --batch, --lr,
/// --lr-schedule, weight decay, --checkpoint-every, --resume): for a run fitted with --fit
/// sampled, which takes none.
void check_sampled_options(const RunOptions& o);

/// Throws Error, naming `task`, for a solver option in `settings` (the run's task_settings) that
/// `fit`'s least-squares solver does not read: --rcond but for qr and ridge; --regularization
/// but for lsqr and cholesky; --solver-tolerance and --solver-iterations but for lsqr.
void check_solver_options(const FitConfig& fit, const nlohmann::json& settings,
                          const std::string& task);

/// metrics.json's "fit" in `run_dir` (how its weights were sampled and solved), or, before its
/// metrics.json, the one its checkpoint carries; null for a run of Adam alone, or no run. What a
/// run evaluated again, resumed or continued with Adam (which does not sample again) keeps.
nlohmann::json recorded_fit(const std::filesystem::path& run_dir);

/// Throws Error when `run_dir` holds a run fitted with --fit sampled: it has no checkpoint, no
/// steps to resume or continue.
void check_not_sampled_run(const std::filesystem::path& run_dir);

}  // namespace hnn::tasks
