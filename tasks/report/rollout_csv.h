#pragma once
// The two CSV formats of rollouts, each written here only.
//
// - Paths (`hnn rollout`): source,traj,t,<state columns>,energy,learned_h, one block of rows
//   per source (the truth, measured data, a model) and trajectory.
// - Comparisons (a run's rollout.csv): traj,t,true_0..,pred_0..,true_energy,pred_energy,
//   learned_h, the truth and the prediction side by side.
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

class PathsCsv {
 public:
  /// `columns` names the state's columns. With `skip_incomplete`, a row whose state has a
  /// missing value is left out (measured paths with gaps).
  explicit PathsCsv(const std::vector<std::string>& columns, CsvDigits digits = {},
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

class ComparisonCsv {
 public:
  explicit ComparisonCsv(Eigen::Index dim, CsvDigits digits = {});
  /// One row per time t(k) of trajectory `traj`; empty energy or learned_h vectors give empty
  /// cells.
  void add(std::size_t traj, const Eigen::VectorXd& t, const Eigen::MatrixXd& truth,
           const Eigen::MatrixXd& pred, const Eigen::VectorXd& true_energy,
           const Eigen::VectorXd& pred_energy, const Eigen::VectorXd& learned_h);
  void add(std::size_t traj, const std::vector<double>& t, const Eigen::MatrixXd& truth,
           const Eigen::MatrixXd& pred, const Eigen::VectorXd& true_energy,
           const Eigen::VectorXd& pred_energy, const Eigen::VectorXd& learned_h) {
    add(traj, as_vector(t), truth, pred, true_energy, pred_energy, learned_h);
  }
  const std::string& str() const { return csv_; }

 private:
  std::string csv_;
  CsvDigits digits_;
};

/// `x_0`, ..., `x_{dim-1}`: the state's columns when they have no names.
std::vector<std::string> numbered_columns(std::string_view prefix, Eigen::Index dim);

}  // namespace hnn::tasks
