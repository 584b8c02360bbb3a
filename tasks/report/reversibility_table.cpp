#include "tasks/report/reversibility_table.h"

#include <fmt/format.h>

namespace hnn::tasks {

using nlohmann::json;

namespace {

constexpr const char* kHeader =
    "# Reversibility\n\n"
    "Each trained model's field integrated forward over the task's rollout span and back "
    "again; mean Euclidean distance between the start and the return, over the rollout "
    "states (pixel pendulum: encoded test pairs, latent space). Implicit midpoint is "
    "symmetric, so it returns for any field up to its solver tolerance; RK4 (dt = span/1000) "
    "and dopri5 (rtol 1e-9) are not, and show how the field amplifies their errors. det: mean "
    "determinant of the flow map's Jacobian over the span (1 = volume kept, Liouville).\n\n"
    "| task | model | midpoint | rk4 | dopri5 | det |\n| --- | --- | --- | --- | --- | --- |\n";

std::string integrator_cell(const json& row, const char* name) {
  for (const json& i : row["integrators"]) {
    if (i["integrator"] != name) continue;
    if (i.contains("failure")) return "failed";
    if (i["return_distance_mean"].is_number())
      return fmt::format("{:.2e}", i["return_distance_mean"].get<double>());
  }
  return "n/a";
}

std::string table_line(const json& row) {
  std::string line =
      fmt::format("| {} | {} |", row["task"].get<std::string>(), row["model"].get<std::string>());
  for (const char* name : {"midpoint", "rk4", "dopri5"})
    line += " " + integrator_cell(row, name) + " |";
  const json& v = row["volume"];
  line += v.contains("det_mean") && v["det_mean"].is_number()
              ? fmt::format(" {:.4g} |\n", v["det_mean"].get<double>())
              : " n/a |\n";
  return line;
}

std::string failure_lines(const json& row) {
  const std::string who =
      fmt::format("{} {}", row["task"].get<std::string>(), row["model"].get<std::string>());
  std::string lines;
  for (const json& i : row["integrators"]) {
    if (i.contains("failure"))
      lines += fmt::format("- {}: {}\n", who, i["failure"].get<std::string>());
  }
  if (row["volume"].contains("failure"))
    lines += fmt::format("- {}, det: {}\n", who, row["volume"]["failure"].get<std::string>());
  return lines;
}

}  // namespace

std::string reversibility_markdown(const json& rows) {
  std::string md = kHeader, failures;
  for (const json& row : rows) {
    md += table_line(row);
    failures += failure_lines(row);
  }
  if (!failures.empty()) md += "\nWhy a cell says failed or n/a:\n\n" + failures;
  return md;
}

}  // namespace hnn::tasks
