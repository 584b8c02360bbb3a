#pragma once
// What the training loop trains: a model, its parameters in groups with their own optimiser
// settings (PyTorch's param_groups), a sampler of batches and the loss of a batch. Each kind of
// task writes one; the loop (train/loop.h) does the rest: Adam steps, the loss curve,
// checkpoints, resume and stop.

#include <cstdint>
#include <stdexcept>
#include <vector>

#include "autodiff/parallel.h"
#include "autodiff/var.h"
#include "nn/dynamics.h"
#include "nn/module.h"
#include "nn/optim.h"
#include "tasks/report/run_folder.h"
#include "tasks/train/sampler.h"

namespace hnn::tasks {

template <typename T>
class Objective {
 public:
  virtual ~Objective() = default;
  /// The model trained (its parameters and the optimisers' moments make a checkpoint).
  virtual nn::Module<T>& model() = 0;
  /// The groups of nn::Adam, each with its own settings; in order, they list
  /// model().parameters() in its order.
  virtual std::vector<nn::AdamGroup<T>> parameter_groups() const = 0;
  virtual RowSampler& sampler() = 0;
  /// The mean loss over the sampler's current batch, on the graph.
  virtual ad::Var<T> batch_loss() = 0;

  // Steps split by rows (nn/row_split.h): an objective whose loss is a mean over its batch's
  // rows, computed by one DynamicsModel, says which; the loop may then give each thread a block
  // of the rows and a replica of that model.
  /// The model the loss is computed by (model() itself, so that the split's gradients come in
  /// parameter_groups' order), or nullptr when the loss cannot be split by rows.
  virtual const nn::DynamicsModel<T>* row_model() const { return nullptr; }
  /// Gathers the sampler's current batch for rows_loss; returns its row count.
  virtual Eigen::Index gather_batch() { throw std::logic_error("gather_batch: no row_model"); }
  /// The mean loss over rows `block` of the gathered batch, computed by `model` (row_model() or
  /// a replica of it). Called on several threads at once, one block each.
  virtual ad::Var<T> rows_loss(const nn::DynamicsModel<T>& /*model*/,
                               ad::RowBlock /*block*/) const {
    throw std::logic_error("rows_loss: no row_model");
  }
  /// The losses of a loss-curve point, without a graph; `batch_loss` is this step's (the train
  /// loss itself when the batch is the full training set).
  virtual CurvePoint curve_point(long step, double batch_loss) const = 0;
  /// A fingerprint of the training data: a checkpoint of other data is refused.
  virtual std::uint64_t data_fingerprint() const = 0;
};

}  // namespace hnn::tasks
