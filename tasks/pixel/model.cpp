// The pixel pendulum's model (autoencoder + latent dynamics) and its loss.

#include "tasks/pixel/model.h"

#include <cmath>
#include <numeric>

#include "autodiff/grad.h"
#include "autodiff/ops.h"
#include "autodiff/tape.h"
#include "nn/hnn.h"
#include "tasks/error.h"

namespace hnn::tasks::pixel {

namespace {

constexpr Eigen::Index kChunk = 1000;  // rows per evaluation chunk (1568 columns each)

template <typename T>
using Column = Eigen::Matrix<T, Eigen::Dynamic, 1>;

std::vector<Eigen::Index> range(Eigen::Index start, Eigen::Index count) {
  std::vector<Eigen::Index> rows(static_cast<std::size_t>(count));
  std::iota(rows.begin(), rows.end(), start);
  return rows;
}

}  // namespace

namespace {

nn::DynamicsConfig latent_config(const PixelConfig& config, nn::ModelKind kind) {
  nn::DynamicsConfig c;
  c.model = kind;
  c.dim = 2;
  c.hidden.assign(config.hidden.begin(), config.hidden.end());
  nn::validate(c);
  return c;
}

nn::AutoencoderConfig autoencoder_config(const PixelConfig& config) {
  nn::AutoencoderConfig c;
  c.input_dim = kPairPixels;
  c.hidden_dim = config.ae_hidden;
  c.latent_dim = 2;
  return c;
}

}  // namespace

template <typename T>
PixelModel<T>::PixelModel(const PixelConfig& config, nn::ModelKind kind, std::mt19937_64& rng)
    : autoencoder_(autoencoder_config(config), rng),
      dynamics_(nn::make_model<T>(latent_config(config, kind), rng)) {}

template <typename T>
PixelModel<T>::PixelModel(nn::Autoencoder<T> autoencoder,
                          std::unique_ptr<nn::DynamicsModel<T>> dynamics)
    : autoencoder_(std::move(autoencoder)), dynamics_(std::move(dynamics)) {}

namespace {

// `half` (the encoder or the decoder) on plain values, in row chunks, without a graph.
template <typename T, typename Half>
ad::Matrix<T> in_chunks(const ad::Matrix<T>& in, Eigen::Index out_cols, Half&& half) {
  ad::Matrix<T> out(in.rows(), out_cols);
  for (Eigen::Index start = 0; start < in.rows(); start += kChunk) {
    const Eigen::Index n = std::min(kChunk, in.rows() - start);
    ad::TapeScope scope;
    ad::NoGradGuard values_only;
    out.middleRows(start, n) = half(ad::Var<T>::constant(in.middleRows(start, n))).value();
  }
  return out;
}

}  // namespace

template <typename T>
ad::Matrix<T> PixelModel<T>::encode(const ad::Matrix<T>& x) const {
  return in_chunks<T>(x, 2, [this](const ad::Var<T>& v) { return encode(v); });
}

template <typename T>
ad::Matrix<T> PixelModel<T>::decode(const ad::Matrix<T>& z) const {
  return in_chunks<T>(z, kPairPixels, [this](const ad::Var<T>& v) { return decode(v); });
}

template <typename T>
ad::Matrix<T> PixelModel<T>::energy(const ad::Matrix<T>& z) const {
  const auto* hnn = dynamic_cast<const nn::Hnn<T>*>(dynamics_.get());
  if (hnn == nullptr) throw std::logic_error("pixel-pendulum: a baseline model learns no H");
  return hnn->energy(z);
}

template <typename T>
void PixelModel<T>::visit_parameters(const nn::ParameterVisitor<T>& visit) {
  nn::visit_child(autoencoder_, "autoencoder", visit);
  nn::visit_child(*dynamics_, "dynamics", visit);
}

template class PixelModel<float>;
template class PixelModel<double>;

template <typename T>
PixelLoss<T> pixel_loss(const PixelModel<T>& model, const ad::Var<T>& x, const ad::Var<T>& x_next,
                        double hnn_weight) {
  const ad::Var<T> z = model.encode(x);
  const ad::Var<T> z_next = model.encode(x_next);
  PixelLoss<T> l;
  l.ae = nn::per_sample_squared_error(model.decode(z), x);
  // For an HNN, f(z) differentiates H with respect to z itself (z requires gradients through
  // the encoder), so the loss reaches the encoder along the second-order path too.
  l.hnn = nn::per_sample_squared_error(z_next, z + model.dynamics().time_derivative(z));
  const ad::Var<T> zq = ad::slice_cols(z, 0, 1), zp = ad::slice_cols(z, 1, 1);
  l.cc = ad::square(zp - (ad::slice_cols(z_next, 0, 1) - zq));
  l.total = l.ae + l.cc + l.hnn * T(hnn_weight);
  return l;
}

template PixelLoss<float> pixel_loss(const PixelModel<float>&, const ad::Var<float>&,
                                     const ad::Var<float>&, double);
template PixelLoss<double> pixel_loss(const PixelModel<double>&, const ad::Var<double>&,
                                      const ad::Var<double>&, double);

PixelLossStats pixel_loss_stats(const PixelModel<double>& model, const PixelData& data, bool test,
                                double hnn_weight) {
  const Eigen::Index start = test ? 0 : data.test_rows;
  const Eigen::Index count = test ? data.test_rows : data.train_rows();
  Column<double> total(count), ae(count), cc(count), hnn(count);
  for (Eigen::Index s = 0; s < count; s += kChunk) {
    const Eigen::Index n = std::min(kChunk, count - s);
    const std::vector<Eigen::Index> rows = range(start + s, n);
    ad::TapeScope scope;
    ad::NoGradGuard values_only;
    const PixelLoss<double> l =
        pixel_loss(model, ad::Var<double>::constant(data.pairs_of<double>(rows, false)),
                   ad::Var<double>::constant(data.pairs_of<double>(rows, true)), hnn_weight);
    total.segment(s, n) = l.total.value().col(0);
    ae.segment(s, n) = l.ae.value().col(0);
    cc.segment(s, n) = l.cc.value().col(0);
    hnn.segment(s, n) = l.hnn.value().col(0);
  }
  return {nn::mean_and_stderr<double>(total), nn::mean_and_stderr<double>(ae),
          nn::mean_and_stderr<double>(cc), nn::mean_and_stderr<double>(hnn)};
}

}  // namespace hnn::tasks::pixel
