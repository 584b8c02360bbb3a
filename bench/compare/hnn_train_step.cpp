// hnn's side of the PyTorch / LibTorch comparison (bench/compare/README.md): trains one task's
// model with the trainer's step (TapeScope, mse of time_derivative or the rollout loss through
// tasks::integrator_step, grad, Adam or AdamW) and prints one JSON line with the median ms/step
// over timed windows and the final train/test losses. Also writes the data and initial parameters
// that torch_step.py and libtorch_step load, so all three run the same computation from the same
// start on the same batches (compare_common.h).

#include <Eigen/Core>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "autodiff/flop_count.h"
#include "autodiff/grad.h"
#include "autodiff/ops.h"
#include "autodiff/parallel.h"
#include "autodiff/tape.h"
#include "bench/compare/compare_common.h"
#include "bench/fma_peak.h"
#include "nn/hnn.h"
#include "nn/loss.h"
#include "nn/optim.h"
#include "nn/row_split.h"
#include "tasks/experiments/registry.h"
#include "tasks/field/field_task.h"
#include "tasks/integrate/integrator_step.h"
#include "tasks/pixel/model.h"
#include "tasks/train/field_objective.h"
#include "tasks/train/rollout_objective.h"

namespace {

namespace ad = hnn::ad;
namespace nn = hnn::nn;
namespace pixel = hnn::tasks::pixel;
namespace cmp = hnn::compare;
using nlohmann::json;

constexpr double kHnnWeight = 0.1;  // pixel loss = ae + cc + 0.1 hnn

// ---- data ---------------------------------------------------------------------------------

using Batch = hnn::physics::Batch;

cmp::Rows to_rows(const Batch& b) {
  return {b.rows(), b.cols(), std::vector<double>(b.data(), b.data() + b.size())};
}

Batch to_batch(const cmp::Rows& r) {
  return Eigen::Map<const Batch>(r.values.data(), r.rows, r.cols);
}

// The pairs of frames of rows [start, start + count) (next: their successors), as the pixel
// trainer assembles them.
Batch pixel_split(const pixel::PixelData& d, Eigen::Index start, Eigen::Index count, bool next) {
  std::vector<Eigen::Index> rows(static_cast<std::size_t>(count));
  for (Eigen::Index i = 0; i < count; ++i) rows[std::size_t(i)] = start + i;
  return d.pairs_of<double>(rows, next);
}

// The task's own dataset (spring, two-body, three-body) or, for the pixel task, the pairs of
// frames of PixelConfig's scene with `pixel_trials` trials (x = pair, target = next pair).
cmp::Data build_data(const cmp::Options& o) {
  if (o.task == "pixel") {
    pixel::PixelConfig config;
    config.trials = o.pixel_trials;
    const pixel::PixelData d = pixel::build_pixel_data(config, o.seed);
    const Eigen::Index n = d.train_rows(), t = d.test_rows;
    return {to_rows(pixel_split(d, t, n, false)), to_rows(pixel_split(d, t, n, true)),
            to_rows(pixel_split(d, 0, t, false)), to_rows(pixel_split(d, 0, t, true))};
  }
  const hnn::tasks::Dataset d = hnn::tasks::build_dataset(cmp::task_name(o.task), o.seed);
  return {to_rows(d.train_x), to_rows(d.train_dxdt), to_rows(d.test_x), to_rows(d.test_dxdt)};
}

// A split as the step sees it: matrices with the same rows. The field loss takes {x, dx/dt}
// (pixel: {pair, next pair}); the rollout loss {start, next_1..next_K, step_1..step_K}, the
// tasks::RolloutWindows of the split's trajectories (Note [Rollout windows]).
using Parts = std::vector<Batch>;

Parts split_parts(const cmp::Options& o, const cmp::Rows& x, const cmp::Rows& dx) {
  if (o.loss != "rollout") return {to_batch(x), to_batch(dx)};
  const cmp::Stretches s = cmp::rollout_stretches(o.task);
  const hnn::tasks::RolloutWindows w = hnn::tasks::rollout_windows(
      hnn::tasks::regular_stretches(to_batch(x), int(s.points), s.t_end), o.horizon);
  Parts parts{w.start};
  parts.insert(parts.end(), w.next.begin(), w.next.end());
  parts.insert(parts.end(), w.step.begin(), w.step.end());
  return parts;
}

// ---- models -------------------------------------------------------------------------------

// The dynamics model of a task as the trainer builds it (FieldModelRun::fresh_model): the kind,
// widths and activation asked for, and the task's angle coordinates and input scales.
nn::DynamicsConfig dynamics_config(const cmp::Options& o) {
  nn::DynamicsConfig config;
  config.model = nn::parse_model_kind(o.model);
  if (config.model == nn::ModelKind::kDhnn) config.field = nn::FieldType::kBoth;
  config.dim = cmp::task_dim(o.task);
  if (!o.hidden.empty()) config.hidden.assign(o.hidden.begin(), o.hidden.end());
  config.activation = nn::parse_activation(o.activation);
  const auto task = hnn::tasks::make_field_task(cmp::task_name(o.task));
  config.angles = task->angle_coordinates();
  config.input_scale = task->input_scale();
  if (nn::is_constrained(config.model)) config.constraints = task->constraints();
  return config;
}

// One model behind a common face: its parameters, its loss on a batch, its Adam groups.
template <typename T>
class Model {
 public:
  /// `rows`: the training set's (a batch of 0 is all of them).
  Model(const cmp::Options& o, Eigen::Index rows)
      : rollout_(o.loss == "rollout"),
        l1_(o.norm == "l1"),
        integrator_(hnn::tasks::parse_rollout_integrator(o.integrator)) {
    std::mt19937_64 rng(o.seed);
    if (o.task == "pixel") {
      pixel::PixelConfig config;
      const auto kind = o.model == "hnn" ? nn::ModelKind::kHnn : nn::ModelKind::kBaseline;
      pixel_ = std::make_unique<pixel::PixelModel<T>>(config, kind, rng);
      for (const nn::NamedParameter<T>& p : pixel_->named_parameters()) {
        named_.push_back(p);
        (p.name.rfind("dynamics.", 0) == 0 ? dyn_ : ae_).push_back(p.var);
      }
    } else {
      dynamics_ = nn::make_model<T>(dynamics_config(o), rng);
      named_ = dynamics_->named_parameters();
      for (const nn::NamedParameter<T>& p : named_) ae_.push_back(p.var);
    }
    if (dynamics_) {
      const int parts = nn::row_split_parts(o.batch > 0 ? o.batch : rows, ad::num_threads());
      if (parts > 1) split_ = std::make_unique<nn::RowSplit<T>>(*dynamics_, parts);
    }
    params_ = ae_;
    params_.insert(params_.end(), dyn_.begin(), dyn_.end());
    // The pixel task's groups (PixelConfig): L2 on the autoencoder only.
    adam_main_ = std::make_unique<nn::Adam<T>>(
        ae_, nn::AdamOptions{.lr = o.lr,
                             .weight_decay = o.weight_decay,
                             .decoupled_weight_decay = o.optimizer == "adamw"});
    if (!dyn_.empty()) {
      adam_dyn_ = std::make_unique<nn::Adam<T>>(
          dyn_, nn::AdamOptions{.lr = o.lr, .weight_decay = o.dynamics_weight_decay});
    }
  }

