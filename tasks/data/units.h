#pragma once
// The units a model trains in: every state column centred and scaled, and a time unit, chosen
// from the training split so that data of any scale (positions of 100, velocities of 0.01)
// trains like the paper's unit-scale systems. Losses, rollouts and the learned H are reported
// back in the file's units.
//
// An HNN stays an HNN in these units only if every degree of freedom's coordinate scale times
// its momentum scale is the same number c: then z = (x - mean) / scale, t' = t / time and
// H' = H * time / c give dz/dt' = (dH'/dp', -dH'/dq'). The scales are the columns' standard
// deviations, each pair adjusted by one common factor to meet that constraint.

#include <nlohmann/json.hpp>

#include "tasks/data/dataset.h"

namespace hnn::tasks {

struct Units {
  Eigen::RowVectorXd mean, scale;  ///< per state column: x = mean + scale * z
  double time = 1;                 ///< the model's time unit, in the file's time unit

  /// z = (x - mean) / scale and its inverse.
  Batch to_model(const Batch& x) const;
  Batch to_file(const Batch& z) const;
  /// dz/dt' = dx/dt * time / scale and its inverse.
  Batch rate_to_model(const Batch& dxdt) const;
  Batch rate_to_file(const Batch& dzdt) const;
  /// H in the file's units per unit of the model's H: c / time.
  double energy_to_file() const;
  /// Both splits in the model's units.
  Dataset to_model(const Dataset& data) const;
  nlohmann::json to_json() const;
};

/// Units fitted to the training split of data with `coordinates` degrees of freedom (state
/// columns q_1..q_n, p_1..p_n): means and standard deviations of the states, scales of each
/// (q_i, p_i) pair multiplied by one factor so that their products are equal, and the time
/// unit that gives the scaled targets a root mean square of 1. Throws Error naming the column
/// (from `names`) when a column is constant or the targets are all zero.
Units fit_units(const Dataset& data, Eigen::Index coordinates,
                const std::vector<std::string>& names);

/// Units that change nothing (mean 0, scale 1, time 1), for `dim` columns.
Units identity_units(Eigen::Index dim);

}  // namespace hnn::tasks
