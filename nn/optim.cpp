#include "nn/optim.h"

#include <fmt/format.h>

#include <cmath>
#include <limits>
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

namespace {

// Parameters of at least this many elements are updated in blocks on the engine's threads (as
// autodiff's large elementwise ops are): a 256 x 256 weight's update was a serial stretch of
// some 40 us in the D-HNN's step, while the other thread waited.
constexpr Eigen::Index kParallelElements = Eigen::Index(1) << 15;

template <typename T>
using Elements = Eigen::Map<Eigen::Array<T, Eigen::Dynamic, 1>>;

}  // namespace

template <typename T>
void Adam<T>::update(std::size_t i, Matrix<T>& p, const Matrix<T>& g) {
  const AdamOptions& o = options_[group_[i]];
  const double t = double(this->steps_);
  const T beta1 = T(o.beta1), beta2 = T(o.beta2);
  const T step_size = T(o.lr / (1.0 - std::pow(o.beta1, t)));
  const T bias_correction2_sqrt = T(std::sqrt(1.0 - std::pow(o.beta2, t)));
  const T eps = T(o.eps), decay = T(o.weight_decay);
  const T shrink = T(1.0 - o.lr * o.weight_decay);  // AdamW's, in double as torch's
  const bool decoupled = decay != T(0) && o.decoupled_weight_decay,
             l2 = decay != T(0) && !decoupled;
  // Elementwise, in blocks of whole SIMD packets (ad::element_block), so any split gives the
  // same bits; each block runs m, v and p while they are in cache. One fused expression per
  // buffer: no temporaries, so no allocation.
  const Eigen::Index n = p.size();
  const int parts = n >= kParallelElements ? ad::parts_for(n) : 1;
  ad::parallel_for(parts, [&](int part) {
    const ad::RowBlock r = ad::element_block(n, parts, part);
    const auto at = [&](auto& x) { return Elements<T>(x.data() + r.begin, r.size()); };
    const Eigen::Map<const Eigen::Array<T, Eigen::Dynamic, 1>> ga(g.data() + r.begin, r.size());
    auto pa = at(p);
    auto m = at(m_[i]);
    auto v = at(v_[i]);
    if (decoupled) pa *= shrink;
    if (l2) {
      m = beta1 * m + (T(1) - beta1) * (ga + decay * pa);
      v = beta2 * v + (T(1) - beta2) * (ga + decay * pa).square();
    } else {
      m = beta1 * m + (T(1) - beta1) * ga;
      v = beta2 * v + (T(1) - beta2) * ga.square();
    }
    // A gradient whose square overflows leaves v at inf, and torch's step there is m / inf = 0.
    // Eigen's fast float sqrt (rsqrt and a Newton step) gives NaN for inf, which would turn the
    // weight into NaN: inf is kept as it is.
    const auto root = (v < std::numeric_limits<T>::infinity()).select(v.sqrt(), v);
    pa -= step_size * m / (root / bias_correction2_sqrt + eps);
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
