#include "nn/mass_hnn.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <stdexcept>
#include <vector>

#include "autodiff/ops.h"
#include "autodiff/tape.h"

namespace hnn::nn {

namespace {

const DynamicsConfig& require_mass_hnn(const DynamicsConfig& config) {
  if (config.model != ModelKind::kMassHnn) {
    throw std::invalid_argument(fmt::format("an hnn-mass model cannot be built from a '{}' config",
                                            to_string(config.model)));
  }
  validate(config);
  return config;
}

template <typename T>
Mlp<T> zero_last_bias(Mlp<T> mlp) {
  ad::Var<T> bias = mlp.layers().back().bias();  // a handle of the layer's own leaf
  bias.mutable_value().setZero();
  return mlp;
}

// 1 x n^2 rows: 1 on L's strict lower triangle, or on its diagonal.
template <typename T>
Matrix<T> triangle_mask(Index n, bool diagonal) {
  Matrix<T> mask = Matrix<T>::Zero(1, n * n);
  for (Index i = 0; i < n; ++i)
    for (Index j = 0; j <= i; ++j) mask(0, i * n + j) = T((i == j) == diagonal ? 1 : 0);
  return mask;
}

// n^4 x n^2: (L L^T)_ij = sum_k L_ik L_jk picks entry (i n + k) n^2 + (j n + k) of L's outer
// product with itself.
template <typename T>
Matrix<T> gram_contraction(Index n) {
  Matrix<T> gram = Matrix<T>::Zero(n * n * n * n, n * n);
  for (Index i = 0; i < n; ++i)
    for (Index j = 0; j < n; ++j)
      for (Index k = 0; k < n; ++k) gram((i * n + k) * n * n + j * n + k, i * n + j) = T(1);
  return gram;
}

// The factor's MLP layer by layer, its hidden activations kept for the two passes below.
template <typename T>
ad::Var<T> layers_forward(const Mlp<T>& mlp, const ad::Var<T>& input,
                          std::vector<ad::Var<T>>& hidden) {
  const std::vector<Linear<T>>& layers = mlp.layers();
  hidden.clear();
  ad::Var<T> h = input;
  for (std::size_t i = 0; i + 1 < layers.size(); ++i) {
    h = ad::tanh(ad::linear(h, layers[i].weight(), layers[i].bias()));
    hidden.push_back(h);
  }
  return ad::linear(h, layers.back().weight(), layers.back().bias());
}

// Forward mode: the output's change for an input change t, layer by layer (1 - h^2) (t W).
template <typename T>
ad::Var<T> layers_tangent(const Mlp<T>& mlp, const std::vector<ad::Var<T>>& hidden, ad::Var<T> t) {
  const std::vector<Linear<T>>& layers = mlp.layers();
  for (std::size_t i = 0; i < hidden.size(); ++i)
    t = ad::tanh_backward(ad::matmul(t, layers[i].weight()), hidden[i]);
  return ad::matmul(t, layers.back().weight());
}

// Reverse mode: the input's gradient for an output gradient g.
template <typename T>
ad::Var<T> layers_cotangent(const Mlp<T>& mlp, const std::vector<ad::Var<T>>& hidden,
                            ad::Var<T> g) {
  const std::vector<Linear<T>>& layers = mlp.layers();
  g = ad::matmul(g, layers.back().weight(), false, true);
  for (std::size_t i = hidden.size(); i-- > 0;)
    g = ad::matmul(ad::tanh_backward(g, hidden[i]), layers[i].weight(), false, true);
  return g;
}

// (q, f(q, w)) of rows (q, w): the positions kept, the second half mapped (v to p and back).
template <typename T, typename F>
ad::Var<T> map_second_half(const ad::Var<T>& x, const F& f) {
  const Index n = x.cols() / 2;
  const ad::Var<T> q = ad::slice_cols(x, 0, n);
  return ad::concat_cols<T>({q, f(q, ad::slice_cols(x, n, n))});
}

}  // namespace

MlpConfig factor_mlp_config(const DynamicsConfig& config) {
  MlpConfig factor = mlp_config(config);
  factor.widths.back() = (config.dim / 2) * (config.dim / 2);
  factor.last_bias = true;
  return factor;
}

template <typename T>
MassHnn<T>::MassHnn(DynamicsConfig config, std::mt19937_64& rng)
    : DynamicsModel<T>(require_mass_hnn(config), Mlp<T>(mlp_config(config), rng)),
      factor_(zero_last_bias(Mlp<T>(factor_mlp_config(config), rng))) {
  form_constants();
}

template <typename T>
MassHnn<T>::MassHnn(DynamicsConfig config, Mlp<T> potential, Mlp<T> mass)
    : DynamicsModel<T>(require_mass_hnn(config), std::move(potential)), factor_(std::move(mass)) {
  const MlpConfig want = factor_mlp_config(config);
  if (factor_.config().widths != want.widths || !factor_.config().last_bias) {
    throw std::invalid_argument(fmt::format("hnn-mass: the factor's MLP is '{}' but wants '{}'",
                                            nn::describe(factor_.config()), nn::describe(want)));
  }
  form_constants();
}

template <typename T>
void MassHnn<T>::form_constants() {
  const Index n = this->dim() / 2;
  strict_lower_ = triangle_mask<T>(n, false);
  diagonal_ = triangle_mask<T>(n, true);
  gram_ = gram_contraction<T>(n);
  epsilon_ = diagonal_ * T(kMassHnnEpsilon);
}

template <typename T>
struct MassHnn<T>::Factor {
  ad::Var<T> lower;  // L, R x n^2
  ad::Var<T> slope;  // dL / d(the MLP's output), elementwise
  ad::Var<T> minv;   // M^-1 = L L^T + eps I
};

template <typename T>
typename MassHnn<T>::Factor MassHnn<T>::factor(const ad::Var<T>& raw) const {
  Factor f;
  const ad::Var<T> strict = ad::Var<T>::constant(strict_lower_),
                   diagonal = ad::Var<T>::constant(diagonal_);
  f.lower = raw * strict + ad::softplus(raw) * diagonal;
  f.slope = strict + ad::sigmoid(raw) * diagonal;
  f.minv = ad::matmul(ad::batched_outer(f.lower, f.lower), ad::Var<T>::constant(gram_)) +
           ad::Var<T>::constant(epsilon_);
  return f;
}

template <typename T>
typename MassHnn<T>::Factor MassHnn<T>::factor_at(const ad::Var<T>& q) const {
  return factor(factor_.forward(this->position_input(q)));
}

template <typename T>
ad::Var<T> MassHnn<T>::momentum_rate(const ad::Var<T>& q, const ad::Var<T>& in,
                                     const std::vector<ad::Var<T>>& hidden, const Factor& k,
                                     const ad::Var<T>& p, const ad::Var<T>& u) const {
  // V's gradient and the kinetic term's, 1/2 |L^T p|^2 having p u^T in L.
  const ad::Var<T> kinetic_gradient =
      layers_cotangent(factor_, hidden, ad::batched_outer(p, u) * k.slope);
  return -this->position_gradient(q, this->mlp_.input_gradient(in, 0) + kinetic_gradient);
}

template <typename T>
ad::Var<T> MassHnn<T>::time_derivative(const ad::Var<T>& x) const {
  this->check_input("time_derivative", x.rows(), x.cols());
  const Index n = x.cols() / 2;
  const ad::Var<T> q = ad::slice_cols(x, 0, n), v = ad::slice_cols(x, n, n);
  const ad::Var<T> in = this->position_input(q);
  thread_local std::vector<ad::Var<T>> hidden;  // reused: no allocation per step
  const Factor k = factor(layers_forward(factor_, in, hidden));
  const ad::Var<T> p = ad::batched_spd_solve(k.minv, v, kMassHnnMinRcond<T>);
  const ad::Var<T> u = ad::batched_matvec(k.lower, p, true);  // L^T p
  const ad::Var<T> p_dot = momentum_rate(q, in, hidden, k, p, u);
  // v = M^-1 p: dv/dt = M^-1 dp/dt + (dL L^T + L dL^T) p, dL the factor's tangent along q' = v.
  const ad::Var<T> l_dot = layers_tangent(factor_, hidden, this->position_tangent(q, v)) * k.slope;
  const ad::Var<T> v_dot = ad::batched_matvec(k.minv, p_dot) + ad::batched_matvec(l_dot, u) +
                           ad::batched_matvec(k.lower, ad::batched_matvec(l_dot, p, true));
  hidden.clear();  // release the handles (capacity stays)
  return ad::concat_cols<T>({v, v_dot});
}

template <typename T>
ad::Var<T> MassHnn<T>::integrated_state(const ad::Var<T>& x) const {
  this->check_input("integrated_state", x.rows(), x.cols());
  return map_second_half(x, [&](const ad::Var<T>& q, const ad::Var<T>& v) {
    return ad::batched_spd_solve(factor_at(q).minv, v, kMassHnnMinRcond<T>);
  });
}

template <typename T>
ad::Var<T> MassHnn<T>::integrated_derivative(const ad::Var<T>& z) const {
  this->check_input("integrated_derivative", z.rows(), z.cols());
  const Index n = z.cols() / 2;
  const ad::Var<T> q = ad::slice_cols(z, 0, n), p = ad::slice_cols(z, n, n);
  const ad::Var<T> in = this->position_input(q);
  thread_local std::vector<ad::Var<T>> hidden;  // reused: no allocation per step
  const Factor k = factor(layers_forward(factor_, in, hidden));
  const ad::Var<T> q_dot = ad::batched_matvec(k.minv, p);
  const ad::Var<T> p_dot = momentum_rate(q, in, hidden, k, p, ad::batched_matvec(k.lower, p, true));
  hidden.clear();
  return ad::concat_cols<T>({q_dot, p_dot});
}

template <typename T>
ad::Var<T> MassHnn<T>::observed_state(const ad::Var<T>& z) const {
  this->check_input("observed_state", z.rows(), z.cols());
  return map_second_half(z, [&](const ad::Var<T>& q, const ad::Var<T>& p) {
    return ad::batched_matvec(factor_at(q).minv, p);
  });
}

template <typename T>
Matrix<T> MassHnn<T>::integrated_field(const MatrixView<T>& z) const {
  return this->values_of("integrated_field", z,
                         [&](const ad::Var<T>& v) { return integrated_derivative(v); });
}

template <typename T>
Matrix<T> MassHnn<T>::energy(const MatrixView<T>& x) const {
  this->check_input("energy", x.rows(), x.cols());
  ad::TapeScope scope;
  ad::NoGradGuard values_only;
  const Index n = x.cols() / 2;
  const ad::Var<T> state = ad::Var<T>::constant(x);
  const ad::Var<T> q = ad::slice_cols(state, 0, n), v = ad::slice_cols(state, n, n);
  const ad::Var<T> p = ad::batched_spd_solve(factor_at(q).minv, v, kMassHnnMinRcond<T>);
  return (ad::sum_cols(p * v) * T(0.5) + this->mlp_.forward(this->position_input(q))).value();
}

template <typename T>
Matrix<T> MassHnn<T>::inverse_mass(const MatrixView<T>& x) const {
  this->check_input("inverse_mass", x.rows(), x.cols());
  ad::TapeScope scope;
  ad::NoGradGuard values_only;
  const Index n = x.cols() / 2;
  const ad::Var<T> state = ad::Var<T>::constant(x);
  return factor_at(ad::slice_cols(state, 0, n)).minv.value();
}

template <typename T>
std::string MassHnn<T>::describe() const {
  const auto widths = [](const Mlp<T>& mlp) {
    return fmt::format("{}", fmt::join(mlp.config().widths, "-"));
  };
  return fmt::format("{} V {}, L {} {} {}", this->name(), widths(this->mlp_), widths(factor_),
                     to_string(this->config_.activation), to_string(this->config_.init));
}

template <typename T>
void MassHnn<T>::visit_parameters(const ParameterVisitor<T>& visit) {
  DynamicsModel<T>::visit_parameters(visit);
  visit_child<T>(factor_, "mass", visit);
}

template class MassHnn<float>;
template class MassHnn<double>;

}  // namespace hnn::nn
