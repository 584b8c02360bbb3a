#include "tasks/report/table1.h"

#include <fmt/format.h>

#include <map>

namespace hnn::tasks {

using nlohmann::json;

namespace {

std::string value_se(const json& row, const std::string& key) {
  const json& v = row[key];
  const json& se = row[key + "_se"];
  if (!v.is_number()) return "n/a";
  if (!se.is_number()) return fmt::format("{:.4e}", v.get<double>());
  return fmt::format("{:.4e} ± {:.1e}", v.get<double>(), se.get<double>());
}

// ", 100 rollouts" when the rows say how many they rolled out (the HNN's row; both models of a
// task use the same count).
std::string rollouts_note(const json& row) {
  const json& n = row.contains("rollouts") ? row["rollouts"] : json();
  return n.is_number_integer() ? fmt::format(", {} rollouts", n.get<int>()) : "";
}

// ", lean 32-32" after a lean run's dtype; nothing for the paper's widths.
std::string widths_note(const json& row) {
  if (row.value("preset", "paper") == "paper") return "";
  return fmt::format(", {} {}", row["preset"].get<std::string>(), row.value("hidden", "?"));
}

}  // namespace

std::string table1_markdown(const json& rows, double wall_seconds,
                            const std::vector<std::string>& notes) {
  std::map<std::string, std::map<std::string, json>> by_task;
  std::vector<std::string> order;
  for (const json& r : rows) {
    const std::string task = r["task"];
    if (!by_task.count(task)) order.push_back(task);
    by_task[task][r["model"].get<std::string>()] = r;
  }
  std::string md = fmt::format(
      "# Table 1, reproduced\n\n"
      "Mean ± standard error, baseline / HNN, in the paper's units (not rescaled); for each "
      "task, our row and then the paper's (*paper*). Losses: mean squared error of dx/dt "
      "over the whole split; energy: MSE between the true energy along true and learned rollouts "
      "(adaptive RK45, rtol 1e-9), from as many test states as each row says (the paper used 15 "
      "per task; its standard errors are over those 15).\n\n"
      "| task | source | train loss (baseline / HNN) | test loss (baseline / HNN) | energy MSE "
      "(baseline / HNN) | train time (baseline / HNN) |\n"
      "| --- | --- | --- | --- | --- | --- |\n");
  for (const std::string& task : order) {
    const json& b = by_task[task]["baseline"];
    const json& h = by_task[task]["hnn"];
    if (b.is_null() || h.is_null()) continue;
    const auto both = [&](const std::string& key) {
      return value_se(b, key) + " / " + value_se(h, key);
    };
    md += fmt::format("| {} | ours ({} steps, {}{}{}) | {} | {} | {} | {:.1f} s / {:.1f} s |\n",
                      task, h["steps"].get<int>(), h["dtype"].get<std::string>(), widths_note(h),
                      rollouts_note(h), both("train_loss"), both("test_loss"), both("energy_mse"),
                      b["train_seconds"].get<double>(), h["train_seconds"].get<double>());
    md += fmt::format("| | *paper*{} | {} | {} | {} | |\n",
                      rollouts_note(h).empty() ? "" : " (15 rollouts)", both("paper_train_loss"),
                      both("paper_test_loss"), both("paper_energy_mse"));
  }
  for (const std::string& note : notes) md += "\n" + note + "\n";
  md += fmt::format("\nWall time of the whole reproduction: {:.1f} s.\n", wall_seconds);
  return md;
}

}  // namespace hnn::tasks
