#include "tasks/train/fit_method.h"

#include <algorithm>
#include <cmath>
#include <optional>

#include "tasks/error.h"
#include "tasks/report/json_values.h"

namespace hnn::tasks {

using nlohmann::json;

namespace {

void check_fraction(double value, const std::string& key, const std::string& task) {
  HNN_TASKS_CHECK(value > 0 && value < 1, "{}: --{} must be in (0, 1), got {}", task,
                  fit_option_name(key), value);
}

// The number under `key`, or empty for "auto" or no such key; a value of another type is
// refused as "--KEY must be auto or WHAT".
std::optional<double> auto_or_number(const json& s, const std::string& key, const char* what,
                                     const std::string& task) {
  const auto it = s.find(key);
  if (it == s.end() || *it == "auto") return std::nullopt;
  HNN_TASKS_CHECK(it->is_number(), "{}: --{} must be auto or {}, got {}", task,
                  fit_option_name(key), what, it->dump());
  return it->get<double>();
}

// "rcond": auto (chosen by validation, nn/sampled/rcond_choice.h) or a number in (0, 1).
std::optional<double> rcond_setting(const json& s, const std::string& task) {
  const std::optional<double> rcond = auto_or_number(s, "rcond", "a number in (0, 1)", task);
  if (rcond) check_fraction(*rcond, "rcond", task);
  return rcond;
}

// "swim_scale": auto (chosen by validation, nn/sampled/scale_choice.h) or a finite number > 0.
std::optional<double> swim_scale_setting(const json& s, const std::string& task) {
  constexpr const char* kWhat = "a finite number > 0";
  const std::optional<double> scale = auto_or_number(s, "swim_scale", kWhat, task);
  HNN_TASKS_CHECK(!scale || (std::isfinite(*scale) && *scale > 0),
                  "{}: --swim-scale must be auto or {}, got {}", task, kWhat,
                  s.at("swim_scale").dump());
  return scale;
}

}  // namespace

std::string fit_option_name(std::string key) {
  std::replace(key.begin(), key.end(), '_', '-');
  return key;
}

std::vector<std::string> fit_method_names() { return nn::names_of(kFitMethodNames); }
std::vector<std::string> sampler_names() { return nn::names_of(nn::kHiddenSamplerNames); }
std::vector<std::string> solver_names() { return nn::names_of(nn::kLeastSquaresSolverNames); }

const std::vector<std::string>& fit_setting_names() {
  static const std::vector<std::string> names = {
      "fit",    "sampler",        "swim_scale",       "rcond",
      "solver", "regularization", "solver_tolerance", "solver_iterations"};
  return names;
}

FitConfig fit_config(const json& s, const std::string& task) {
  FitConfig c;
  try {
    if (s.contains("fit"))
      c.method = nn::parse_name(kFitMethodNames, s["fit"].get<std::string>(), "fit method");
    if (s.contains("sampler")) {
      c.sampled.sampler =
          nn::parse_name(nn::kHiddenSamplerNames, s["sampler"].get<std::string>(), "sampler");
    }
    if (s.contains("solver")) {
      c.sampled.solver =
          nn::parse_name(nn::kLeastSquaresSolverNames, s["solver"].get<std::string>(), "solver");
    }
    nn::SampledFitConfig& f = c.sampled;
    f.regularization = s.value("regularization", f.regularization);
    f.tolerance = s.value("solver_tolerance", f.tolerance);
    f.max_iterations = s.value("solver_iterations", f.max_iterations);
  } catch (const std::exception& e) {
    throw Error(fmt::format("{}: bad fit settings {}: {}", task, s.dump(), e.what()));
  }
  c.sampled.rcond = rcond_setting(s, task);
  c.sampled.swim_scale = swim_scale_setting(s, task);
  for (const std::string& key : fit_setting_names()) {
    HNN_TASKS_CHECK(c.samples() || key == "fit" || !s.contains(key),
                    "{}: --{} applies to a sampled fit only (add --fit sampled or --fit "
                    "sampled+adam)",
                    task, fit_option_name(key));
  }
  HNN_TASKS_CHECK(c.sampled.sampler != nn::HiddenSampler::kElm || !s.contains("swim_scale"),
                  "{}: --swim-scale does not apply to --sampler elm (it draws weights at random, "
                  "not from pairs of points; uswim and aswim read it)",
                  task);
  check_fraction(c.sampled.tolerance, "solver_tolerance", task);
  HNN_TASKS_CHECK(c.sampled.regularization > 0 && std::isfinite(c.sampled.regularization),
                  "{}: --regularization must be a finite number > 0, got {}", task,
                  c.sampled.regularization);
  HNN_TASKS_CHECK(c.sampled.max_iterations >= 1,
                  "{}: --solver-iterations must be at least 1, got {}", task,
                  c.sampled.max_iterations);
  return c;
}

namespace {

// --rcond auto's ladder: [{"rcond": 1e-14, "error": 0.05, "rank": 100}, ...]; empty otherwise.
json rcond_curve(const std::vector<nn::RcondTrial>& curve) {
  json out = json::array();
  for (const nn::RcondTrial& t : curve)
    out.push_back({{"rcond", t.rcond}, {"error", number(t.error)}, {"rank", t.rank}});
  return out;
}

// --swim-scale auto's walk: [{"scale": 0.549, "error": 1e-5}, ...]; empty otherwise.
json scale_curve(const std::vector<nn::ScaleTrial>& curve) {
  json out = json::array();
  for (const nn::ScaleTrial& t : curve)
    out.push_back({{"scale", t.scale}, {"error", number(t.error)}});
  return out;
}

}  // namespace

json fit_report_json(const FitConfig& config, const nn::SampledFitReport& r) {
  return {
      {"method", config.name()},
      {"sampler", nn::name_of(nn::kHiddenSamplerNames, config.sampled.sampler)},
      {"swim_scale", config.sampled.swim_scale ? json(*config.sampled.swim_scale) : json("auto")},
      {"swim_scale_used", r.swim_scale > 0 ? json(r.swim_scale) : json()},  // null: not read
      {"swim_scale_validation", scale_curve(r.scale_validation)},
      {"rcond", config.sampled.rcond ? json(*config.sampled.rcond) : json("auto")},
      {"rcond_used", r.rcond > 0 ? json(r.rcond) : json()},  // null: a solver without it
      {"rcond_validation", rcond_curve(r.rcond_validation)},
      {"validation_seconds", r.validation_seconds},
      {"solver", r.solver},
      {"regularization", config.sampled.regularization},
      {"regularization_used", r.regularization},
      {"solver_tolerance", config.sampled.tolerance},
      {"solver_iterations", config.sampled.max_iterations},
      {"sample_seconds", r.sample_seconds},
      {"assemble_seconds", r.assemble_seconds},
      {"solve_seconds", r.solve_seconds},
      {"gram_seconds", r.gram_seconds},
      {"rows", r.rows},
      {"columns", r.columns},
      {"matrix_bytes", r.matrix_bytes},
      {"residual_rms", number(r.residual_rms)},
      {"iterations", r.iterations}};
}

}  // namespace hnn::tasks
