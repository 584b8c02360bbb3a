#include "tasks/train/rollout_objective.h"

#include <algorithm>
#include <cmath>
#include <optional>

#include "autodiff/ops.h"
#include "autodiff/tape.h"
#include "nn/enum_names.h"
#include "nn/loss.h"
#include "tasks/data/dataset.h"
#include "tasks/error.h"

namespace hnn::tasks {

namespace {

// Curves evaluate at most this many windows of each split.
constexpr Eigen::Index kCurveWindows = 2000;

// Relative slack of "a near-multiple of dt".
constexpr double kMultipleSlack = 0.01;

}  // namespace

// relu(d) + relu(-d): its derivative is sign(d) (0 at 0).
template <typename T>
ad::Var<T> mean_absolute_error(const ad::Var<T>& a, const ad::Var<T>& b) {
  const ad::Var<T> d = ad::sub(a, b);
  return ad::mean(ad::add(ad::relu(d), ad::relu(ad::neg(d))));
}
template ad::Var<float> mean_absolute_error(const ad::Var<float>&, const ad::Var<float>&);
template ad::Var<double> mean_absolute_error(const ad::Var<double>&, const ad::Var<double>&);

template <typename T>
ad::Var<T> rollout_error(RolloutNorm norm, const ad::Var<T>& predicted,
                         const ad::Var<T>& measured) {
  return norm == RolloutNorm::kL1 ? mean_absolute_error(predicted, measured)
                                  : nn::mse(predicted, measured);
}
template ad::Var<float> rollout_error(RolloutNorm, const ad::Var<float>&, const ad::Var<float>&);
template ad::Var<double> rollout_error(RolloutNorm, const ad::Var<double>&, const ad::Var<double>&);

namespace {
constexpr nn::NameTable<RolloutNorm, 2> kRolloutNormNames{
    {{RolloutNorm::kL2, "l2"}, {RolloutNorm::kL1, "l1"}}};
}  // namespace

std::string_view to_string(RolloutNorm norm) { return nn::name_of(kRolloutNormNames, norm); }

std::vector<std::string> rollout_norm_names() { return nn::names_of(kRolloutNormNames); }

namespace {
constexpr nn::NameTable<RowSampler::Draw, 2> kMinibatchDrawNames{
    {{RowSampler::Draw::kWithReplacement, "independent"}, {RowSampler::Draw::kEpochs, "epochs"}}};
}  // namespace

std::vector<std::string> minibatch_draw_names() { return nn::names_of(kMinibatchDrawNames); }

nlohmann::json RolloutLossConfig::to_json() const {
  if (!rollout) return {{"loss", "derivative"}};
  nlohmann::json j = {{"loss", "rollout"},
                      {"integrator", std::string(to_string(integrator))},
                      {"horizon", horizon},
                      {"dt", dt > 0 ? nlohmann::json(dt) : nlohmann::json("sampling interval")}};
  if (norm != RolloutNorm::kL2) j["norm"] = std::string(to_string(norm));  // older runs: l2
  if (minibatches != RowSampler::Draw::kWithReplacement)  // older runs: independent
    j["minibatches"] = std::string(nn::name_of(kMinibatchDrawNames, minibatches));
  return j;
}

const std::vector<std::string>& rollout_setting_names() {
  static const std::vector<std::string> names = {"loss", "horizon", "integrator",
                                                 "dt",   "norm",    "minibatches"};
  return names;
}

RolloutLossConfig rollout_loss_config(const nlohmann::json& s, const std::string& task,
                                      const RolloutLossConfig& defaults) {
  RolloutLossConfig c;
  try {
    const std::string default_loss = defaults.rollout ? "rollout" : "derivative";
    const std::string loss = s.value("loss", default_loss);
    HNN_TASKS_CHECK(loss == "derivative" || loss == "rollout",
                    "{}: loss '{}' is not one of derivative, rollout", task, loss);
    if (loss == default_loss) c = defaults;
    c.rollout = loss == "rollout";
    if (s.contains("horizon")) {
      HNN_TASKS_CHECK(s["horizon"].is_number_integer(), "{}: horizon must be an integer, got {}",
                      task, s["horizon"].dump());
      c.horizon = s["horizon"].get<int>();
    }
    if (s.contains("integrator"))
      c.integrator = parse_rollout_integrator(s["integrator"].get<std::string>());
    if (s.contains("dt")) c.dt = s["dt"].get<double>();
    if (s.contains("norm")) {
      const std::string norm = s["norm"].get<std::string>();
      const std::optional<RolloutNorm> parsed = nn::find_name(kRolloutNormNames, norm);
      HNN_TASKS_CHECK(parsed.has_value(), "{}: norm '{}' is not one of {}", task, norm,
                      nn::join_names(kRolloutNormNames));
      c.norm = *parsed;
    }
    if (s.contains("minibatches")) {
      const std::string draw = s["minibatches"].get<std::string>();
      const auto parsed = nn::find_name(kMinibatchDrawNames, draw);
      HNN_TASKS_CHECK(parsed.has_value(), "{}: minibatches '{}' is not one of {}", task, draw,
                      nn::join_names(kMinibatchDrawNames));
      c.minibatches = *parsed;
    }
  } catch (const nlohmann::json::exception& e) {
    throw Error(fmt::format("{}: bad rollout-loss settings {}: {}", task, s.dump(), e.what()));
  }
  HNN_TASKS_CHECK(
      c.rollout || (!s.contains("horizon") && !s.contains("integrator") && !s.contains("dt") &&
                    !s.contains("norm") && !s.contains("minibatches")),
      "{}: --horizon, --integrator, --dt, --norm and --minibatches apply to the "
      "rollout loss only (add --loss rollout)",
      task);
  HNN_TASKS_CHECK(c.horizon >= 1, "{}: horizon must be at least 1 step, got {}", task, c.horizon);
  HNN_TASKS_CHECK(!s.contains("dt") || (c.dt > 0 && std::isfinite(c.dt)),
                  "{}: --dt must be a positive step, got {}", task, c.dt);
  return c;
}

int rollout_substeps(const RolloutWindows& w, double dt) {
  if (dt <= 0) return 1;
  double shortest = INFINITY, longest = 0;
  for (const Batch& step : w.step) {
    shortest = std::min(shortest, step.minCoeff());
    longest = std::max(longest, step.maxCoeff());
  }
  const double steps = std::round(longest / dt);
  const bool fits = steps >= 1 && std::abs(shortest / dt - steps) <= kMultipleSlack * steps &&
                    std::abs(longest / dt - steps) <= kMultipleSlack * steps;
  HNN_TASKS_CHECK(fits,
                  "--dt {} does not divide the sampling interval ({}{}) into whole steps: use the "
                  "interval divided by a whole number",
                  dt, shortest,
                  longest > shortest * (1 + 1e-9) ? fmt::format(" to {}", longest) : std::string());
  return int(steps);
}

RolloutWindows rollout_windows(const std::vector<Stretch>& stretches, int horizon) {
  HNN_TASKS_CHECK(horizon >= 1, "the rollout horizon must be at least 1 step, got {}", horizon);
  Eigen::Index count = 0, longest = 0, dim = 0;
  for (const Stretch& s : stretches) {
    count += std::max<Eigen::Index>(0, s.x.rows() - horizon);
    longest = std::max(longest, s.x.rows());
    dim = s.x.cols();
  }
  HNN_TASKS_CHECK(count > 0,
                  "a horizon of {} steps is past the end of every training stretch (the longest "
                  "has {} points, so {} steps at most)",
                  horizon, longest, std::max<Eigen::Index>(0, longest - 1));
  RolloutWindows w;
  w.start.resize(count, dim);
  w.next.assign(std::size_t(horizon), Batch(count, dim));
  w.step.assign(std::size_t(horizon), Batch(count, 1));
  Eigen::Index row = 0;
  for (const Stretch& s : stretches) {
    for (Eigen::Index i = 0; i + horizon < s.x.rows(); ++i, ++row) {
      w.start.row(row) = s.x.row(i);
      for (int j = 0; j < horizon; ++j) {
        w.next[std::size_t(j)].row(row) = s.x.row(i + j + 1);
        w.step[std::size_t(j)](row, 0) = s.t(i + j + 1) - s.t(i + j);
      }
    }
  }
  return w;
}

template <typename T>
RolloutObjective<T>::RolloutObjective(nn::DynamicsModel<T>& model, RolloutWindows train,
                                      RolloutWindows test, Eigen::Index batch_size,
                                      const nn::AdamOptions& adam, std::uint64_t seed,
                                      RolloutIntegrator integrator, int substeps, RolloutNorm norm,
                                      RowSampler::Draw minibatches)
    : model_(model),
      train_(std::move(train)),
      test_(std::move(test)),
      adam_(adam),
      sampler_(train_.count(), batch_size, minibatches, seed),
      integrator_(integrator),
      substeps_(substeps),
      norm_(norm),
      scratch_(1 + 2 * train_.next.size()) {}

template <typename T>
void RolloutObjective<T>::gather_rows(const Batch& m, const std::vector<Eigen::Index>* rows,
                                      double scale, std::size_t slot) const {
  ad::Matrix<T>& out = scratch_[slot];
  const Eigen::Index n = rows == nullptr ? m.rows() : Eigen::Index(rows->size());
  out.resize(n, m.cols());  // no allocation once the size has been seen
  if (rows == nullptr) {
    out = (m * scale).template cast<T>();
  } else {
    for (Eigen::Index i = 0; i < n; ++i)
      out.row(i) = (m.row((*rows)[std::size_t(i)]) * scale).template cast<T>();
  }
}

template <typename T>
Eigen::Index RolloutObjective<T>::gather(const RolloutWindows& w,
                                         const std::vector<Eigen::Index>* rows) const {
  horizon_ = w.next.size();
  if (scratch_.size() < 1 + 2 * horizon_) scratch_.resize(1 + 2 * horizon_);
  gather_rows(w.start, rows, 1.0, 0);
  for (std::size_t j = 0; j < horizon_; ++j) {
    gather_rows(w.step[j], rows, 1.0 / substeps_, 1 + 2 * j);
    gather_rows(w.next[j], rows, 1.0, 2 + 2 * j);
  }
  return scratch_[0].rows();
}

// `substeps_` steps of the integrator per sampling interval, each row with its own length.
template <typename T>
ad::Var<T> RolloutObjective<T>::rows_loss(const nn::DynamicsModel<T>& model,
                                          ad::RowBlock block) const {
  const auto rows = [&](std::size_t slot) {
    return ad::Var<T>::constant(scratch_[slot].middleRows(block.begin, block.size()));
  };
  ad::Var<T> z = model.integrated_state(rows(0));
  ad::Var<T> total;
  for (std::size_t j = 0; j < horizon_; ++j) {
    const ad::Var<T> h = rows(1 + 2 * j);
    for (int s = 0; s < substeps_; ++s) z = integrator_step(model, z, h, integrator_);
    const ad::Var<T> step_loss = rollout_error(norm_, model.observed_state(z), rows(2 + 2 * j));
    total = total.defined() ? total + step_loss : step_loss;
  }
  return total * T(1.0 / double(horizon_));
}

template <typename T>
ad::Var<T> RolloutObjective<T>::batch_loss() {
  return rows_loss(model_, {0, gather_batch()});
}

template <typename T>
Eigen::Index RolloutObjective<T>::gather_batch() {
  return gather(train_, sampler_.full() ? nullptr : &sampler_.rows());
}

template <typename T>
CurvePoint RolloutObjective<T>::curve_point(long step, double batch_loss) const {
  const auto at_most = [](const RolloutWindows& w) {
    std::vector<Eigen::Index> rows(std::size_t(std::min(kCurveWindows, w.count())));
    for (std::size_t i = 0; i < rows.size(); ++i)
      rows[i] = Eigen::Index(i) * w.count() / Eigen::Index(rows.size());
    return rows;
  };
  ad::TapeScope scope;
  ad::NoGradGuard values_only;
  const std::vector<Eigen::Index> train_rows = at_most(train_);
  const auto loss_of = [&](const RolloutWindows& w, const std::vector<Eigen::Index>& rows) {
    return double(rows_loss(model_, {0, gather(w, &rows)}).item());
  };
  const double train = sampler_.full() ? batch_loss : loss_of(train_, train_rows);
  double test = NAN;
  if (test_.count() > 0) test = loss_of(test_, at_most(test_));
  return {step, train, test};
}

template <typename T>
std::uint64_t RolloutObjective<T>::data_fingerprint() const {
  return fingerprint(Dataset{train_.start, train_.next.back(), {}, {}});
}

template class RolloutObjective<float>;
template class RolloutObjective<double>;

}  // namespace hnn::tasks
