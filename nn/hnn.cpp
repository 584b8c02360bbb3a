#include "nn/hnn.h"

#include <fmt/format.h>

#include <stdexcept>

#include "autodiff/ops.h"
#include "autodiff/tape.h"
#include "nn/constrained/constrained_model.h"
#include "nn/lnn.h"
#include "nn/mass_hnn.h"

namespace hnn::nn {

namespace {

// An Hnn is built from a kHnn or kDhnn config, a Baseline from a kBaseline one.
const DynamicsConfig& require(const DynamicsConfig& config, ModelKind kind) {
  const bool fits = kind == ModelKind::kBaseline ? config.model == ModelKind::kBaseline
                                                 : learns_scalars(config.model);
  if (!fits) {
    throw std::invalid_argument(fmt::format("a {} model cannot be built from a '{}' config",
                                            to_string(kind), to_string(config.model)));
  }
  validate(config);
  return config;
}

// (dH/dp, -dH/dq) from dH/dx = (dH/dq, dH/dp).
template <typename T>
ad::Var<T> symplectic_gradient(const ad::Var<T>& dh) {
  const Index n = dh.cols() / 2;
  thread_local std::vector<ad::Var<T>> halves;  // reused: no allocation per step
  halves.assign({ad::slice_cols(dh, n, n), -ad::slice_cols(dh, 0, n)});
  const ad::Var<T> field = ad::concat_cols<T>(halves);
  halves.clear();
  return field;
}

}  // namespace

// ---- Hnn ----------------------------------------------------------------------------------

template <typename T>
Hnn<T>::Hnn(DynamicsConfig config, std::mt19937_64& rng)
    : DynamicsModel<T>(require(config, ModelKind::kHnn),
                       Mlp<T>(mlp_config(require(config, ModelKind::kHnn)), rng)) {}

template <typename T>
Hnn<T>::Hnn(DynamicsConfig config, Mlp<T> mlp)
    : DynamicsModel<T>(require(config, ModelKind::kHnn), std::move(mlp)) {}

template <typename T>
ad::Var<T> Hnn<T>::energy(const ad::Var<T>& x) const {
  this->check_input("energy", x.rows(), x.cols());
  if (this->config_.field == FieldType::kConservative) {
    throw std::logic_error("hnn-conservative: the model learns no Hamiltonian, only D");
  }
  const ad::Var<T> out = this->mlp_.forward(this->mlp_input(x));
  return out.cols() == 1 ? out : ad::slice_cols(out, 0, 1);
}

template <typename T>
Matrix<T> Hnn<T>::energy(const MatrixView<T>& x) const {
  ad::TapeScope scope;
  ad::NoGradGuard values_only;
  return energy(ad::Var<T>::constant(x)).value();
}

template <typename T>
ad::Var<T> Hnn<T>::dissipation(const ad::Var<T>& x) const {
  this->check_input("dissipation", x.rows(), x.cols());
  if (this->config_.field == FieldType::kSolenoidal) {
    throw std::logic_error("hnn: a solenoidal HNN learns no dissipation potential D");
  }
  const ad::Var<T> out = this->mlp_.forward(this->mlp_input(x));
  return out.cols() == 1 ? out : ad::slice_cols(out, 1, 1);
}

// One formula for every field type: H is the MLP's column 0 and D its last column (1 for kBoth,
// 0 for kConservative). In training, Mlp::input_gradient also gives the exact parameter
// gradients of each part (through one fused op for a tanh MLP). kBoth takes both gradients from
// one Mlp::input_gradients, which shares the work of the two (a D-HNN's training step).
template <typename T>
typename Hnn<T>::Parts Hnn<T>::time_derivative_parts(const ad::Var<T>& x) const {
  this->check_input("time_derivative", x.rows(), x.cols());
  const FieldType field = this->config_.field;
  Parts parts;
  if (field == FieldType::kBoth) {
    const Index dim = x.cols();
    const ad::Var<T> both = this->input_gradients(x);  // [dH/dx | dD/dx]
    parts.solenoidal = symplectic_gradient(ad::slice_cols(both, 0, dim));
    parts.conservative = ad::slice_cols(both, dim, dim);
    return parts;
  }
  if (field != FieldType::kConservative) {
    parts.solenoidal = symplectic_gradient(this->input_gradient(x, 0));
  }
  if (field != FieldType::kSolenoidal) {
    parts.conservative = this->input_gradient(x, this->mlp_.output_dim() - 1);
  }
  return parts;
}

template <typename T>
ad::Var<T> Hnn<T>::time_derivative(const ad::Var<T>& x) const {
  const Parts parts = time_derivative_parts(x);
  if (!parts.conservative.defined()) return parts.solenoidal;
  if (!parts.solenoidal.defined()) return parts.conservative;
  return parts.solenoidal + parts.conservative;
}

template <typename T>
Matrix<T> Hnn<T>::field(const MatrixView<T>& x) const {
  this->check_input("field", x.rows(), x.cols());
  ad::TapeScope scope;
  ad::NoGradGuard values_only;
  return time_derivative(ad::Var<T>::leaf(x)).value();
}

// ---- Baseline -----------------------------------------------------------------------------

template <typename T>
Baseline<T>::Baseline(DynamicsConfig config, std::mt19937_64& rng)
    : DynamicsModel<T>(require(config, ModelKind::kBaseline),
                       Mlp<T>(mlp_config(require(config, ModelKind::kBaseline)), rng)) {}

template <typename T>
Baseline<T>::Baseline(DynamicsConfig config, Mlp<T> mlp)
    : DynamicsModel<T>(require(config, ModelKind::kBaseline), std::move(mlp)) {}

template <typename T>
ad::Var<T> Baseline<T>::time_derivative(const ad::Var<T>& x) const {
  this->check_input("time_derivative", x.rows(), x.cols());
  const ad::Var<T> out = this->mlp_.forward(this->mlp_input(x));
  if (!this->config_.given_velocities) return out;
  const Index n = this->dim() / 2;  // dq/dt = v, the state's second half; the MLP gives dv/dt
  return ad::concat_cols<T>({ad::slice_cols(x, n, n), out});
}

// ---- factory ------------------------------------------------------------------------------

template <typename T>
std::unique_ptr<DynamicsModel<T>> make_model(const DynamicsConfig& config, std::mt19937_64& rng) {
  if (config.model == ModelKind::kLnn) return std::make_unique<Lnn<T>>(config, rng);
  if (config.model == ModelKind::kMassHnn) return std::make_unique<MassHnn<T>>(config, rng);
  if (is_constrained(config.model)) return std::make_unique<ConstrainedModel<T>>(config, rng);
  if (learns_scalars(config.model)) return std::make_unique<Hnn<T>>(config, rng);
  return std::make_unique<Baseline<T>>(config, rng);
}

template <typename U, typename T>
std::unique_ptr<DynamicsModel<U>> cast_model(const DynamicsModel<T>& model) {
  if (const auto* mass = dynamic_cast<const MassHnn<T>*>(&model)) {
    return std::make_unique<MassHnn<U>>(mass->template cast<U>());
  }
  if (const auto* constrained = dynamic_cast<const ConstrainedModel<T>*>(&model)) {
    return std::make_unique<ConstrainedModel<U>>(constrained->template cast<U>());
  }
  Mlp<U> mlp = model.mlp().template cast<U>();
  if (model.config().model == ModelKind::kLnn) {
    return std::make_unique<Lnn<U>>(model.config(), std::move(mlp));
  }
  if (learns_scalars(model.config().model)) {
    return std::make_unique<Hnn<U>>(model.config(), std::move(mlp));
  }
  return std::make_unique<Baseline<U>>(model.config(), std::move(mlp));
}

template class Hnn<float>;
template class Hnn<double>;
template class Baseline<float>;
template class Baseline<double>;
template std::unique_ptr<DynamicsModel<float>> make_model(const DynamicsConfig&, std::mt19937_64&);
template std::unique_ptr<DynamicsModel<double>> make_model(const DynamicsConfig&, std::mt19937_64&);
template std::unique_ptr<DynamicsModel<float>> cast_model(const DynamicsModel<float>&);
template std::unique_ptr<DynamicsModel<double>> cast_model(const DynamicsModel<float>&);
template std::unique_ptr<DynamicsModel<float>> cast_model(const DynamicsModel<double>&);
template std::unique_ptr<DynamicsModel<double>> cast_model(const DynamicsModel<double>&);

}  // namespace hnn::nn
