#pragma once
// The one CSV format of rollouts, written here only: a run's rollout.csv and `hnn rollout`'s
// rollout_<integrator>.csv alike.
//
//   source,traj,t,<state columns>,energy,learned_h
//
// One block of rows per source and trajectory. The source is "true" (the true system
// integrated), "data" (measured or held-out data) or the model's name (hnn, baseline, dhnn); the
// state columns are the data's own names where the run has them (q,p), else x_0..x_{d-1};
// energy is the true energy of the row's state (a known H), learned_h the model's H along its
// own path. A long layout, not truth and prediction side by side, because they need not share
// times: measured data keep their own times and a rollout can run past the data's end.
//
// A value that is NaN or infinite is an empty cell (csv_cell.h): a missing sample, a column a
// source does not have, a rollout that failed.

#include <Eigen/Core>
#include <string>
#include <string_view>
#include <vector>

namespace hnn::tasks {

/// Times as a vector.
inline Eigen::VectorXd as_vector(const std::vector<double>& v) {
  return Eigen::Map<const Eigen::VectorXd>(v.data(), Eigen::Index(v.size()));
}

struct CsvDigits {
  int values = 12;  ///< significant digits of every value but the times
  int times = 9;
};

/// The sources of a rollout CSV besides the models' names.
inline constexpr std::string_view kTrueSource = "true", kDataSource = "data";

class RolloutCsv {
 public:
  /// `columns` names the state's columns. With `skip_incomplete`, a row whose state has a
  /// missing value is left out (measured paths with gaps).
  explicit RolloutCsv(const std::vector<std::string>& columns, CsvDigits digits = {},
                      bool skip_incomplete = false);
  /// One row per time t(k): states.row(k), energy(k) and learned_h(k); empty vectors give empty
  /// cells.
  void add(std::string_view source, std::size_t traj, const Eigen::VectorXd& t,
           const Eigen::MatrixXd& states, const Eigen::VectorXd& energy = {},
           const Eigen::VectorXd& learned_h = {});
  void add(std::string_view source, std::size_t traj, const std::vector<double>& t,
           const Eigen::MatrixXd& states, const Eigen::VectorXd& energy = {},
           const Eigen::VectorXd& learned_h = {}) {
    add(source, traj, as_vector(t), states, energy, learned_h);
  }
  const std::string& str() const { return csv_; }

 private:
  std::string csv_;
  CsvDigits digits_;
  bool skip_incomplete_;
};

/// `x_0`, ..., `x_{dim-1}`: the state's columns when they have no names.
std::vector<std::string> numbered_columns(std::string_view prefix, Eigen::Index dim);

}  // namespace hnn::tasks
