#pragma once
// Shared helpers of the nn tests: the ideal mass-spring data set and a plain training loop.

#include <cmath>
#include <functional>
#include <random>
#include <vector>

#include "autodiff/autodiff.h"
#include "autodiff/gradcheck.h"
#include "nn/nn.h"

namespace hnn::nn::testing {

/// States x = (q, p) and exact derivatives of H = q^2 + p^2 (dq/dt = 2p, dp/dt = -2q), as in
/// docs/tasks.md task 1: radius U[0.1, 1], 30 points over t in [0, 3], Gaussian noise on the
/// inputs.
struct SpringData {
  Matrix<double> x, dxdt;
};

inline SpringData spring_data(int trajectories, std::uint64_t seed, double noise = 0.1,
                              int points = 30) {
  std::mt19937_64 rng(seed);
  SpringData data{Matrix<double>(trajectories * points, 2),
                  Matrix<double>(trajectories * points, 2)};
  for (int k = 0; k < trajectories; ++k) {
    double dq = 2 * uniform01(rng) - 1, dp = 2 * uniform01(rng) - 1;
    const double radius = 0.1 + 0.9 * uniform01(rng), norm = std::hypot(dq, dp);
    const double q0 = radius * dq / norm, p0 = radius * dp / norm;
    const Matrix<double> eps = random_normal<double>(points, 2, rng, 0.0, noise);
    for (int i = 0; i < points; ++i) {
      const double t = 3.0 * i / (points - 1);
      const double q = q0 * std::cos(2 * t) + p0 * std::sin(2 * t);
      const double p = p0 * std::cos(2 * t) - q0 * std::sin(2 * t);
      const int row = k * points + i;
      data.x(row, 0) = q + eps(i, 0);
      data.x(row, 1) = p + eps(i, 1);
      data.dxdt(row, 0) = 2 * p;
      data.dxdt(row, 1) = -2 * q;
    }
  }
  return data;
}

/// Full-batch Adam on mse(model.time_derivative(x), dxdt); returns the loss before each step.
template <typename T>
std::vector<double> train(const DynamicsModel<T>& model, const Matrix<T>& x, const Matrix<T>& dxdt,
                          int steps, AdamOptions options) {
  Adam<T> adam(model.parameters(), options);
  const ad::Var<T> input = ad::Var<T>::leaf(x);
  const ad::Var<T> target = ad::Var<T>::leaf(dxdt, /*requires_grad=*/false);
  std::vector<double> losses;
  for (int step = 0; step < steps; ++step) {
    ad::TapeScope scope;
    const ad::Var<T> loss = mse(model.time_derivative(input), target);
    adam.step(ad::grad<T>({loss}, adam.parameters()));
    losses.push_back(double(loss.item()));
  }
  return losses;
}

/// A small double HNN or baseline for derivative checks.
inline DynamicsConfig small_config(ModelKind kind, Index dim, std::vector<Index> hidden,
                                   FieldType field = FieldType::kSolenoidal,
                                   Activation activation = Activation::kTanh) {
  DynamicsConfig config;
  config.model = kind;
  config.dim = dim;
  config.hidden = std::move(hidden);
  config.field = field;
  config.activation = activation;
  return config;
}

/// The training loss mse(field(x), target) differentiated in x and in every parameter, against
/// central differences: first (gradcheck) and second order (gradgradcheck). `field` is the
/// model's time_derivative unless given.
struct TrainingGradientChecks {
  ad::CheckResult first, second;
};
using FieldOnTape = std::function<ad::Var<double>(const ad::Var<double>&)>;
inline TrainingGradientChecks check_training_gradients(const DynamicsModel<double>& model,
                                                       const Matrix<double>& x,
                                                       const Matrix<double>& target,
                                                       FieldOnTape field = {}) {
  if (!field) field = [&](const ad::Var<double>& in) { return model.time_derivative(in); };
  auto& bound = const_cast<DynamicsModel<double>&>(model);  // rebound to the checks' leaves
  const auto loss = [&](const std::vector<ad::Var<double>>& in) {
    bound.bind_parameters(std::vector<ad::Var<double>>(in.begin() + 1, in.end()));
    return mse(field(in[0]), ad::Var<double>::constant(target));
  };
  std::vector<Matrix<double>> inputs{x};
  for (const ad::Var<double>& p : model.parameters()) inputs.push_back(p.value());
  return {ad::gradcheck(loss, inputs), ad::gradgradcheck(loss, inputs)};
}

}  // namespace hnn::nn::testing