  /// The training loss of a batch (split_parts' layout), on the tape.
  ad::Var<T> loss(const std::vector<ad::Matrix<T>>& parts) const {
    return loss(parts, dynamics_.get(), {0, parts[0].rows()});
  }

  /// The training loss of rows `block` of a batch computed by `model` (the dynamics model or a
  /// replica of it), as the trainer's objectives give it (tasks/train/objective.h, rows_loss).
  ad::Var<T> loss(const std::vector<ad::Matrix<T>>& parts, const nn::DynamicsModel<T>* model,
                  ad::RowBlock block) const {
    const auto rows = [&](std::size_t k) {
      return ad::Var<T>::constant(parts[k].middleRows(block.begin, block.size()));
    };
    if (rollout_) return rollout_loss(rows, parts.size(), *model);
    if (pixel_) return ad::mean(pixel::pixel_loss(*pixel_, rows(0), rows(1), kHnnWeight).total);
    return nn::mse(model->time_derivative(rows(0)), rows(1));
  }

  /// Nodes one step records on the tape (forward and backward: the step's op count), unsplit.
  std::size_t tape_nodes(const std::vector<ad::Matrix<T>>& parts) {
    ad::TapeScope scope;
    const std::size_t mark = ad::Tape<T>::current().size();
    ad::grad_into(loss(parts), params_, grads_);
    return ad::Tape<T>::current().size() - mark;
  }

