#pragma once
// A model's loss over a whole split, with the standard error of the paper's Table 1.

#include "nn/dynamics.h"
#include "nn/loss.h"
#include "physics/system.h"

namespace hnn::tasks {

using physics::Batch;

/// Mean squared error of the model's field over a whole split (all N points, all D components),
/// with the reference implementation's standard error: std(N x D squared errors, n - 1
/// normalised) / sqrt(N), the convention of the paper's Table 1. Throws on an empty split.
nn::MeanStderr loss_stats(const nn::DynamicsModel<double>& model, const Batch& x,
                          const Batch& dxdt);
/// The same for any field (a model in other units, say).
nn::MeanStderr loss_stats(const physics::VectorField& field, const Batch& x, const Batch& dxdt);

}  // namespace hnn::tasks
