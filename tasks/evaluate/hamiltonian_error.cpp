#include "tasks/evaluate/hamiltonian_error.h"

#include <cmath>

#include "tasks/report/json_values.h"

namespace hnn::tasks {

double hamiltonian_rel_l2(const Eigen::VectorXd& truth, const Eigen::VectorXd& learned) {
  if (truth.size() != learned.size() || truth.size() == 0) return NAN;
  const Eigen::ArrayXd e = (learned - truth).array();
  const double scale = truth.norm();
  return scale > 0 ? std::sqrt((e - e.mean()).square().sum()) / scale : NAN;
}

nlohmann::json hamiltonian_error_metrics(const physics::System& truth, const LearnedField& model,
                                         const Batch& x) {
  if (!model.hamiltonian) {
    return {
        {"hamiltonian_rel_l2", nullptr},
        {"hamiltonian_rel_l2_note", "the model learns no H (an hnn, dhnn, lnn or hnn-mass does)"}};
  }
  return {{"hamiltonian_rel_l2",
           number(hamiltonian_rel_l2(truth.hamiltonian_batch(x), model.hamiltonian(x)))},
          {"hamiltonian_rel_l2_count", x.rows()}};
}

}  // namespace hnn::tasks
