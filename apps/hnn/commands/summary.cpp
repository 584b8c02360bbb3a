// The few lines `hnn train` and `hnn evaluate` print (summary.h), from metrics.json's keys: each
// line is left out when a task has no such key (the pixel pendulum has no R^2, a data run without
// a known H no energy MSE, a run on scattered states no rollouts).

#include "apps/hnn/commands/summary.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>
#include <utility>
#include <vector>

namespace hnn::app {

namespace {

using nlohmann::json;

std::optional<double> number_at(const json& m, const std::string& key) {
  const auto it = m.find(key);
  if (it == m.end() || !it->is_number()) return std::nullopt;
  return it->get<double>();
}

// "3.12e-02 ± 1.1e-03" (the key and its "_se"), or "" when the run has no such number.
std::string with_se(const json& m, const std::string& key) {
  const std::optional<double> value = number_at(m, key);
  if (!value) return "";
  const std::optional<double> se = number_at(m, key + "_se");
  return se ? fmt::format("{:.3g} ± {:.2g}", *value, *se) : fmt::format("{:.3g}", *value);
}

std::string text_at(const json& m, const std::string& key) {
  const auto it = m.find(key);
  if (it == m.end()) return "";
  return it->is_string() ? it->get<std::string>() : it->dump();
}

// "2000 steps"; "sampled fit (uswim)" or "sampled fit (uswim), then 200 Adam steps".
std::string fit_words(const json& m) {
  const std::string steps = fmt::format("{} steps", text_at(m, "steps"));
  const auto fit = m.find("fit");
  if (fit == m.end() || !fit->is_object()) return steps;
  const std::string sampled = fmt::format("sampled fit ({})", text_at(*fit, "sampler"));
  return text_at(*fit, "method") == "sampled" ? sampled : sampled + ", then Adam " + steps;
}

// "spring hnn: seed 0, 2000 steps, hidden 200-200, double".
std::string heading_line(const json& m) {
  return fmt::format("{} {}: seed {}, {}, hidden {}, {}", text_at(m, "task"), text_at(m, "model"),
                     text_at(m, "seed"), fit_words(m), text_at(m, "hidden"), text_at(m, "dtype"));
}

// The held-out error of the trial of `curve` whose `key` is `chosen` (NaN if none).
double chosen_error(const json& curve, const char* key, double chosen) {
  for (const json& trial : curve)
    if (number_at(trial, key) == chosen) return number_at(trial, "error").value_or(NAN);
  return NAN;
}

// "  rcond      auto chose 1e-03 in 0.01 s (held-out field error 3.77e-02; 5.39e-02 at 1e-14,
// 0.263 at 1e-01)", for --rcond auto; "" otherwise.
std::string rcond_line(const json& fit) {
  const auto curve = fit.find("rcond_validation");
  if (curve == fit.end() || !curve->is_array() || curve->empty()) return "";
  const auto error_at = [&](const json& trial) { return number_at(trial, "error").value_or(NAN); };
  const double chosen = number_at(fit, "rcond_used").value_or(NAN);
  return fmt::format(
      "  rcond      auto chose {:.0e} in {:.3g} s (held-out field error {:.3g}; {:.3g} at {:.0e}, "
      "{:.3g} at {:.0e})\n",
      chosen, number_at(fit, "validation_seconds").value_or(NAN),
      chosen_error(*curve, "rcond", chosen), error_at(curve->front()),
      number_at(curve->front(), "rcond").value_or(NAN), error_at(curve->back()),
      number_at(curve->back(), "rcond").value_or(NAN));
}

// "  swim scale auto chose 0.0343 (held-out field error 2.1e-10; 1.6e-06 at 0.549)", for
// --swim-scale auto; "" otherwise. Its time is in the rcond line's (or is the validation's).
std::string swim_scale_line(const json& fit) {
  const auto curve = fit.find("swim_scale_validation");
  if (curve == fit.end() || !curve->is_array() || curve->empty()) return "";
  const double chosen = number_at(fit, "swim_scale_used").value_or(NAN);
  return fmt::format(
      "  swim scale auto chose {:.3g} (held-out field error {:.3g}; {:.3g} at {:.3g})\n", chosen,
      chosen_error(*curve, "scale", chosen), number_at(curve->front(), "error").value_or(NAN),
      number_at(curve->front(), "scale").value_or(NAN));
}

// "  fit        sampling 0.01 s, forming the matrix 0.02 s, solving 0.1 s (qr, rcond 1e-13):
// 2000 x 100 system, 1.6 MB, residual 1.2e-05", and the rcond line.
std::string fit_line(const json& m) {
  const auto fit = m.find("fit");
  if (fit == m.end() || !fit->is_object()) return "";
  const auto seconds = [&](const char* key) { return number_at(*fit, key).value_or(NAN); };
  std::string solver = text_at(*fit, "solver");
  if (const auto rcond = number_at(*fit, "rcond_used"))
    solver += fmt::format(", rcond {:g}", *rcond);
  return fmt::format(
             "  fit        sampling {:.3g} s, forming the matrix {:.3g} s, solving {:.3g} s ({}): "
             "{} x {} system, {:.3g} MB, residual {:.3g}\n",
             seconds("sample_seconds"), seconds("assemble_seconds"), seconds("solve_seconds"),
             solver, text_at(*fit, "rows"), text_at(*fit, "columns"), seconds("matrix_bytes") / 1e6,
             seconds("residual_rms")) +
         swim_scale_line(*fit) + rcond_line(*fit);
}

// R² to four digits, or its distance from 1 where four digits would round it to 1: a model
// whose fit is 1 - 2.6e-05 printed "R² test 1".
std::string r2_text(double r2) {
  if (r2 < 1.0 && r2 >= 0.99995) return fmt::format("1 - {:.2g}", 1.0 - r2);
  return fmt::format("{:.4g}", r2);
}

// "  loss     test 3.1e-02 ± 1e-03, train 3e-02 ± 1e-03; R² test 0.998, train 1 - 2.6e-05".
std::string loss_lines(const json& m) {
  std::string line = fmt::format("  loss       test {}, train {}", with_se(m, "test_loss"),
                                 with_se(m, "train_loss"));
  if (const auto r2 = number_at(m, "test_r2")) {
    line += fmt::format("; R² test {}", r2_text(*r2));
    if (const auto train = number_at(m, "train_r2")) line += ", train " + r2_text(*train);
  }
  line += "\n";
  if (m.contains("test_loss_standardised")) {
    line += fmt::format(
        "             in the data file's units; in standardised units (the progress line's and "
        "loss_curve.csv's): test {}, train {}\n",
        with_se(m, "test_loss_standardised"), with_se(m, "train_loss_standardised"));
  }
  return line;
}

// The model's valid prediction time. Rollouts whose error never passed the threshold count
// their whole span (censored): when every one did, the time is only the rollouts' length, and
// the words say so instead of giving it a spread; when some did, it is a lower bound.
std::string model_valid_time(const json& m, double count) {
  const double threshold = number_at(m, "valid_prediction_threshold").value_or(NAN);
  const double censored = number_at(m, "valid_prediction_censored").value_or(0);
  if (censored > 0 && censored == count) {
    return fmt::format(
        "valid prediction time: the whole rollout ({:.3g}); the relative state error of all {:g} "
        "stayed below {:g}",
        *number_at(m, "valid_prediction_time"), count, threshold);
  }
  std::string text = "valid prediction time " + with_se(m, "valid_prediction_time");
  if (!std::isnan(threshold))
    text += fmt::format(" (until the relative state error passes {:g})", threshold);
  if (censored > 0) {
    text += fmt::format(
        "; {:g} of {:g} rollouts never passed it and count their whole span, so it is a lower "
        "bound",
        censored, count);
  }
  return text;
}

// The valid prediction time, beside the truth's own (perturbed by 1e-4) where known.
std::string prediction_line(const json& m) {
  if (!number_at(m, "valid_prediction_time")) return "";
  const double count = number_at(m, "valid_prediction_time_count").value_or(0);
  std::string line = "  rollouts   " + model_valid_time(m, count);
  if (const auto floor = number_at(m, "valid_prediction_time_floor")) {
    const bool whole = number_at(m, "valid_prediction_floor_censored").value_or(0) == count;
    line += fmt::format("; the truth perturbed by 1e-4: {}{:.3g}",
                        whole && count > 0 ? "the whole rollout, " : "", *floor);
  }
  return line + "\n";
}

// A run on scattered states: no rollouts to report, and the one line says so.
std::string skipped_rollouts_line(const json& m) {
  if (!m.contains("rollouts_skipped")) return "";
  return "  rollouts   none: scattered states, no trajectories (no valid prediction time or "
         "reversibility)\n";
}

// The learned H against the true one on the held-out points, up to H's constant.
std::string hamiltonian_line(const json& m) {
  const std::optional<double> error = number_at(m, "hamiltonian_rel_l2");
  if (!error) return "";
  std::string points;
  if (const auto n = number_at(m, "hamiltonian_rel_l2_count"))
    points = fmt::format(" on {:g} held-out points", *n);
  return fmt::format("  H          relative L2 error {:.3g}{} (up to a constant)\n", *error,
                     points);
}

// The energy error against the true H: absolute and relative; or why there is none.
std::string energy_lines(const json& m) {
  std::string out;
  if (const std::string mse = with_se(m, "energy_mse"); !mse.empty()) {
    out += fmt::format("  energy     MSE {} against the true H", mse);
    if (const std::string relative = with_se(m, "energy_relative_mse"); !relative.empty())
      out += fmt::format(", relative {} (MSE / mean true E²)", relative);
    out += "\n";
  } else if (m.contains("energy_note")) {
    out += fmt::format("  energy     {}\n", text_at(m, "energy_note"));
  }
  if (const std::string end = with_se(m, "energy_error_end"); !end.empty())
    out += fmt::format("  energy     error at the end {} (the LNN paper's metric)\n", end);
  return out;
}

// The constrained tasks' metric (Finzi et al.'s, in Cartesian (x, v)), its floor and the failed
// rollouts, which it does not pool.
std::string constrained_line(const json& m) {
  const std::optional<double> error = number_at(m, "cartesian_error");
  const std::optional<double> failed = number_at(m, "cartesian_error_failed");
  if (!failed) return "";
  std::string line = fmt::format("  rollouts   Cartesian relative error (geometric mean) {}",
                                 error ? fmt::format("{:.3g}", *error) : std::string("none"));
  if (const auto floor = number_at(m, "cartesian_error_floor"))
    line += fmt::format(", floor {:.3g}", *floor);
  return line + fmt::format("; failed rollouts {:g} of {:g}\n", *failed,
                            number_at(m, "cartesian_error_rollouts").value_or(NAN));
}

// What the training's integrator (and the data's noise) cost on their own: the true system's
// rollout loss through it, which a model's training loss goes below only by fitting the noise or
// undoing the integrator's error, beside the loss the training ended at.
std::string integrator_line(const json& m) {
  const auto truth = number_at(m, "truth_rollout_loss");
  const auto training = m.find("training");
  if (!truth || training == m.end() || !training->is_object()) return "";
  const std::string dt = text_at(*training, "dt");
  std::string line = fmt::format(
      "  integrator the true system through {} ({}) has rollout loss {:.3g}",
      text_at(*training, "integrator"),
      dt == "sampling interval" ? "a step per sampling interval" : "steps of " + dt, *truth);
  if (const auto last = number_at(m, "final_batch_loss"))
    line += fmt::format("; the training's last batch {:.3g}", *last);
  return line + "\n";
}

// Learned masses (--masses learned) beside the system's, and how far apart they move it (the
// motion fixes only part of them: metrics.json's masses_note).
std::string masses_line(const json& m) {
  const auto error = number_at(m, "masses_tangent_error");
  if (!error) return "";
  return fmt::format(
      "  masses     learned {:.4g} (true {:.4g}); as they move the system, {:.2g} off up to a "
      "scale\n",
      fmt::join(m.at("masses_learned").get<std::vector<double>>(), ", "),
      fmt::join(m.at("masses_true").get<std::vector<double>>(), ", "), *error);
}

std::string timing_line(const json& m) {
  constexpr std::pair<const char*, const char*> kTimes[] = {{"train_seconds", "training"},
                                                            {"curve_seconds", "loss curve"},
                                                            {"data_seconds", "data"},
                                                            {"eval_seconds", "evaluation"}};
  std::vector<std::string> parts;
  for (const auto& [key, name] : kTimes) {
    if (const auto s = number_at(m, key)) parts.push_back(fmt::format("{} {:.1f} s", name, *s));
  }
  if (parts.empty()) return "";
  std::string line = "  time      ";
  for (std::size_t i = 0; i < parts.size(); ++i) line += (i ? ", " : " ") + parts[i];
  return line + "\n";
}

}  // namespace

std::string metrics_summary(const json& m) {
  return heading_line(m) + "\n" + loss_lines(m) + prediction_line(m) + constrained_line(m) +
         integrator_line(m) + masses_line(m) + skipped_rollouts_line(m) + hamiltonian_line(m) +
         energy_lines(m) + fit_line(m) + timing_line(m);
}

void print_warnings(const json& metrics) {
  const auto it = metrics.find("warnings");
  if (it == metrics.end() || !it->is_array()) return;
  for (const json& warning : *it)
    fmt::print(stderr, "hnn: warning: {}\n", warning.get<std::string>());
}

std::string files_in(const std::filesystem::path& dir, std::filesystem::file_time_type since) {
  std::vector<std::string> names;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    if (entry.is_regular_file() && entry.last_write_time() >= since)
      names.push_back(entry.path().filename().string());
  }
  std::sort(names.begin(), names.end());
  std::string out;
  for (const std::string& name : names) out += (out.empty() ? "" : ", ") + name;
  return out;
}

}  // namespace hnn::app
