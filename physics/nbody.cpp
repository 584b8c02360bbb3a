// NBody: pairwise gravity vectorised over the batch (one column op per pair).
#include "physics/nbody.h"

#include <fmt/format.h>

#include <cmath>
#include <numbers>
#include <stdexcept>

namespace hnn::physics {
namespace {

// Two draws in a fixed order (constructor arguments have none).
Eigen::Vector2d draw2(std::uniform_real_distribution<double>& d, std::mt19937_64& rng) {
  const double first = d(rng);
  return {first, d(rng)};
}

Eigen::Vector2d rotate(const Eigen::Vector2d& v, double angle) {
  const double c = std::cos(angle), s = std::sin(angle);
  return {c * v.x() - s * v.y(), s * v.x() + c * v.y()};
}

}  // namespace

NBody::NBody(std::vector<double> masses, double gravity)
    : masses_(std::move(masses)), gravity_(gravity) {
  if (masses_.size() < 2) throw std::invalid_argument("NBody needs at least 2 bodies");
  for (double m : masses_) {
    if (!(m > 0.0) || !std::isfinite(m)) {
      throw std::invalid_argument(fmt::format("NBody mass {} is not positive and finite", m));
    }
  }
  if (!(gravity_ > 0.0) || !std::isfinite(gravity_)) {
    throw std::invalid_argument(fmt::format("NBody G = {} is not positive and finite", gravity_));
  }
}

NBody NBody::equal_masses(int bodies) {
  return NBody(std::vector<double>(static_cast<std::size_t>(std::max(bodies, 0)), 1.0));
}

std::string NBody::name() const { return fmt::format("{}body", bodies()); }

int NBody::column(int body, int axis, bool momentum) const {
  return (momentum ? 2 * bodies() : 0) + axis * bodies() + body;
}

Eigen::VectorXd NBody::hamiltonian_batch(const BatchView& x) const {
  const int n = bodies();
  Eigen::ArrayXd h = Eigen::ArrayXd::Zero(x.rows());
  for (int i = 0; i < n; ++i) {
    const auto px = x.col(column(i, 0, true)).array(), py = x.col(column(i, 1, true)).array();
    h += (px.square() + py.square()) / (2.0 * masses_[i]);
    for (int j = i + 1; j < n; ++j) {
      const Eigen::ArrayXd dx = x.col(i).array() - x.col(j).array();
      const Eigen::ArrayXd dy = x.col(n + i).array() - x.col(n + j).array();
      h -= gravity_ * masses_[i] * masses_[j] / (dx.square() + dy.square()).sqrt();
    }
  }
  return h.matrix();
}

void NBody::velocity(const BatchView& p, BatchSpan dq) const {
  const int n = bodies();
  for (int i = 0; i < n; ++i) {
    dq.col(i) = p.col(i) / masses_[i];
    dq.col(n + i) = p.col(n + i) / masses_[i];
  }
}

void NBody::force(const BatchView& q, BatchSpan dp) const {
  const int n = bodies();
  dp.setZero();
  Eigen::ArrayXd dx(q.rows()), dy(q.rows()), s(q.rows());  // reused across pairs
  for (int i = 0; i < n; ++i) {
    for (int j = i + 1; j < n; ++j) {
      dx = q.col(j).array() - q.col(i).array();
      dy = q.col(n + j).array() - q.col(n + i).array();
      // s = G m_i m_j / r^3: force on i is s (q_j - q_i), on j the opposite.
      s = dx.square() + dy.square();
      s = (gravity_ * masses_[i] * masses_[j]) / (s * s.sqrt());  // a cheaper r^-3 than pow
      dp.col(i).array() += s * dx;
      dp.col(n + i).array() += s * dy;
      dp.col(j).array() -= s * dx;
      dp.col(n + j).array() -= s * dy;
    }
  }
}

Eigen::MatrixXd NBody::total_momentum(const Batch& x) const {
  const int n = bodies();
  Eigen::MatrixXd total(x.rows(), 2);
  total.col(0) = x.middleCols(2 * n, n).rowwise().sum();
  total.col(1) = x.middleCols(3 * n, n).rowwise().sum();
  return total;
}

Eigen::VectorXd NBody::angular_momentum(const Batch& x) const {
  const int n = bodies();
  const auto qx = x.middleCols(0, n).array(), qy = x.middleCols(n, n).array();
  const auto px = x.middleCols(2 * n, n).array(), py = x.middleCols(3 * n, n).array();
  return (qx * py - qy * px).rowwise().sum().matrix();
}

Eigen::MatrixXd NBody::center_of_mass(const Batch& x) const {
  const int n = bodies();
  const Eigen::Map<const Eigen::VectorXd> m(masses_.data(), n);
  Eigen::MatrixXd com(x.rows(), 2);
  com.col(0) = x.middleCols(0, n) * m / m.sum();
  com.col(1) = x.middleCols(n, n) * m / m.sum();
  return com;
}

Batch NBody::sample_initial_states(int n, std::mt19937_64& rng) const {
  if (bodies() == 2) return sample_two_body(n, rng);
  if (bodies() == 3) return sample_three_body(n, rng);
  throw std::logic_error(fmt::format("no initial-state sampler for {} bodies", bodies()));
}

// docs/tasks.md, task 4: body 1 at pos ~ U[0.5, 1.5]^2, body 2 at -pos, velocities of
// a circular orbit scaled by (1 + 0.05 n), n ~ N(0, 1), body 2 opposite.
Batch NBody::sample_two_body(int n, std::mt19937_64& rng) const {
  std::uniform_real_distribution<double> u(0.5, 1.5);
  std::normal_distribution<double> normal(0.0, 1.0);
  Batch x(n, dim());
  for (int k = 0; k < n; ++k) {
    const Eigen::Vector2d pos = draw2(u, rng);
    const double r = pos.norm();
    const Eigen::Vector2d vel =
        Eigen::Vector2d(-pos.y(), pos.x()) / (2.0 * std::pow(r, 1.5)) * (1.0 + 0.05 * normal(rng));
    for (int axis = 0; axis < 2; ++axis) {
      x(k, column(0, axis, false)) = pos(axis);
      x(k, column(1, axis, false)) = -pos(axis);
      x(k, column(0, axis, true)) = masses_[0] * vel(axis);
      x(k, column(1, axis, true)) = -masses_[1] * vel(axis);
    }
  }
  return x;
}

// docs/tasks.md, task 4b: a rotating equilateral triangle of radius U[0.9, 1.2],
// each velocity component scaled by (1 + 0.2 u), u ~ U[-1, 1].
Batch NBody::sample_three_body(int n, std::mt19937_64& rng) const {
  std::uniform_real_distribution<double> unit(-1.0, 1.0), radius(0.9, 1.2);
  const double third = 2.0 * std::numbers::pi / 3.0;
  const double speed = std::sqrt(std::sin(std::numbers::pi / 3.0) /
                                 (2.0 * std::pow(std::cos(std::numbers::pi / 6.0), 2)));
  Batch x(n, dim());
  for (int k = 0; k < n; ++k) {
    Eigen::Vector2d p1 = draw2(unit, rng);
    while (p1.norm() == 0.0) p1 = draw2(unit, rng);
    const double r = radius(rng);
    p1 *= r / p1.norm();
    const Eigen::Vector2d v1 = rotate(p1, std::numbers::pi / 2.0) / std::pow(r, 1.5) * speed;
    for (int b = 0; b < 3; ++b) {
      const Eigen::Vector2d pos = rotate(p1, b * third);
      Eigen::Vector2d vel = rotate(v1, b * third);
      vel.x() *= 1.0 + 0.2 * unit(rng);
      vel.y() *= 1.0 + 0.2 * unit(rng);
      for (int axis = 0; axis < 2; ++axis) {
        x(k, column(b, axis, false)) = pos(axis);
        x(k, column(b, axis, true)) = masses_[b] * vel(axis);
      }
    }
  }
  return x;
}

}  // namespace hnn::physics
