#include "nn/init.h"

#include <fmt/format.h>

#include <Eigen/QR>
#include <array>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include "nn/enum_names.h"

namespace hnn::nn {

namespace {

constexpr NameTable<Init, 7> kInitNames{{
    {Init::kOrthogonal, "orthogonal"},
    {Init::kXavierUniform, "xavier_uniform"},
    {Init::kXavierNormal, "xavier_normal"},
    {Init::kKaimingUniform, "kaiming_uniform"},
    {Init::kKaimingNormal, "kaiming_normal"},
    {Init::kLecunNormal, "lecun_normal"},
    {Init::kTorchDefault, "torch_default"},
}};

using RowMajorD = Matrix<double>;

RowMajorD normal_matrix(Index rows, Index cols, std::mt19937_64& rng, double std) {
  RowMajorD m(rows, cols);
  fill_standard_normal(std::span<double>(m.data(), std::size_t(m.size())), rng);
  return m * std;
}

RowMajorD uniform_matrix(Index rows, Index cols, std::mt19937_64& rng, double low, double high) {
  RowMajorD m(rows, cols);
  for (Index i = 0; i < m.size(); ++i) m.data()[i] = low + (high - low) * uniform01(rng);
  return m;
}

// The torch-shaped (rows x cols) orthogonal matrix in double.
RowMajorD orthogonal_double(Index rows, Index cols, std::mt19937_64& rng) {
  RowMajorD a = normal_matrix(rows, cols, rng, 1.0);
  const bool wide = rows < cols;
  Eigen::MatrixXd tall = wide ? Eigen::MatrixXd(a.transpose()) : Eigen::MatrixXd(a);
  const Index m = tall.rows(), k = tall.cols();
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(tall);
  Eigen::MatrixXd q = qr.householderQ() * Eigen::MatrixXd::Identity(m, k);
  for (Index j = 0; j < k; ++j) {
    if (qr.matrixQR()(j, j) < 0) q.col(j) *= -1.0;
  }
  return wide ? RowMajorD(q.transpose()) : RowMajorD(q);
}

}  // namespace

double uniform01(std::mt19937_64& rng) { return double(rng() >> 11) * 0x1.0p-53; }

void fill_standard_normal(std::span<double> out, std::mt19937_64& rng) {
  for (std::size_t i = 0; i < out.size(); i += 2) {
    const double u1 = 1.0 - uniform01(rng);  // (0, 1]: the log is finite
    const double u2 = uniform01(rng);
    const double r = std::sqrt(-2.0 * std::log(u1));
    const double angle = 2.0 * std::numbers::pi * u2;
    out[i] = r * std::cos(angle);
    if (i + 1 < out.size()) out[i + 1] = r * std::sin(angle);
  }
}

template <typename T>
Matrix<T> random_normal(Index rows, Index cols, std::mt19937_64& rng, double mean, double std) {
  return (normal_matrix(rows, cols, rng, std).array() + mean).matrix().template cast<T>();
}

template <typename T>
Matrix<T> random_uniform(Index rows, Index cols, std::mt19937_64& rng, double low, double high) {
  return uniform_matrix(rows, cols, rng, low, high).template cast<T>();
}

std::string_view to_string(Init init) { return name_of(kInitNames, init); }

Init parse_init(std::string_view name) { return parse_name(kInitNames, name, "initialisation"); }

template <typename T>
Matrix<T> orthogonal(Index rows, Index cols, std::mt19937_64& rng, double gain) {
  if (rows < 1 || cols < 1) {
    throw std::invalid_argument(fmt::format("orthogonal: empty shape {}x{}", rows, cols));
  }
  return (orthogonal_double(rows, cols, rng) * gain).template cast<T>();
}

template <typename T>
Matrix<T> init_weight(Init init, Index fan_in, Index fan_out, std::mt19937_64& rng) {
  if (fan_in < 1 || fan_out < 1) {
    throw std::invalid_argument(fmt::format("init_weight: empty layer {} -> {}", fan_in, fan_out));
  }
  const double in = double(fan_in), sum = double(fan_in + fan_out);
  // Every scheme draws the torch-shaped (fan_out x fan_in) matrix, then transposes it.
  RowMajorD w;
  switch (init) {
    case Init::kOrthogonal:
      w = orthogonal_double(fan_out, fan_in, rng);
      break;
    case Init::kXavierUniform: {
      const double a = std::sqrt(6.0 / sum);
      w = uniform_matrix(fan_out, fan_in, rng, -a, a);
      break;
    }
    case Init::kXavierNormal:
      w = normal_matrix(fan_out, fan_in, rng, std::sqrt(2.0 / sum));
      break;
    case Init::kKaimingUniform: {
      const double a = std::sqrt(6.0 / in);
      w = uniform_matrix(fan_out, fan_in, rng, -a, a);
      break;
    }
    case Init::kKaimingNormal:
      w = normal_matrix(fan_out, fan_in, rng, std::sqrt(2.0 / in));
      break;
    case Init::kLecunNormal:
      w = normal_matrix(fan_out, fan_in, rng, std::sqrt(1.0 / in));
      break;
    case Init::kTorchDefault: {
      const double a = 1.0 / std::sqrt(in);
      w = uniform_matrix(fan_out, fan_in, rng, -a, a);
      break;
    }
    default:
      throw std::invalid_argument(fmt::format("init_weight: unknown scheme {}", int(init)));
  }
  return w.transpose().template cast<T>();
}

template <typename T>
Matrix<T> init_bias(Index fan_in, Index fan_out, std::mt19937_64& rng) {
  const double a = 1.0 / std::sqrt(double(fan_in));
  return uniform_matrix(1, fan_out, rng, -a, a).template cast<T>();
}

#define HNN_INSTANTIATE(T)                                                           \
  template Matrix<T> random_normal(Index, Index, std::mt19937_64&, double, double);  \
  template Matrix<T> random_uniform(Index, Index, std::mt19937_64&, double, double); \
  template Matrix<T> orthogonal(Index, Index, std::mt19937_64&, double);             \
  template Matrix<T> init_weight(Init, Index, Index, std::mt19937_64&);              \
  template Matrix<T> init_bias(Index, Index, std::mt19937_64&);
HNN_INSTANTIATE(float)
HNN_INSTANTIATE(double)
#undef HNN_INSTANTIATE

}  // namespace hnn::nn
