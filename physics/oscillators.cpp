// Spring and Pendulum: formulas and samplers.
#include "physics/oscillators.h"

#include <cmath>
#include <stdexcept>

namespace hnn::physics {
namespace {

void require_positive(double value, const char* what) {
  if (!(value > 0.0) || !std::isfinite(value)) {
    throw std::invalid_argument(std::string(what) + " must be positive and finite");
  }
}

}  // namespace

Spring::Spring(double stiffness, double kinetic) : stiffness_(stiffness), kinetic_(kinetic) {
  require_positive(stiffness, "Spring stiffness");
  require_positive(kinetic, "Spring kinetic coefficient");
}

Eigen::VectorXd Spring::hamiltonian_batch(const BatchView& x) const {
  return (stiffness_ * x.col(0).array().square() + kinetic_ * x.col(1).array().square()).matrix();
}

void Spring::velocity(const BatchView& p, BatchSpan dq) const { dq = 2.0 * kinetic_ * p; }

void Spring::force(const BatchView& q, BatchSpan dp) const { dp = -2.0 * stiffness_ * q; }

Batch Spring::sample_initial_states(int n, std::mt19937_64& rng) const {
  return sample_on_annulus(n, 0.1, 1.0, rng);
}

DampedSpring::DampedSpring(double rho) : rho_(rho) {
  require_positive(rho, "DampedSpring damping rho");
}

Eigen::VectorXd DampedSpring::hamiltonian_batch(const BatchView& x) const {
  return (x.col(0).array().square() + x.col(1).array().square()).matrix();
}

Batch DampedSpring::conservative_part(const BatchView& x) const {
  Batch f(x.rows(), 2);
  f.col(0) = 2.0 * x.col(1);
  f.col(1) = -2.0 * x.col(0);
  return f;
}

Batch DampedSpring::dissipative_part(const BatchView& x) const {
  Batch f = Batch::Zero(x.rows(), 2);
  f.col(0) = -rho_ * x.col(0);
  return f;
}

void DampedSpring::vector_field(const BatchView& x, Batch& dxdt) const {
  dxdt = conservative_part(x) + dissipative_part(x);
}

Batch DampedSpring::sample_initial_states(int n, std::mt19937_64& rng) const {
  std::uniform_real_distribution<double> u(-1.2, 1.2);
  Batch x(n, 2);
  for (Eigen::Index i = 0; i < x.size(); ++i) x.data()[i] = u(rng);
  return x;
}

double Spring::omega() const { return 2.0 * std::sqrt(stiffness_ * kinetic_); }

std::optional<Batch> Spring::exact_flow(const Batch& x0, double t) const {
  // q = A cos(wt) + B sin(wt) with q' = 2 kinetic p and p' = -2 stiffness q.
  const double w = omega(), c = std::cos(w * t), s = std::sin(w * t);
  Batch x(x0.rows(), 2);
  x.col(0) = c * x0.col(0) + (2.0 * kinetic_ / w) * s * x0.col(1);
  x.col(1) = c * x0.col(1) - (2.0 * stiffness_ / w) * s * x0.col(0);
  return x;
}

Pendulum::Pendulum(double potential, double kinetic) : potential_(potential), kinetic_(kinetic) {
  require_positive(potential, "Pendulum potential coefficient");
  require_positive(kinetic, "Pendulum kinetic coefficient");
}

Eigen::VectorXd Pendulum::hamiltonian_batch(const BatchView& x) const {
  return (potential_ * (1.0 - x.col(0).array().cos()) + kinetic_ * x.col(1).array().square())
      .matrix();
}

void Pendulum::velocity(const BatchView& p, BatchSpan dq) const { dq = 2.0 * kinetic_ * p; }

void Pendulum::force(const BatchView& q, BatchSpan dp) const {
  dp.array() = -potential_ * q.array().sin();
}

Batch Pendulum::sample_initial_states(int n, std::mt19937_64& rng) const {
  return sample_on_annulus(n, 1.3, 2.3, rng);
}

double Pendulum::small_angle_omega() const { return std::sqrt(2.0 * potential_ * kinetic_); }

Batch sample_on_annulus(int n, double r_lo, double r_hi, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::uniform_real_distribution<double> radius(r_lo, r_hi);
  Batch x(n, 2);
  for (int i = 0; i < n; ++i) {
    // Draw order as in the reference: direction first, then radius.
    double dq = 0.0, dp = 0.0;
    while (dq == 0.0 && dp == 0.0) {
      dq = unit(rng);
      dp = unit(rng);
    }
    const double scale = radius(rng) / std::hypot(dq, dp);
    x(i, 0) = dq * scale;
    x(i, 1) = dp * scale;
  }
  return x;
}

Batch sample_evaluation_states(int n, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-0.8, 0.8);
  Batch x(n, 2);
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < 2; ++j) {
      const double v = u(rng);
      x(i, j) = v + (v >= 0.0 ? 0.2 : -0.2);
    }
  }
  return x;
}

}  // namespace hnn::physics
