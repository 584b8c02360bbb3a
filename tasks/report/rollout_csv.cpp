#include "tasks/report/rollout_csv.h"

#include <fmt/format.h>

#include <cmath>

#include "tasks/report/csv_cell.h"

namespace hnn::tasks {

namespace {

double at(const Eigen::VectorXd& v, Eigen::Index k) { return k < v.size() ? v(k) : NAN; }

}  // namespace

std::vector<std::string> numbered_columns(std::string_view prefix, Eigen::Index dim) {
  std::vector<std::string> names;
  for (Eigen::Index c = 0; c < dim; ++c) names.push_back(fmt::format("{}_{}", prefix, c));
  return names;
}

RolloutCsv::RolloutCsv(const std::vector<std::string>& columns, CsvDigits digits,
                       bool skip_incomplete)
    : csv_("source,traj,t"), digits_(digits), skip_incomplete_(skip_incomplete) {
  for (const std::string& name : columns) csv_ += "," + name;
  csv_ += ",energy,learned_h\n";
}

void RolloutCsv::add(std::string_view source, std::size_t traj, const Eigen::VectorXd& t,
                     const Eigen::MatrixXd& states, const Eigen::VectorXd& energy,
                     const Eigen::VectorXd& learned_h) {
  for (Eigen::Index k = 0; k < states.rows(); ++k) {
    if (skip_incomplete_ && !states.row(k).allFinite()) continue;
    csv_ += fmt::format("{},{},{}", source, traj, csv_cell(t(k), digits_.times));
    for (Eigen::Index c = 0; c < states.cols(); ++c)
      csv_ += "," + csv_cell(states(k, c), digits_.values);
    csv_ += "," + csv_cell(at(energy, k), digits_.values) + "," +
            csv_cell(at(learned_h, k), digits_.values) + "\n";
  }
}

}  // namespace hnn::tasks
