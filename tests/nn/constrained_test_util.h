#pragma once
// Shared helpers of the CHNN/CLNN tests: chain pendulums in Cartesian coordinates, their exact
// motion from the angle equations, and the constraint Jacobians written out point by point
// (independently of nn/constrained/mechanics.cpp's incidence operators).

#include <Eigen/Cholesky>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "nn/nn.h"

namespace hnn::nn::testing {

/// A chain pendulum: point 0 hangs from `pivot` by lengths[0], point k from point k-1 by
/// lengths[k]; masses on the diagonal of M, or the given full mass matrix.
inline ConstraintSpec chain_spec(const std::vector<double>& lengths, Index dim,
                                 Eigen::MatrixXd mass, std::vector<double> pivot) {
  ConstraintSpec spec;
  spec.points = Index(lengths.size());
  spec.dim = dim;
  spec.mass = std::move(mass);
  spec.anchors.push_back({0, std::move(pivot), lengths[0]});
  for (Index k = 1; k < spec.points; ++k) spec.links.push_back({k - 1, k, lengths[std::size_t(k)]});
  return spec;
}

/// The message of the E that f throws ("" when it throws none).
template <typename E, typename F>
std::string message_of(F f) {
  try {
    f();
  } catch (const E& e) {
    return e.what();
  }
  return "";
}

/// A CHNN or CLNN config for `spec` with a small tanh MLP.
inline DynamicsConfig constrained_config(ModelKind kind, const ConstraintSpec& spec,
                                         std::vector<Index> hidden) {
  DynamicsConfig config;
  config.model = kind;
  config.dim = 2 * spec.positions();
  config.hidden = std::move(hidden);
  config.constraints = spec;
  return config;
}

/// G = dPhi/dx (C x N d) at positions x for phi_c = |e_c|^2 / 2, links then anchors, then a pin's
/// d rows (its weights on each axis); with the velocities in place of the positions in e
/// (relative velocities, anchors still, pins zero), Gdot.
inline Eigen::MatrixXd constraint_jacobian(const ConstraintSpec& spec, const Eigen::VectorXd& x,
                                           bool velocities = false) {
  const Index d = spec.dim;
  Eigen::MatrixXd g = Eigen::MatrixXd::Zero(spec.constraints(), spec.positions());
  Index c = 0;
  for (const Link& link : spec.links) {
    const Eigen::VectorXd e = x.segment(link.i * d, d) - x.segment(link.j * d, d);
    g.block(c, link.i * d, 1, d) = e.transpose();
    g.block(c++, link.j * d, 1, d) = -e.transpose();
  }
  for (const Anchor& anchor : spec.anchors) {
    Eigen::VectorXd e = x.segment(anchor.i * d, d);
    if (!velocities) e -= Eigen::Map<const Eigen::VectorXd>(anchor.point.data(), d);
    g.block(c++, anchor.i * d, 1, d) = e.transpose();
  }
  for (const Pin& pin : spec.pins) {
    for (Index k = 0; k < d && !velocities; ++k)
      for (Index j = 0; j < spec.points; ++j) g(c + k, j * d + k) = pin.weights[std::size_t(j)];
    c += d;
  }
  return g;
}

/// M^-1 (x) I_d, the inverse mass on the point-major positions.
inline Eigen::MatrixXd inverse_mass(const ConstraintSpec& spec) {
  const Index d = spec.dim, n = spec.positions();
  const Eigen::MatrixXd point_minv =
      spec.mass.llt().solve(Eigen::MatrixXd::Identity(spec.points, spec.points));
  Eigen::MatrixXd minv = Eigen::MatrixXd::Zero(n, n);
  for (Index i = 0; i < spec.points; ++i)
    for (Index j = 0; j < spec.points; ++j)
      for (Index a = 0; a < d; ++a) minv(i * d + a, j * d + a) = point_minv(i, j);
  return minv;
}

/// The state (x, v) with v = u projected M-orthogonally onto G(x) v = 0.
inline Eigen::RowVectorXd tangent_state(const ConstraintSpec& spec, const Eigen::VectorXd& x,
                                        const Eigen::VectorXd& u) {
  const Eigen::MatrixXd minv = inverse_mass(spec), g = constraint_jacobian(spec, x);
  const Eigen::MatrixXd s = g * minv * g.transpose();
  const Eigen::VectorXd v = u - minv * g.transpose() * s.llt().solve(g * u);
  Eigen::RowVectorXd z(2 * x.size());
  z << x.transpose(), v.transpose();
  return z;
}

/// Random states on the manifold of a chain spec: each point at its length from the one before
/// in a random direction, velocities random and then projected M-orthogonally onto G v = 0.
inline Matrix<double> chain_states(const ConstraintSpec& spec, Index rows, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal;
  const Index d = spec.dim, n = spec.positions();
  Matrix<double> z(rows, 2 * n);
  for (Index r = 0; r < rows; ++r) {
    Eigen::VectorXd x(n), u(n);
    for (Index k = 0; k < spec.points; ++k) {
      Eigen::VectorXd dir(d);
      for (Index a = 0; a < d; ++a) dir(a) = normal(rng);
      const Eigen::VectorXd from =
          k == 0 ? Eigen::Map<const Eigen::VectorXd>(spec.anchors[0].point.data(), d).eval()
                 : x.segment((k - 1) * d, d).eval();
      const double length = k == 0 ? spec.anchors[0].length : spec.links[std::size_t(k - 1)].length;
      x.segment(k * d, d) = from + length * dir.normalized();
    }
    for (Index i = 0; i < n; ++i) u(i) = normal(rng);
    z.row(r) = tangent_state(spec, x, u);
  }
  return z;
}

}  // namespace hnn::nn::testing
