#pragma once
// The error of a learned H against the true one on held-out states: the sampled-HNN paper's
// metric (Rahma, Datar & Dietrich 2024, their error/l2.py), taken up to H's free constant, since
// Hamilton's equations fix H only up to one.

#include <nlohmann/json.hpp>

#include "physics/system.h"
#include "tasks/evaluate/rollouts.h"

namespace hnn::tasks {

/// ||e - mean(e)|| / ||truth|| with e = learned - truth over the same states: the relative L2
/// error after the best constant shift (the mean difference). The denominator is the true H as
/// the system defines it, as the paper's is, so its constant matters there only. NaN when the
/// sizes differ, there are no states, or the true H is zero on all of them.
double hamiltonian_rel_l2(const Eigen::VectorXd& truth, const Eigen::VectorXd& learned);

/// metrics.json's "hamiltonian_rel_l2" of `model` against `truth` on the states x (the held-out
/// points), with "hamiltonian_rel_l2_count"; a model without an H (a baseline, an LNN) gets
/// null and "hamiltonian_rel_l2_note" saying so.
nlohmann::json hamiltonian_error_metrics(const physics::System& truth, const LearnedField& model,
                                         const Batch& x);

}  // namespace hnn::tasks
