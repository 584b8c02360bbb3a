#include "tasks/pixel/objective.h"

#include <numeric>

#include "autodiff/ops.h"
#include "autodiff/tape.h"

namespace hnn::tasks::pixel {

namespace {

constexpr Eigen::Index kChunk = 1000;  // rows per evaluation chunk (1568 columns each)

std::vector<Eigen::Index> range(Eigen::Index start, Eigen::Index count) {
  std::vector<Eigen::Index> rows(static_cast<std::size_t>(count));
  std::iota(rows.begin(), rows.end(), start);
  return rows;
}

// Mean combined loss over rows [start, start + count) of the pairs, without a graph.
template <typename T>
double mean_loss(const PixelModel<T>& model, const PixelData& data, Eigen::Index start,
                 Eigen::Index count, double hnn_weight) {
  double total = 0;
  for (Eigen::Index s = start; s < start + count; s += kChunk) {
    const std::vector<Eigen::Index> rows = range(s, std::min(kChunk, start + count - s));
    ad::TapeScope scope;
    ad::NoGradGuard values_only;
    const PixelLoss<T> l =
        pixel_loss(model, ad::Var<T>::constant(data.pairs_of<T>(rows, false)),
                   ad::Var<T>::constant(data.pairs_of<T>(rows, true)), hnn_weight);
    total += double(l.total.value().template cast<double>().sum());
  }
  return total / double(count);
}

Eigen::Index batch_rows(const PixelConfig& config, const PixelData& data) {
  const Eigen::Index n = data.train_rows();
  return config.batch_size == 0 ? n : std::min<Eigen::Index>(config.batch_size, n);
}

}  // namespace

template <typename T>
PixelObjective<T>::PixelObjective(PixelModel<T>& model, const PixelData& data,
                                  const PixelConfig& config, std::uint64_t seed)
    : model_(model),
      data_(data),
      config_(config),
      sampler_(data.train_rows(), batch_rows(config, data), RowSampler::Draw::kWithoutReplacement,
               seed),
      rows_(std::size_t(batch_rows(config, data))) {}

// PyTorch's param_groups: the latent model gets its own weight decay (see
// PixelConfig::dynamics_weight_decay).
template <typename T>
std::vector<nn::AdamGroup<T>> PixelObjective<T>::parameter_groups() const {
  nn::AdamGroup<T> autoencoder{{},
                               {.lr = config_.learning_rate, .weight_decay = config_.weight_decay}};
  nn::AdamGroup<T> dynamics{
      {}, {.lr = config_.learning_rate, .weight_decay = config_.dynamics_weight_decay}};
  for (const nn::NamedParameter<T>& p : model_.named_parameters())
    (p.name.starts_with("dynamics.") ? dynamics : autoencoder).parameters.push_back(p.var);
  return {autoencoder, dynamics};
}

template <typename T>
ad::Var<T> PixelObjective<T>::batch_loss() {
  const std::vector<Eigen::Index>& drawn = sampler_.rows();
  for (std::size_t i = 0; i < drawn.size(); ++i) rows_[i] = data_.test_rows + drawn[i];
  return ad::mean(pixel_loss(model_, ad::Var<T>::constant(data_.pairs_of<T>(rows_, false)),
                             ad::Var<T>::constant(data_.pairs_of<T>(rows_, true)),
                             config_.hnn_weight)
                      .total);
}

template <typename T>
CurvePoint PixelObjective<T>::curve_point(long step, double) const {
  const Eigen::Index train = std::min<Eigen::Index>(config_.curve_rows, data_.train_rows());
  const Eigen::Index test = std::min<Eigen::Index>(config_.curve_rows, data_.test_rows);
  return {step, mean_loss(model_, data_, data_.test_rows, train, config_.hnn_weight),
          mean_loss(model_, data_, 0, test, config_.hnn_weight)};
}

// FNV-1a of the frames (the pairs and their split follow from them and the config).
template <typename T>
std::uint64_t PixelObjective<T>::data_fingerprint() const {
  std::uint64_t hash = 0xcbf29ce484222325ull ^ std::uint64_t(data_.test_rows);
  const auto* bytes = reinterpret_cast<const unsigned char*>(data_.frames.data());
  for (std::size_t i = 0; i < std::size_t(data_.frames.size()) * sizeof(float); ++i)
    hash = (hash ^ bytes[i]) * 0x100000001b3ull;
  return hash;
}

template class PixelObjective<float>;
template class PixelObjective<double>;

}  // namespace hnn::tasks::pixel