  /// One training step: the trainer's loop body (tasks/train/loop.cpp, train_step), the batch's
  /// rows split among the threads as the trainer splits them.
  void step(const std::vector<ad::Matrix<T>>& parts) {
    ad::TapeScope scope;  // everything this step records is recycled at the closing brace
    if (split_) {
      const auto rows_loss = [&](const nn::DynamicsModel<T>& model, ad::RowBlock block) {
        return loss(parts, &model, block);
      };
      split_->loss_and_gradients(parts[0].rows(), rows_loss, grads_);
    } else {
      ad::grad_into(loss(parts), params_, grads_);
    }
    const auto split = std::ptrdiff_t(ae_.size());
    if (adam_dyn_) {
      adam_main_->step({grads_.begin(), grads_.begin() + split});
      adam_dyn_->step({grads_.begin() + split, grads_.end()});
    } else {
      adam_main_->step(grads_);
    }
  }

  /// The mean loss over a whole split, without a graph (chunks of 1000 rows).
  double mean_loss(const Parts& split) const {
    if (dynamics_ && !rollout_) return hnn::tasks::field_mse(*dynamics_, split[0], split[1]);
    double total = 0;
    std::vector<ad::Matrix<T>> chunk(split.size());
    for (Eigen::Index s = 0; s < split[0].rows(); s += 1000) {
      const Eigen::Index n = std::min<Eigen::Index>(1000, split[0].rows() - s);
      ad::TapeScope scope;
      ad::NoGradGuard values_only;
      for (std::size_t i = 0; i < split.size(); ++i)
        chunk[i] = split[i].middleRows(s, n).template cast<T>();
      total += double(loss(chunk).item()) * double(n);
    }
    return total / double(split[0].rows());
  }

  const std::vector<nn::NamedParameter<T>>& named_parameters() const { return named_; }
  /// The known constraints and masses of a constrained model (torch_peers.Chnn reads them), or
  /// nullptr.
  const nn::ConstraintSpec* constraints() const {
    return dynamics_ && !dynamics_->config().constraints.empty() ? &dynamics_->config().constraints
                                                                 : nullptr;
  }

 private:
  // RolloutObjective's loss: from the start states, one integrator step per window step, the
  // MSE (or mean absolute error) of every reached state, averaged over the steps.
  template <typename Rows>
  ad::Var<T> rollout_loss(const Rows& rows, std::size_t parts,
                          const nn::DynamicsModel<T>& model) const {
    const std::size_t horizon = (parts - 1) / 2;
    ad::Var<T> z = model.integrated_state(rows(0)), total;
    for (std::size_t j = 0; j < horizon; ++j) {
      const ad::Var<T> h = rows(1 + horizon + j);
      z = hnn::tasks::integrator_step(model, z, h, integrator_);
      const ad::Var<T> x = model.observed_state(z), target = rows(1 + j);
      const ad::Var<T> step_loss =
          l1_ ? hnn::tasks::mean_absolute_error(x, target) : nn::mse(x, target);
      total = total.defined() ? total + step_loss : step_loss;
    }
    return total * T(1.0 / double(horizon));
  }

