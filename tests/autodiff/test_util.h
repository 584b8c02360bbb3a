#pragma once
// Shared helpers of the autodiff tests: seeded random matrices, a tanh MLP written with engine
// ops, the HNN loss, and the task Hamiltonians of docs/tasks.md.

#include <unistd.h>

#include <Eigen/QR>
#include <cmath>
#include <fstream>
#include <random>
#include <vector>

#include "autodiff/autodiff.h"

namespace hnn::ad::testing {

using MatrixD = Matrix<double>;

/// rows x cols, entries uniform in [lo, hi), from an explicit seed.
inline MatrixD random_matrix(Eigen::Index rows, Eigen::Index cols, unsigned seed, double lo = -1,
                             double hi = 1) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> uniform(lo, hi);
  MatrixD m(rows, cols);
  for (Eigen::Index i = 0; i < m.size(); ++i) m.data()[i] = uniform(rng);
  return m;
}

/// Entries with |x| in [lo, hi) and a random sign: keeps inputs away from kinks at 0.
inline MatrixD random_away_from_zero(Eigen::Index rows, Eigen::Index cols, unsigned seed,
                                     double lo = 0.2, double hi = 1.5) {
  MatrixD m = random_matrix(rows, cols, seed, lo, hi);
  const MatrixD sign = random_matrix(rows, cols, seed + 7919);
  for (Eigen::Index i = 0; i < m.size(); ++i)
    if (sign.data()[i] < 0) m.data()[i] = -m.data()[i];
  return m;
}

/// Entries N(0, 1), from an explicit seed.
inline MatrixD gaussian_matrix(Eigen::Index rows, Eigen::Index cols, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal;
  MatrixD m(rows, cols);
  for (Eigen::Index i = 0; i < m.size(); ++i) m.data()[i] = normal(rng);
  return m;
}

/// A rows x cols matrix with orthonormal rows or columns (whichever are fewer), the Q factor of
/// a Gaussian matrix: the orthogonal initialisation of the HNN reference code.
inline MatrixD orthogonal_matrix(Eigen::Index rows, Eigen::Index cols, unsigned seed) {
  const bool tall = rows >= cols;
  const Eigen::MatrixXd g = gaussian_matrix(tall ? rows : cols, tall ? cols : rows, seed);
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(g);
  const Eigen::MatrixXd q =
      qr.householderQ() * Eigen::MatrixXd::Identity(g.rows(), g.cols());  // thin Q
  return tall ? MatrixD(q) : MatrixD(q.transpose());
}

/// Parameters of a tanh MLP sizes[0] -> ... -> sizes.back(): {W1, b1, W2, b2, ...}, with
/// orthogonal weights and small random biases.
inline std::vector<MatrixD> mlp_parameters(const std::vector<Eigen::Index>& sizes, unsigned seed) {
  std::vector<MatrixD> params;
  for (std::size_t l = 0; l + 1 < sizes.size(); ++l) {
    params.push_back(orthogonal_matrix(sizes[l], sizes[l + 1], seed + 101 * unsigned(l)));
    params.push_back(random_matrix(1, sizes[l + 1], seed + 101 * unsigned(l) + 1, -0.1, 0.1));
  }
  return params;
}

template <typename T>
std::vector<Var<T>> as_leaves(const std::vector<MatrixD>& values) {
  std::vector<Var<T>> leaves;
  for (const MatrixD& v : values) leaves.push_back(Var<T>::leaf(v.cast<T>()));
  return leaves;
}

/// tanh MLP with a linear last layer; params as mlp_parameters() makes them.
template <typename T>
Var<T> mlp(const std::vector<Var<T>>& params, Var<T> x) {
  for (std::size_t l = 0; l + 2 < params.size(); l += 2)
    x = tanh(linear(x, params[l], params[l + 1]));
  return linear(x, params[params.size() - 2], params.back());
}

/// The HNN field (dH/dp, -dH/dq) of x = (q, p), recorded so it can be differentiated again.
template <typename T>
Var<T> hnn_field(const std::vector<Var<T>>& params, const Var<T>& x) {
  const Var<T> dh = grad<T>({sum(mlp(params, x))}, {x}, {.create_graph = true})[0];
  const Eigen::Index n = x.cols() / 2;
  return concat_cols<T>({slice_cols(dh, n, n), -slice_cols(dh, 0, n)});
}

/// The HNN training loss mean((J grad_x H - target)^2).
template <typename T>
Var<T> hnn_loss(const std::vector<Var<T>>& params, const Var<T>& x, const Var<T>& target) {
  return mean(square(hnn_field(params, x) - target));
}

// ---- the task Hamiltonians, written with engine ops, x = (q, p) batch x 2n ----------------

/// Spring: H = q^2 + p^2.
template <typename T>
Var<T> spring_h(const Var<T>& x) {
  return sum_cols(square(x));
}

/// Pendulum: H = 3 (1 - cos q) + p^2.
template <typename T>
Var<T> pendulum_h(const Var<T>& x) {
  return scale(T(1) - cos(slice_cols(x, 0, 1)), T(3)) + square(slice_cols(x, 1, 1));
}

/// Two-body, x = (qx1, qx2, qy1, qy2, px1, px2, py1, py2): H = sum |p_i|^2 / 2 - 1/|q1 - q2|.
template <typename T>
Var<T> two_body_h(const Var<T>& x) {
  const Var<T> dx = slice_cols(x, 0, 1) - slice_cols(x, 1, 1);
  const Var<T> dy = slice_cols(x, 2, 1) - slice_cols(x, 3, 1);
  const Var<T> kinetic = scale(sum_cols(square(slice_cols(x, 4, 4))), T(0.5));
  return kinetic - pow(square(dx) + square(dy), T(-0.5));  // 1/r = (r^2)^(-1/2)
}

/// Analytic gradients of the three, batch x 2n.
template <typename T>
Matrix<T> spring_grad(const Matrix<T>& x) {
  return T(2) * x;
}

template <typename T>
Matrix<T> pendulum_grad(const Matrix<T>& x) {
  Matrix<T> g(x.rows(), 2);
  g.col(0) = T(3) * x.col(0).array().sin();
  g.col(1) = T(2) * x.col(1);
  return g;
}

template <typename T>
Matrix<T> two_body_grad(const Matrix<T>& x) {
  Matrix<T> g(x.rows(), 8);
  for (Eigen::Index i = 0; i < x.rows(); ++i) {
    const T dx = x(i, 0) - x(i, 1), dy = x(i, 2) - x(i, 3);
    const T r3 = std::pow(dx * dx + dy * dy, T(1.5));
    g(i, 0) = dx / r3;  // d(-1/r)/d qx1 = (qx1 - qx2) / r^3
    g(i, 1) = -dx / r3;
    g(i, 2) = dy / r3;
    g(i, 3) = -dy / r3;
    for (int k = 4; k < 8; ++k) g(i, k) = x(i, k);
  }
  return g;
}

/// Relative Frobenius error |a - b| / |b|.
template <typename A, typename B>
double relative_error(const A& a, const B& b) {
  return (a - b).norm() / b.norm();
}

/// Resident set size of this process in bytes (the second field of /proc/self/statm).
inline long resident_bytes() {
  std::ifstream statm("/proc/self/statm");
  long size = 0, resident = 0;
  statm >> size >> resident;
  return resident * sysconf(_SC_PAGESIZE);
}

}  // namespace hnn::ad::testing
