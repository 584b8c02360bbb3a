#pragma once
// The pixel pendulum's model: an autoencoder with an HNN (or a baseline MLP) on its 2-D latent
// space, and its loss ae + cc + w hnn.
#include <memory>
#include <random>
#include <string>

#include "nn/autoencoder.h"
#include "nn/dynamics.h"
#include "nn/hnn.h"
#include "nn/loss.h"
#include "tasks/pixel/frames.h"

namespace hnn::tasks::pixel {

/// The autoencoder and the latent dynamics model, saved and loaded together. Parameters:
/// "autoencoder.<...>" then "dynamics.<...>"; kind "pixel:<dynamics kind>".
template <typename T>
class PixelModel : public nn::Module<T> {
 public:
  /// Initialised from rng: the autoencoder first, then the latent MLP (the reference's order).
  PixelModel(const PixelConfig& config, nn::ModelKind kind, std::mt19937_64& rng);
  PixelModel(nn::Autoencoder<T> autoencoder, std::unique_ptr<nn::DynamicsModel<T>> dynamics);
  PixelModel(PixelModel&&) noexcept = default;
  PixelModel& operator=(PixelModel&&) noexcept = default;

  ad::Var<T> encode(const ad::Var<T>& x) const { return autoencoder_.encode(x); }
  ad::Var<T> decode(const ad::Var<T>& z) const { return autoencoder_.decode(z); }
  /// Plain values, in chunks, without a graph.
  ad::Matrix<T> encode(const ad::Matrix<T>& x) const;
  ad::Matrix<T> decode(const ad::Matrix<T>& z) const;
  const nn::Autoencoder<T>& autoencoder() const { return autoencoder_; }
  const nn::DynamicsModel<T>& dynamics() const { return *dynamics_; }
  bool is_hnn() const { return dynamics_->config().model == nn::ModelKind::kHnn; }
  /// The learned H at latent states (an HNN only; throws std::logic_error otherwise).
  ad::Matrix<T> energy(const ad::Matrix<T>& z) const;

  void visit_parameters(const nn::ParameterVisitor<T>& visit) override;
  std::string kind() const override { return "pixel:" + dynamics_->kind(); }

  template <typename U>
  PixelModel<U> cast() const {
    return PixelModel<U>(autoencoder_.template cast<U>(), nn::cast_model<U>(*dynamics_));
  }

 private:
  nn::Autoencoder<T> autoencoder_;
  std::unique_ptr<nn::DynamicsModel<T>> dynamics_;
};

/// The per-sample terms of the loss (each R x 1, on the graph): ae = mean over pixels of
/// (x - dec(enc(x)))^2; hnn = mean over the latent of (z' - (z + f(z)))^2 with z' = enc(x_next)
/// (one Euler step of one frame); cc = (z_p - (z'_q - z_q))^2; total = ae + cc + w hnn.
template <typename T>
struct PixelLoss {
  ad::Var<T> total, ae, cc, hnn;
};
template <typename T>
PixelLoss<T> pixel_loss(const PixelModel<T>& model, const ad::Var<T>& x, const ad::Var<T>& x_next,
                        double hnn_weight);

/// mean +- std/sqrt(N) of each loss term over a whole split (test = true: the test split).
struct PixelLossStats {
  nn::MeanStderr total, ae, cc, hnn;
};
PixelLossStats pixel_loss_stats(const PixelModel<double>& model, const PixelData& data, bool test,
                                double hnn_weight);

}  // namespace hnn::tasks::pixel
