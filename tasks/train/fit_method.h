#pragma once
// How a field model is fitted: by Adam on its loss (the default), by sampling its hidden layers
// and solving its last layer by least squares (nn/sampled/sampled_fit.h, no backpropagation), or
// by sampling then fine-tuning every weight with Adam. The task settings "fit", "sampler",
// "rcond", "solver", "regularization", "solver_tolerance" and "solver_iterations", the same on
// every task that learns a field; parsed once, where a run's settings are resolved
// (tasks/run.cpp), into RunSettings::fit.

#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <vector>

#include "nn/enum_names.h"
#include "nn/sampled/sampled_fit.h"

namespace hnn::tasks {

/// The hidden width of --fit sampled with the paper preset and no --hidden: one layer of 400
/// gave the sampled HNN's lowest energy error on spring and pendulum, two sampled layers of the
/// paper's 200 a thousand times more on spring (docs/sampled.md, "Noisy data: --rcond auto").
inline constexpr int kSampledWidth = 400;

enum class FitMethod { kAdam, kSampled, kSampledAdam };
inline constexpr nn::NameTable<FitMethod, 3> kFitMethodNames{{
    {FitMethod::kAdam, "adam"},
    {FitMethod::kSampled, "sampled"},
    {FitMethod::kSampledAdam, "sampled+adam"},
}};
std::vector<std::string> fit_method_names();
std::vector<std::string> sampler_names();
std::vector<std::string> solver_names();

struct FitConfig {
  FitMethod method = FitMethod::kAdam;
  /// The sampled fit's settings; its seed is the run's (set where the fit runs).
  nn::SampledFitConfig sampled{};

  /// Whether the hidden layers are sampled and the last layer solved.
  bool samples() const { return method != FitMethod::kAdam; }
  /// Whether Adam trains for the run's steps (from the sampled weights with sampled+adam).
  bool steps() const { return method != FitMethod::kSampled; }
  std::string_view name() const { return nn::name_of(kFitMethodNames, method); }
};

/// The keys above. Throws Error (naming `task`) on a bad value, and on a key other than "fit"
/// without a sampled fit.
FitConfig fit_config(const nlohmann::json& settings, const std::string& task);
const std::vector<std::string>& fit_setting_names();
/// "solver_tolerance" -> "solver-tolerance": the option that sets a key of fit_setting_names().
std::string fit_option_name(std::string key);

/// metrics.json's "fit": the method, the sampler and what the fit did (`report`).
nlohmann::json fit_report_json(const FitConfig& config, const nn::SampledFitReport& report);

}  // namespace hnn::tasks
