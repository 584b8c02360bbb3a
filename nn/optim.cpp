#include "nn/optim.h"

#include <fmt/format.h>

#include <cmath>
#include <set>
#include <stdexcept>

#include "autodiff/parallel.h"

namespace hnn::nn {

template <typename T>
Optimizer<T>::Optimizer(std::vector<ad::Var<T>> parameters) : parameters_(std::move(parameters)) {
  std::set<const Matrix<T>*> seen;  // a leaf's value lives as long as the leaf: its identity
  for (std::size_t i = 0; i < parameters_.size(); ++i) {
    if (!parameters_[i].defined() || !parameters_[i].is_leaf()) {
      throw std::invalid_argument(fmt::format(
          "optimizer: parameter #{} is not a leaf; only leaves can be updated in place", i));
    }
    if (!seen.insert(&parameters_[i].value()).second) {
      throw std::invalid_argument(fmt::format(
          "optimizer: parameter #{} is listed twice; it would be updated twice a step", i));
    }
  }
}

template <typename T>
void Optimizer<T>::step(const std::vector<ad::Var<T>>& grads) {
  if (grads.size() != parameters_.size()) {
    throw std::invalid_argument(
        fmt::format("optimizer: {} gradients for {} parameters", grads.size(), parameters_.size()));
  }
  for (std::size_t i = 0; i < grads.size(); ++i) {
    const ad::Var<T>& p = parameters_[i];
    if (!grads[i].defined() || grads[i].rows() != p.rows() || grads[i].cols() != p.cols()) {
      throw std::invalid_argument(
          fmt::format("optimizer: gradient #{} is {} but its parameter is {}", i,
                      grads[i].defined() ? grads[i].shape() : std::string("undefined"), p.shape()));
    }
  }
  ++steps_;
  for (std::size_t i = 0; i < grads.size(); ++i) {
    update(i, parameters_[i].mutable_value(), grads[i].value());
  }
}

template <typename T>
void Optimizer<T>::step() {
  ++steps_;
  for (std::size_t i = 0; i < parameters_.size(); ++i) {
    update(i, parameters_[i].mutable_value(), parameters_[i].grad());
  }
}

template <typename T>
void Optimizer<T>::zero_grad() {
  for (ad::Var<T>& p : parameters_) p.zero_grad();
}

namespace {
void check_non_negative(const char* what, const char* name, double value) {
  if (!(value >= 0)) {
    throw std::invalid_argument(fmt::format("{}: {} must be >= 0, got {}", what, name, value));
  }
}

// The groups' parameters end to end.
template <typename T>
std::vector<ad::Var<T>> joined(const std::vector<AdamGroup<T>>& groups) {
  std::vector<ad::Var<T>> all;
  for (const AdamGroup<T>& group : groups) {
    all.insert(all.end(), group.parameters.begin(), group.parameters.end());
  }
  return all;
}

void check_adam(const AdamOptions& o, const std::string& what) {
  check_non_negative(what.c_str(), "lr", o.lr);
  check_non_negative(what.c_str(), "eps", o.eps);
  check_non_negative(what.c_str(), "weight_decay", o.weight_decay);
  for (double beta : {o.beta1, o.beta2}) {
    if (!(beta >= 0 && beta < 1)) {
      throw std::invalid_argument(fmt::format("{}: betas must be in [0, 1), got {}", what, beta));
    }
  }
}
}  // namespace

template <typename T>
Adam<T>::Adam(std::vector<ad::Var<T>> parameters, AdamOptions options)
    : Adam(std::vector<AdamGroup<T>>{{std::move(parameters), options}}) {}

template <typename T>
Adam<T>::Adam(const std::vector<AdamGroup<T>>& groups) : Optimizer<T>(joined(groups)) {
  if (groups.empty()) throw std::invalid_argument("Adam: no parameter groups");
  for (std::size_t k = 0; k < groups.size(); ++k) {
    check_adam(groups[k].options, groups.size() == 1 ? "Adam" : fmt::format("Adam group {}", k));
    options_.push_back(groups[k].options);
    group_.insert(group_.end(), groups[k].parameters.size(), k);
  }
  for (const ad::Var<T>& p : this->parameters_) {
    m_.push_back(Matrix<T>::Zero(p.rows(), p.cols()));
    v_.push_back(Matrix<T>::Zero(p.rows(), p.cols()));
  }
}

template <typename T>
void Adam<T>::set_lr(double lr) {
  for (AdamOptions& o : options_) o.lr = lr;
}

template <typename T>
void Adam<T>::set_lr(std::size_t group, double lr) {
  options_.at(group).lr = lr;
}

template <typename T>
void Adam<T>::load_state(AdamState<T> state) {
  if (state.steps < 0) {
    throw std::invalid_argument(fmt::format("Adam: state has {} steps", state.steps));
  }
  if (state.m.size() != m_.size() || state.v.size() != v_.size()) {
    throw std::invalid_argument(fmt::format("Adam: state has {}/{} moments for {} parameters",
                                            state.m.size(), state.v.size(), m_.size()));
  }
  for (std::size_t i = 0; i < m_.size(); ++i) {
    for (const Matrix<T>* moment : {&state.m[i], &state.v[i]}) {
      if (moment->rows() != m_[i].rows() || moment->cols() != m_[i].cols()) {
        throw std::invalid_argument(
            fmt::format("Adam: state moment #{} is {}x{} but its parameter is {}x{}", i,
                        moment->rows(), moment->cols(), m_[i].rows(), m_[i].cols()));
      }
    }
  }
  this->steps_ = state.steps;
  m_ = std::move(state.m);
  v_ = std::move(state.v);
}

// Not in an anonymous namespace: Adam<T>::update's lambda captures an AdamStep, and GCC warns of
// a type local to this file inside a class template's member (-Wsubobject-linkage).
namespace detail {

// One Adam step's constants, as torch.optim.Adam(W) computes them at step t.
template <typename T>
struct AdamStep {
  T beta1, beta2, step_size, bias_correction2_sqrt, eps, decay, shrink;
  bool decoupled, l2;
};

// The step over elements [begin, end) of p, its gradient g and moments m and v, in one pass. A
// plain loop, which GCC vectorises with the CPU's sqrt (-fno-math-errno), through pointers that do
// not alias. As Eigen expressions, the select() that kept an overflowed v at inf ran one element
// at a time (Eigen 3.4 has no packet select), and without it Eigen's vectorised float sqrt,
// approximate, turns inf into NaN: 2.3 ms of the pixel task's step (bench/nn_bench,
// BM_AdamUpdate). Where v overflows to inf, the step is m / inf = 0, as torch's.
template <typename T>
void adam_elements(AdamStep<T> c, Eigen::Index begin, Eigen::Index end, T* __restrict p,
                   const T* __restrict g, T* __restrict m, T* __restrict v) {
  for (Eigen::Index k = begin; k < end; ++k) {
    const T pk = c.decoupled ? p[k] * c.shrink : p[k];
    const T gk = c.l2 ? g[k] + c.decay * pk : g[k];
    const T mk = c.beta1 * m[k] + (T(1) - c.beta1) * gk;
    const T vk = c.beta2 * v[k] + (T(1) - c.beta2) * (gk * gk);
    m[k] = mk;
    v[k] = vk;
    p[k] = pk - c.step_size * mk / (std::sqrt(vk) / c.bias_correction2_sqrt + c.eps);
  }
}

}  // namespace detail

template <typename T>
void Adam<T>::update(std::size_t i, Matrix<T>& p, const Matrix<T>& g) {
  const AdamOptions& o = options_[group_[i]];
  const double t = double(this->steps_);
  const T decay = T(o.weight_decay);
  const bool decoupled = decay != T(0) && o.decoupled_weight_decay;
  const detail::AdamStep<T> c{
      .beta1 = T(o.beta1),
      .beta2 = T(o.beta2),
      .step_size = T(o.lr / (1.0 - std::pow(o.beta1, t))),
      .bias_correction2_sqrt = T(std::sqrt(1.0 - std::pow(o.beta2, t))),
      .eps = T(o.eps),
      .decay = decay,
      .shrink = T(1.0 - o.lr * o.weight_decay),  // AdamW's, in double as torch's
      .decoupled = decoupled,
      .l2 = decay != T(0) && !decoupled};
  // In blocks of whole SIMD packets (ad::element_block), one per thread for large parameters, as
  // autodiff's elementwise ops: any split gives the same bits.
  ad::for_element_blocks(p.size(), [&](ad::RowBlock block) {
    detail::adam_elements(c, block.begin, block.end, p.data(), g.data(), m_[i].data(),
                          v_[i].data());
  });
}

template <typename T>
Sgd<T>::Sgd(std::vector<ad::Var<T>> parameters, SgdOptions options)
    : Optimizer<T>(std::move(parameters)), options_(options) {
  check_non_negative("Sgd", "lr", options_.lr);
  check_non_negative("Sgd", "momentum", options_.momentum);
  check_non_negative("Sgd", "weight_decay", options_.weight_decay);
  if (options_.nesterov && (options_.momentum <= 0 || options_.dampening != 0)) {
    throw std::invalid_argument("Sgd: Nesterov momentum requires momentum > 0 and dampening 0");
  }
  if (options_.momentum != 0) {
    for (const ad::Var<T>& p : this->parameters_) {
      buffers_.push_back(Matrix<T>::Zero(p.rows(), p.cols()));
    }
  }
}

template <typename T>
void Sgd<T>::update(std::size_t i, Matrix<T>& p, const Matrix<T>& g) {
  const T lr = T(options_.lr), decay = T(options_.weight_decay);
  const T mu = T(options_.momentum), damp = T(options_.dampening);
  const auto d = g.array() + decay * p.array();  // an expression, evaluated where used
  if (options_.momentum == 0) {
    p.array() -= lr * d;
    return;
  }
  auto b = buffers_[i].array();
  if (this->steps_ == 1) {
    b = d;
  } else {
    b = mu * b + (T(1) - damp) * d;
  }
  if (options_.nesterov) {
    p.array() -= lr * (d + mu * b);
  } else {
    p.array() -= lr * b;
  }
}

template class Optimizer<float>;
template class Optimizer<double>;
template class Adam<float>;
template class Adam<double>;
template class Sgd<float>;
template class Sgd<double>;

}  // namespace hnn::nn
