#include "nn/lnn.h"

#include <fmt/format.h>

#include <stdexcept>
#include <vector>

#include "autodiff/functional.h"
#include "autodiff/grad.h"
#include "autodiff/ops.h"
#include "autodiff/tape.h"

namespace hnn::nn {

namespace {

const DynamicsConfig& require_lnn(const DynamicsConfig& config) {
  if (config.model != ModelKind::kLnn) {
    throw std::invalid_argument(
        fmt::format("an lnn model cannot be built from a '{}' config", to_string(config.model)));
  }
  validate(config);
  return config;
}

// The n x n blocks [j][i] = jacobian[j][offset + i] of a row-wise Jacobian R x (n · 2n), each
// block flattened row-major: the v-v or v-q part of the Hessian of L.
template <typename T>
ad::Var<T> hessian_block(const ad::Var<T>& jacobian, Index n, Index offset) {
  thread_local std::vector<ad::Var<T>> rows;  // reused: no allocation per step
  rows.clear();
  for (Index j = 0; j < n; ++j) rows.push_back(ad::slice_cols(jacobian, j * 2 * n + offset, n));
  const ad::Var<T> block = ad::concat_cols<T>(rows);
  rows.clear();
  return block;
}

template <typename T>
Matrix<T> prior_slope(const DynamicsConfig& config) {
  const Index n = config.dim / 2;
  Matrix<T> slope = Matrix<T>::Constant(1, n, T(config.kinetic_prior));
  for (Index i = 0; i < n && !config.input_scale.empty(); ++i) {
    const double s = config.input_scale[std::size_t(n + i)];
    slope(0, i) /= T(s * s);
  }
  return slope;
}

}  // namespace

template <typename T>
Lnn<T>::Lnn(DynamicsConfig config, std::mt19937_64& rng)
    : DynamicsModel<T>(require_lnn(config), Mlp<T>(mlp_config(require_lnn(config)), rng)),
      prior_slope_(prior_slope<T>(config)) {}

template <typename T>
Lnn<T>::Lnn(DynamicsConfig config, Mlp<T> mlp)
    : DynamicsModel<T>(require_lnn(config), std::move(mlp)), prior_slope_(prior_slope<T>(config)) {}

template <typename T>
ad::Var<T> Lnn<T>::lagrangian(const ad::Var<T>& x) const {
  this->check_input("lagrangian", x.rows(), x.cols());
  const ad::Var<T> in = this->mlp_input(x);
  const ad::Var<T> l = this->mlp_.forward(in);
  if (this->config_.kinetic_prior == 0) return l;
  const Index n = x.cols() / 2;
  const T half_prior = T(0.5 * this->config_.kinetic_prior);
  return l + ad::sum_cols(ad::square(ad::slice_cols(in, n, n))) * half_prior;
}

template <typename T>
Matrix<T> Lnn<T>::energy(const MatrixView<T>& states) const {
  this->check_input("energy", states.rows(), states.cols());
  ad::TapeScope scope;
  ad::GradModeGuard record(true);
  const Index n = states.cols() / 2;
  const ad::Var<T> in = ad::Var<T>::leaf(states);
  const Matrix<T>& x = in.value();  // the leaf's copy: the sums below read a Matrix, as before
  const Matrix<T> dl = this->input_gradient(in, 0).value();
  // The prior term's share, v · (v · slope) - |v~|² prior / 2, is |v~|² prior / 2.
  const Matrix<T> v2 = x.rightCols(n).array().square().matrix();
  return (x.rightCols(n).cwiseProduct(dl.rightCols(n)).rowwise().sum() -
          this->mlp_.forward(this->mlp_input(in)).value() +
          T(0.5) * (v2 * prior_slope_.transpose()))
      .eval();
}

// The Euler-Lagrange equations, d/dt dL/dv = dL/dq, expanded: (d²L/dv²) a + (d²L/dv dq) v = dL/dq.
// dL/dx is one input gradient; the Hessian rows of its v-part are n more reverse passes over
// the batch (row_jacobian), recorded when the caller records (training differentiates them).
template <typename T>
ad::Var<T> Lnn<T>::time_derivative(const ad::Var<T>& x) const {
  this->check_input("time_derivative", x.rows(), x.cols());
  const bool record = ad::grad_enabled();
  const Index n = x.cols() / 2;
  ad::GradModeGuard inner(true);  // the Hessians need dL/dx on the tape even for values only
  // Differentiating with respect to x needs x to require gradients: a constant batch becomes a
  // variable on the tape (its copy is the only cost; recycled, unlike a leaf).
  const ad::Var<T> in = x.requires_grad() ? x : ad::Var<T>::variable(x.value());
  const ad::Var<T> dl = this->input_gradient(in, 0);
  ad::Var<T> dl_dv = ad::slice_cols(dl, n, n);
  if (this->config_.kinetic_prior != 0) {
    dl_dv = dl_dv + ad::slice_cols(in, n, n) * ad::Var<T>::constant(prior_slope_);
  }
  const ad::Var<T> jacobian = ad::row_jacobian(dl_dv, in, {.create_graph = record});
  ad::GradModeGuard outer(record);
  const ad::Var<T> v = ad::slice_cols(x, n, n);
  const ad::Var<T> dl_dq = ad::slice_cols(dl, 0, n);
  const ad::Var<T> force = dl_dq - ad::batched_matvec(hessian_block(jacobian, n, 0), v);
  const ad::Var<T> a = ad::batched_solve(hessian_block(jacobian, n, n), force);
  return ad::concat_cols<T>({v, a});
}

template class Lnn<float>;
template class Lnn<double>;

}  // namespace hnn::nn