  bool rollout_, l1_;
  hnn::tasks::RolloutIntegrator integrator_;
  std::unique_ptr<nn::DynamicsModel<T>> dynamics_;
  std::unique_ptr<pixel::PixelModel<T>> pixel_;
  std::vector<nn::NamedParameter<T>> named_;
  std::vector<ad::Var<T>> ae_, dyn_, params_, grads_;
  std::unique_ptr<nn::Adam<T>> adam_main_, adam_dyn_;
  std::unique_ptr<nn::RowSplit<T>> split_;  // null: each op splits its own work
};

// Parameters in torch's layout (a Linear's weight out x in), float64, in hnn's order; and a JSON
// manifest of names and shapes next to them.
template <typename T>
void save_init(const Model<T>& model, const std::string& path) {
  std::ofstream out(path, std::ios::binary);
  json manifest = json::array();
  for (const nn::NamedParameter<T>& p : model.named_parameters()) {
    const ad::Matrix<T>& v = p.var.value();
    const bool weight = p.name.size() >= 6 && p.name.compare(p.name.size() - 6, 6, "weight") == 0;
    // A weight is in x out here (y = x W); torch stores W^T. A bias is 1 x out in both.
    const Batch torch_layout =
        weight ? Batch(v.transpose().template cast<double>()) : Batch(v.template cast<double>());
    cmp::write_rows(out, to_rows(torch_layout));
    manifest.push_back(
        {{"name", p.name}, {"shape", weight ? json{v.cols(), v.rows()} : json{v.cols()}}});
  }
  if (!out) throw std::runtime_error("cannot write " + path);
  std::ofstream(path + ".json") << manifest.dump(1) << "\n";
  if (const nn::ConstraintSpec* spec = model.constraints()) {
    json links = json::array(), anchors = json::array();
    for (const nn::Link& l : spec->links) links.push_back({l.i, l.j});
    for (const nn::Anchor& a : spec->anchors) anchors.push_back({a.i, a.point});
    json mass = json::array();
    for (Eigen::Index r = 0; r < spec->mass.rows(); ++r)
      mass.push_back(std::vector<double>(spec->mass.row(r).begin(), spec->mass.row(r).end()));
    std::ofstream(path + ".constraints.json") << json{{"points", spec->points},
                                                      {"dim", spec->dim},
                                                      {"mass", mass},
                                                      {"links", links},
                                                      {"anchors", anchors}}
                                                     .dump(1)
                                              << "\n";
  }
}

// ---- the timed run ------------------------------------------------------------------------

// Rows `indices` of every part, into `batch` (sized once).
template <typename T>
void gather(const std::vector<ad::Matrix<T>>& parts, cmp::BatchIndices& indices, Eigen::Index rows,
            std::vector<ad::Matrix<T>>& batch) {
  batch.resize(parts.size());
  for (std::size_t k = 0; k < parts.size(); ++k) batch[k].resize(rows, parts[k].cols());
  for (Eigen::Index i = 0; i < rows; ++i) {
    const Eigen::Index row = indices.next();
    for (std::size_t k = 0; k < parts.size(); ++k) batch[k].row(i) = parts[k].row(row);
  }
}

template <typename T>
json run(const cmp::Options& o, const cmp::Data& data) {
  const Parts train = split_parts(o, data.train_x, data.train_dx);
  std::vector<ad::Matrix<T>> parts, batch;
  for (const Batch& p : train) parts.push_back(p.cast<T>());
  Model<T> model(o, parts[0].rows());
  if (!o.save_init.empty()) save_init(model, o.save_init);
  cmp::BatchIndices indices(o.seed, parts[0].rows());
  cmp::StepTimer timer(o.steps, o.warmup, o.window);
  std::uint64_t gemm_flops = 0;  // of the first batch, unsplit (before the timing)
  std::size_t nodes = 0;
  for (int step = 0; step < o.steps; ++step) {
    if (o.batch != 0) gather(parts, indices, o.batch, batch);
    const std::vector<ad::Matrix<T>>& rows = o.batch == 0 ? parts : batch;
    if (step == 0) {
      const ad::GemmFlopCounter counter;
      nodes = model.tape_nodes(rows);
      gemm_flops = counter.flops();
    }
    model.step(rows);
    timer.tick(step + 1);
  }
  json result = timer.to_json();
  result["gemm_flops_per_step"] = gemm_flops;
  result["tape_nodes_per_step"] = nodes;
  result["stolen_parts"] = ad::stolen_parts();  // row-split parts the caller ran for a late worker
  result["train_loss"] = model.mean_loss(train);
  result["test_loss"] = model.mean_loss(split_parts(o, data.test_x, data.test_dx));
  result["train_rows"] = parts[0].rows();  // windows, for the rollout loss
  return result;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    const cmp::Options o = cmp::parse_options(argc, argv, "hnn_train_step");
    if (!o.init.empty()) {  // the torches read hnn's parameters; hnn starts from its own seed's
      throw std::invalid_argument("--init is for the torch programs: hnn starts from seed " +
                                  std::to_string(o.seed) +
                                  "'s parameters (--save-init writes them)");
    }
    if (!o.fma_peak.empty()) {
      if (o.fma_peak != "float32" && o.fma_peak != "float64")
        throw std::invalid_argument("--fma-peak takes float32 or float64, got " + o.fma_peak);
      const bool single = o.fma_peak == "float32";
      const double peak =
          single ? hnn::bench::fma_peak<float>(o.threads) : hnn::bench::fma_peak<double>(o.threads);
      std::printf("%s\n", json{{"fma_peak_gflops", peak / 1e9},
                               {"threads", o.threads},
                               {"dtype", single ? "float32" : "float64"}}
                              .dump()
                              .c_str());
      return 0;
    }
    ad::set_num_threads(o.threads);
    Eigen::setNbThreads(o.threads);
    const cmp::Data data = o.data.empty() ? build_data(o) : cmp::load_data(o);
    if (!o.save_data.empty()) cmp::save_data(data, o.save_data);
    json result = o.dtype == "float32" ? run<float>(o, data) : run<double>(o, data);
    cmp::add_run_fields(result, o, "hnn", data);
    result["ad_threads"] = ad::num_threads();
    result["init"] = "hnn, seed " + std::to_string(o.seed);
    std::printf("%s\n", result.dump().c_str());
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "hnn_train_step: %s\n", e.what());
    return 1;
  }
}
