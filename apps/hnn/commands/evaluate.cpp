// `hnn evaluate`: the metrics of a run folder's saved parameters, again; says which run, on
// which data, and what it wrote.

#include <fmt/format.h>

#include "apps/hnn/commands/commands.h"
#include "apps/hnn/commands/comparison.h"
#include "apps/hnn/commands/summary.h"
#include "tasks/run.h"

namespace hnn::app {

namespace {

// "on its own data (seed 0)", "on data/pend.csv (its own)", "on other.csv (--data)".
std::string data_evaluated(const nlohmann::json& m, const std::string& data) {
  if (!data.empty()) return fmt::format("on {} (--data)", data);
  const auto file = m.find("data_file");
  if (file != m.end() && file->is_string() && !file->get<std::string>().empty())
    return fmt::format("on {} (its own data file)", file->get<std::string>());
  return fmt::format("on its own data (the task's, seed {})", m.value("seed", 0ULL));
}

// The runs' names in the comparison: their models, or their folders when the models are alike.
std::pair<std::string, std::string> run_names(const nlohmann::json& a, const std::string& a_dir,
                                              const nlohmann::json& b, const std::string& b_dir) {
  const std::string x = a.value("model", ""), y = b.value("model", "");
  if (x != y && !x.empty() && !y.empty()) return {x, y};
  return {std::filesystem::path(a_dir).lexically_normal().string(),
          std::filesystem::path(b_dir).lexically_normal().string()};
}

}  // namespace

void add_evaluate_command(CLI::App& app) {
  auto* cmd = app.add_subcommand("evaluate", "Evaluate the saved parameters of a run folder");
  auto dir = std::make_shared<std::string>();
  auto data = std::make_shared<std::string>();
  auto write = std::make_shared<bool>(false);
  auto json = std::make_shared<bool>(false);
  auto against = std::make_shared<std::string>();
  cmd->add_option("run", *dir, "Run folder written by `hnn train`")
      ->required()
      ->check(CLI::ExistingDirectory);
  cmd->add_option("--data", *data,
                  "Evaluate on this measured-data file instead of the run's own: another file "
                  "of the same format, or the run's own at a new place (its SHA-256 is not "
                  "checked)")
      ->check(CLI::ExistingFile);
  cmd->add_flag("--write", *write,
                "Also rewrite the run's evaluation files (rollout.csv and the task's own)");
  cmd->add_flag("--json", *json, "Print the metrics as JSON on stdout instead of the summary");
  cmd->add_option("--against", *against,
                  "Another run of the same task and data (a baseline, say), evaluated alike and "
                  "shown beside this one with the ratios")
      ->check(CLI::ExistingDirectory)
      ->option_text("RUN");
  cmd->callback([=] {
    if (!against->empty()) check_comparable(*dir, *against);
    const auto start = std::filesystem::file_time_type::clock::now();
    const nlohmann::json m = tasks::evaluate_run(*dir, *data, *write);
    const nlohmann::json other =
        against->empty() ? nlohmann::json() : tasks::evaluate_run(*against, *data, false);
    if (*json) {
      fmt::print("{}\n", against->empty() ? m.dump(2)
                                          : nlohmann::json{{"run", m}, {"against", other}}.dump(2));
    } else {
      const std::string written = *write ? files_in(*dir, start) : "";
      fmt::print("hnn evaluate: the parameters in {} {}\n{}  wrote      {}\n",
                 (std::filesystem::path(*dir) / "params.bin").string(), data_evaluated(m, *data),
                 metrics_summary(m),
                 written.empty() ? "nothing (metrics.json is as training left it; --write "
                                   "rewrites the evaluation files)"
                                 : written);
      if (!against->empty()) {
        const auto [a, b] = run_names(m, *dir, other, *against);
        fmt::print("  against    {}, evaluated alike on the same data\n{}", *against,
                   comparison_table(m, a, other, b));
      }
    }
    print_warnings(m);
  });
}

}  // namespace hnn::app
