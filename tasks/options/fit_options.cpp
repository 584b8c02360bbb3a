#include "tasks/options/fit_options.h"

#include <utility>

#include "tasks/error.h"
#include "tasks/report/run_folder.h"
#include "tasks/train/checkpoint.h"

namespace hnn::tasks {

namespace fs = std::filesystem;

// An LNN's accelerations invert its Hessian in dq/dt, a mass HNN's its learned mass matrix: neither
// is linear in a last layer.
void check_fit_model(const FitConfig& fit, nn::ModelKind model, const std::string& task) {
  HNN_TASKS_CHECK(
      !fit.samples() || !nn::needs_velocities(model),
      "{}: --fit {} does not fit an {}: its accelerations are not linear in its last "
      "layer (they invert {}), so no least-squares solve gives it (models it fits: "
      "hnn, baseline, dhnn)",
      task, fit.name(), nn::to_string(model),
      model == nn::ModelKind::kLnn ? "the Hessian of L in dq/dt" : "its learned mass matrix");
}

const char* adam_option_given(const RunOptions& o) {
  const std::pair<bool, const char*> adam_options[] = {
      {o.steps.has_value(), "--steps"},
      {o.batch_size.has_value(), "--batch"},
      {o.learning_rate.has_value(), "--lr"},
      {o.lr_schedule.has_value(), "--lr-schedule"},
      {o.optimizer.has_value(), "--optimizer"},
      {o.weight_decay.has_value(), "weight decay"},
      {o.checkpoint_every.has_value(), "--checkpoint-every"},
      {o.resume, "--resume"}};
  for (const auto& [given, name] : adam_options)
    if (given) return name;
  return nullptr;
}

// The options of Adam's steps, given with --fit sampled (which takes no steps): refused.
void check_sampled_options(const RunOptions& o) {
  const char* name = adam_option_given(o);
  HNN_TASKS_CHECK(name == nullptr,
                  "{} does not apply to --fit sampled: it takes no training steps (the hidden "
                  "layers are sampled, the last layer solved); --fit sampled+adam fine-tunes "
                  "with Adam from there",
                  name);
}

void check_solver_options(const FitConfig& fit, const nlohmann::json& settings,
                          const std::string& task) {
  using nn::LeastSquaresSolver;
  const LeastSquaresSolver solver = fit.sampled.solver;
  const bool lsqr = solver == LeastSquaresSolver::kLsqr;
  const bool iterates = nn::iterates(solver);
  struct SolverOption {
    const char* key;
    bool read;  // by this solver
    const char* readers;
  };
  const SolverOption options[] = {
      {"rcond", nn::reads_rcond(solver), "qr, ridge and sketch"},
      {"regularization", lsqr || solver == LeastSquaresSolver::kCholesky, "lsqr and cholesky"},
      {"solver_tolerance", iterates, "lsqr and sketch"},
      {"solver_iterations", iterates, "lsqr and sketch"}};
  for (const SolverOption& o : options) {
    HNN_TASKS_CHECK(
        o.read || !settings.contains(o.key), "{}: --{} does not apply to --solver {} (read by {})",
        task, fit_option_name(o.key), nn::name_of(nn::kLeastSquaresSolverNames, solver), o.readers);
  }
}

nlohmann::json recorded_fit(const fs::path& run_dir) {
  const RunFolder folder(run_dir);
  std::error_code ec;
  if (fs::exists(folder.file("metrics.json"), ec))
    return folder.read_metrics().value("fit", nlohmann::json());
  // Interrupted before its metrics.json: its checkpoint carries the report (tasks/run.cpp).
  if (!fs::exists(folder.checkpoint_dir() / "state.json", ec)) return nullptr;
  return read_train_state(folder.checkpoint_dir()).run.value("fit", nlohmann::json());
}

void check_not_sampled_run(const fs::path& run_dir) {
  const RunFolder folder(run_dir);
  std::error_code ec;
  if (fs::exists(folder.checkpoint_dir() / "state.json", ec)) return;
  if (!fs::exists(folder.file("metrics.json"), ec)) return;
  const nlohmann::json settings = folder.read_metrics().value("task_settings", nlohmann::json());
  HNN_TASKS_CHECK(!settings.is_object() || settings.value("fit", "") != "sampled",
                  "'{}' holds a run fitted with --fit sampled: it took no training steps, so "
                  "there is nothing to resume or continue (train a new run with --fit "
                  "sampled+adam --steps N to fine-tune with Adam)",
                  run_dir.string());
}

}  // namespace hnn::tasks
