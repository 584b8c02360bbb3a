#include "nn/dynamics.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <span>
#include <stdexcept>

#include "autodiff/ops.h"
#include "autodiff/tape.h"

namespace hnn::nn {

std::string_view to_string(ModelKind kind) { return name_of(kModelKindNames, kind); }
std::string_view to_string(FieldType field) { return name_of(kFieldTypeNames, field); }
ModelKind parse_model_kind(std::string_view name) {
  return parse_name(kModelKindNames, name, "model");
}
FieldType parse_field_type(std::string_view name) {
  return parse_name(kFieldTypeNames, name, "field type");
}

namespace {

// A CHNN or CLNN needs its system, and sees positions only: no angles, no input scales. Any other
// model refuses a system it would ignore.
void validate_constraints(const DynamicsConfig& config) {
  if (!is_constrained(config.model)) {
    if (!config.constraints.empty()) {
      throw std::invalid_argument(
          fmt::format("model: a {} model takes no constraints (only chnn and clnn do)",
                      to_string(config.model)));
    }
    return;
  }
  if (config.constraints.empty()) {
    throw std::invalid_argument(
        fmt::format("model: a {} model needs the constrained system (DynamicsConfig::constraints)",
                    to_string(config.model)));
  }
  validate(config.constraints);
  if (config.dim != 2 * config.constraints.positions()) {
    throw std::invalid_argument(
        fmt::format("model: a {} state of {} points in {} dimensions has dim {}, got {}",
                    to_string(config.model), config.constraints.points, config.constraints.dim,
                    2 * config.constraints.positions(), config.dim));
  }
  if (config.angles != 0 || !config.input_scale.empty()) {
    throw std::invalid_argument(fmt::format(
        "model: a {} model takes Cartesian positions as they are: no angles, no input_scale",
        to_string(config.model)));
  }
}

}  // namespace

void validate(const DynamicsConfig& config) {
  validate_constraints(config);
  if (config.dim < 1) {
    throw std::invalid_argument(fmt::format("model: state dimension {} must be >= 1", config.dim));
  }
  if (config.model == ModelKind::kDhnn && config.field != FieldType::kBoth) {
    throw std::invalid_argument(
        fmt::format("model: a dhnn learns H and D (field type 'both'), got field type '{}'",
                    to_string(config.field)));
  }
  if (learns_scalars(config.model) && config.dim % 2 != 0 &&
      config.field != FieldType::kConservative) {
    throw std::invalid_argument(
        fmt::format("model: an HNN needs an even state dimension x = (q, p), got {}", config.dim));
  }
  if (needs_velocities(config.model) && config.dim % 2 != 0) {
    throw std::invalid_argument(
        fmt::format("model: an {} needs an even state dimension x = (q, v), got {}",
                    to_string(config.model), config.dim));
  }
  if (config.model == ModelKind::kMassHnn && config.activation != Activation::kTanh) {
    throw std::invalid_argument(fmt::format(
        "model: an hnn-mass is built for tanh (its mass matrix's tangent and gradient pass through "
        "tanh layers), got activation '{}'",
        to_string(config.activation)));
  }
  if (config.given_velocities && (config.model != ModelKind::kBaseline || config.dim % 2 != 0)) {
    throw std::invalid_argument(fmt::format(
        "model: given velocities need a baseline with an even state x = (q, v), got a {} of "
        "dimension {}",
        to_string(config.model), config.dim));
  }
  if (!(std::isfinite(config.kinetic_prior) && config.kinetic_prior >= 0)) {
    throw std::invalid_argument(fmt::format(
        "model: kinetic_prior must be a finite number >= 0, got {}", config.kinetic_prior));
  }
  const bool scales_ok = std::all_of(config.input_scale.begin(), config.input_scale.end(),
                                     [](double s) { return s > 0 && std::isfinite(s); });
  if (!(config.input_scale.empty() || Index(config.input_scale.size()) == config.dim) ||
      !scales_ok) {
    throw std::invalid_argument(fmt::format(
        "model: input_scale needs one positive, finite scale per coordinate ({}), got [{}]",
        config.dim, fmt::join(config.input_scale, ", ")));
  }
  if (config.angles < 0 || 2 * config.angles > config.dim) {
    throw std::invalid_argument(fmt::format(
        "model: {} angle coordinates do not fit a state of dimension {} (angles are coordinates "
        "q, the first half)",
        config.angles, config.dim));
  }
  for (Index i = 0; i < config.angles && !config.input_scale.empty(); ++i) {
    if (config.input_scale[std::size_t(i)] != 1.0) {
      throw std::invalid_argument(fmt::format(
          "model: angle coordinate {} has input scale {}; an angle is seen as (cos, sin), "
          "unscaled, so its scale must be 1",
          i, config.input_scale[std::size_t(i)]));
    }
  }
}

MlpConfig mlp_config(const DynamicsConfig& config) {
  validate(config);
  MlpConfig mlp;
  // An angle is seen as (cos, sin); a constrained model's MLP sees the positions only, a mass
  // HNN's their embedding.
  Index in = config.dim + config.angles;
  if (is_constrained(config.model)) in = config.dim / 2;
  if (config.model == ModelKind::kMassHnn) in = config.dim / 2 + config.angles;
  mlp.widths.push_back(in);
  mlp.widths.insert(mlp.widths.end(), config.hidden.begin(), config.hidden.end());
  Index out = config.given_velocities ? config.dim / 2 : config.dim;
  if (learns_scalars(config.model)) out = config.field == FieldType::kBoth ? 2 : 1;
  if (!learns_scalars(config.model) && config.model != ModelKind::kBaseline) out = 1;
  mlp.widths.push_back(out);
  mlp.activation = config.activation;
  mlp.init = config.init;
  mlp.last_bias = false;
  return mlp;
}

template <typename T>
DynamicsModel<T>::DynamicsModel(DynamicsConfig config, Mlp<T> mlp)
    : config_(std::move(config)), mlp_(std::move(mlp)) {
  const MlpConfig want = mlp_config(config_);
  const MlpConfig& got = mlp_.config();
  if (got.widths != want.widths || got.activation != want.activation ||
      got.last_bias != want.last_bias) {
    throw std::invalid_argument(fmt::format("{}: the MLP is '{}' but the config wants '{}'", name(),
                                            nn::describe(got), nn::describe(want)));
  }
}

template <typename T>
std::string DynamicsModel<T>::name() const {
  if (!learns_scalars(config_.model)) return std::string(to_string(config_.model));
  switch (config_.field) {
    case FieldType::kSolenoidal:
      return "hnn";
    case FieldType::kConservative:
      return "hnn-conservative";
    case FieldType::kBoth:
      return "hnn-dissipative";
  }
  return "hnn-unknown";
}

template <typename T>
std::string DynamicsModel<T>::kind() const {
  return fmt::format("{}:{}", name(), to_string(config_.activation));
}

template <typename T>
std::string DynamicsModel<T>::describe() const {
  return fmt::format("{} {}", name(), nn::describe(mlp_.config()));
}

template <typename T>
void DynamicsModel<T>::visit_parameters(const ParameterVisitor<T>& visit) {
  visit_child<T>(mlp_, "mlp", visit);
}

template <typename T>
Matrix<T> DynamicsModel<T>::field(const MatrixView<T>& x) const {
  return values_of("field", x, [&](const ad::Var<T>& v) { return time_derivative(v); });
}

template <typename T>
Matrix<T> DynamicsModel<T>::learned_energy(const MatrixView<T>&) const {
  throw std::logic_error(fmt::format("a {} model learns no conserved energy", name()));
}

template <typename T>
void DynamicsModel<T>::check_input(const char* what, Index rows, Index cols) const {
  if (cols != config_.dim || rows < 1) {
    throw ad::Error(fmt::format("{}.{}: input is {} but the model takes R x {}", name(), what,
                                ad::shape_str(rows, cols), config_.dim));
  }
}

namespace {

// A constant on the tape whose value `fill` writes in place: the recycled node keeps its buffer
// across steps, so a warmed-up step allocates nothing (a Matrix built for Var::constant would).
template <typename T, typename Fill>
ad::Var<T> tape_constant(Index rows, Index cols, const Fill& fill) {
  ad::Node<T>& node = ad::Tape<T>::current().push();
  node.op = "constant";
  node.value.resize(rows, cols);
  fill(node.value);
  return ad::Var<T>::of(node);
}

// 1 / scale, one column per coordinate, `copies` times side by side (1 x copies * dim).
template <typename T>
ad::Var<T> inverse_scale(std::span<const double> scale, Index copies = 1) {
  const auto dim = Index(scale.size());
  return tape_constant<T>(1, copies * dim, [&](Matrix<T>& v) {
    for (Index i = 0; i < v.cols(); ++i) v(0, i) = T(1.0 / scale[std::size_t(i % dim)]);
  });
}

}  // namespace

// Column blocks side by side; the parts vector is reused, so a step allocates nothing.
template <typename T>
ad::Var<T> concat(std::initializer_list<ad::Var<T>> blocks) {
  thread_local std::vector<ad::Var<T>> parts;
  parts.assign(blocks);
  const ad::Var<T> out = ad::concat_cols<T>(parts);
  parts.clear();
  return out;
}

namespace {

// What an MLP sees of coordinates y whose first `angles` columns are angles (scale: one per column
// of y, or empty): y / scale, each angle as (cos, sin).
template <typename T>
ad::Var<T> embed(const ad::Var<T>& y, Index angles, std::span<const double> scale) {
  const ad::Var<T> in = scale.empty() ? y : y * inverse_scale<T>(scale);
  if (angles == 0) return in;
  const ad::Var<T> angle = ad::slice_cols(in, 0, angles);
  return concat<T>(
      {ad::cos(angle), ad::sin(angle), ad::slice_cols(in, angles, in.cols() - angles)});
}

// A gradient g at embed(y) carried back to y: the chain rule through the embedding,
// d/dθ = -sin θ d/dcos + cos θ d/dsin, then 1 / scale.
template <typename T>
ad::Var<T> embedding_gradient(const ad::Var<T>& y, Index angles, std::span<const double> scale,
                              ad::Var<T> g) {
  if (angles > 0) {
    const ad::Var<T> angle = ad::slice_cols(y, 0, angles);
    const ad::Var<T> d_angle = ad::cos(angle) * ad::slice_cols(g, angles, angles) -
                               ad::sin(angle) * ad::slice_cols(g, 0, angles);
    g = concat<T>({d_angle, ad::slice_cols(g, 2 * angles, g.cols() - 2 * angles)});
  }
  return scale.empty() ? g : g * inverse_scale<T>(scale);
}

// The positions' share of a state's scales: its first half, or none.
std::span<const double> position_scale(const DynamicsConfig& config) {
  if (config.input_scale.empty()) return {};
  return std::span<const double>(config.input_scale).first(std::size_t(config.dim / 2));
}

}  // namespace

template <typename T>
ad::Var<T> DynamicsModel<T>::mlp_input(const ad::Var<T>& x) const {
  return embed(x, config_.angles, config_.input_scale);
}

template <typename T>
ad::Var<T> DynamicsModel<T>::position_input(const ad::Var<T>& q) const {
  return embed(q, config_.angles, position_scale(config_));
}

template <typename T>
ad::Var<T> DynamicsModel<T>::position_gradient(const ad::Var<T>& q, const ad::Var<T>& g) const {
  return embedding_gradient(q, config_.angles, position_scale(config_), g);
}

// d embed(q) = (-sin θ dθ, cos θ dθ, dq / scale for the rest).
template <typename T>
ad::Var<T> DynamicsModel<T>::position_tangent(const ad::Var<T>& q, const ad::Var<T>& q_dot) const {
  const std::span<const double> scale = position_scale(config_);
  const ad::Var<T> rate = scale.empty() ? q_dot : q_dot * inverse_scale<T>(scale);
  const Index a = config_.angles;
  if (a == 0) return rate;
  const ad::Var<T> angle = ad::slice_cols(q, 0, a), angle_rate = ad::slice_cols(rate, 0, a);
  return concat<T>({-(ad::sin(angle) * angle_rate), ad::cos(angle) * angle_rate,
                    ad::slice_cols(rate, a, rate.cols() - a)});
}

template <typename T>
ad::Var<T> DynamicsModel<T>::input_gradient(const ad::Var<T>& x, Index column) const {
  return embedding_gradient(x, config_.angles, config_.input_scale,
                            mlp_.input_gradient(mlp_input(x), column));
}

template <typename T>
ad::Var<T> DynamicsModel<T>::input_gradients(const ad::Var<T>& x) const {
  const ad::Var<T> g = mlp_.input_gradients(mlp_input(x));
  if (config_.angles == 0) {  // every output's block scaled by one op
    if (config_.input_scale.empty()) return g;
    return g * inverse_scale<T>(config_.input_scale, mlp_.output_dim());
  }
  const Index width = x.cols() + config_.angles;  // one output's block of g
  thread_local std::vector<ad::Var<T>> blocks;    // reused: no allocation per step
  blocks.clear();
  for (Index j = 0; j < mlp_.output_dim(); ++j)
    blocks.push_back(embedding_gradient(x, config_.angles, config_.input_scale,
                                        ad::slice_cols(g, j * width, width)));
  const ad::Var<T> all = ad::concat_cols<T>(blocks);
  blocks.clear();  // release the handles (capacity stays)
  return all;
}

template class DynamicsModel<float>;
template class DynamicsModel<double>;

}  // namespace hnn::nn
