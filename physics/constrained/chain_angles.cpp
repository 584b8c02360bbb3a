// The chain pendulum in angles and its maps to and from Cartesian coordinates (chain_angles.h).
#include "physics/constrained/chain_angles.h"

#include <Eigen/Dense>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include "physics/constrained/systems.h"

namespace hnn::physics::constrained {

Batch chain_cartesian(const Eigen::VectorXd& lengths, const Batch& angles_and_rates) {
  const auto links = static_cast<int>(lengths.size());
  if (angles_and_rates.cols() != 2 * links)
    throw std::invalid_argument("chain_cartesian: needs 2 x links columns (angles, rates)");
  Batch z(angles_and_rates.rows(), 4 * links);
  for (Eigen::Index r = 0; r < z.rows(); ++r) {
    double x = 0.0, y = 0.0, vx = 0.0, vy = 0.0;
    for (int k = 0; k < links; ++k) {
      const double theta = angles_and_rates(r, k), omega = angles_and_rates(r, links + k);
      const double s = std::sin(theta), c = std::cos(theta), l = lengths[k];
      x += l * s;
      y -= l * c;
      vx += l * c * omega;
      vy += l * s * omega;
      z.row(r).segment(2 * k, 2) << x, y;
      z.row(r).segment(2 * links + 2 * k, 2) << vx, vy;
    }
  }
  return z;
}

Batch chain_angles(int links, const Batch& cartesian) {
  if (cartesian.cols() != 4 * links)
    throw std::invalid_argument("chain_angles: needs 4 x links columns (x, v)");
  Batch out(cartesian.rows(), 2 * links);
  for (Eigen::Index r = 0; r < out.rows(); ++r) {
    for (int k = 0; k < links; ++k) {
      const auto rel = [&](int offset) {
        const double here = cartesian(r, offset + 2 * k);
        return k == 0 ? here : here - cartesian(r, offset + 2 * (k - 1));
      };
      const double rx = rel(0), ry = rel(1), ux = rel(2 * links), uy = rel(2 * links + 1);
      out(r, k) = std::atan2(rx, -ry);
      out(r, links + k) = (rx * uy - ry * ux) / (rx * rx + ry * ry);
    }
  }
  return out;
}

void unwrap_angles(std::vector<Batch>& states, int links) {
  for (std::size_t k = 1; k < states.size(); ++k) {
    for (Eigen::Index r = 0; r < states[k].rows(); ++r) {
      for (int c = 0; c < links; ++c) {
        const double jump = states[k](r, c) - states[k - 1](r, c);
        states[k](r, c) -= 2.0 * std::numbers::pi * std::round(jump / (2.0 * std::numbers::pi));
      }
    }
  }
}

ChainPendulumAngles::ChainPendulumAngles(Eigen::VectorXd masses, Eigen::VectorXd lengths, double g)
    : masses_(std::move(masses)),
      lengths_(std::move(lengths)),
      g_(g),
      cartesian_(chain_pendulum(masses_, lengths_)) {}

ChainPendulumAngles::ChainPendulumAngles(int links)
    : ChainPendulumAngles(chain_pendulum_masses(links), chain_pendulum_lengths(links)) {}

Eigen::MatrixXd ChainPendulumAngles::mass_matrix(const Eigen::VectorXd& theta) const {
  const int n = links();
  Eigen::MatrixXd m(n, n);
  for (int a = 0; a < n; ++a)
    for (int b = 0; b < n; ++b) {
      const double mu = masses_.tail(n - std::max(a, b)).sum();
      m(a, b) = mu * lengths_[a] * lengths_[b] * std::cos(theta[a] - theta[b]);
    }
  return m;
}

Eigen::VectorXd ChainPendulumAngles::hamiltonian_batch(const BatchView& x) const {
  const int n = links();
  Eigen::VectorXd h(x.rows());
  for (Eigen::Index r = 0; r < x.rows(); ++r) {
    const Eigen::VectorXd theta = x.row(r).head(n).transpose(), p = x.row(r).tail(n).transpose();
    double potential = 0.0;
    for (int a = 0; a < n; ++a)
      potential -= g_ * masses_.tail(n - a).sum() * lengths_[a] * std::cos(theta[a]);
    h[r] = 0.5 * p.dot(mass_matrix(theta).ldlt().solve(p)) + potential;
  }
  return h;
}

// dp_c/dt = -dH/dtheta_c = omega^T (dM/dtheta_c) omega / 2 - dV/dtheta_c
// = -sum_b mu_cb l_c l_b omega_c omega_b sin(theta_c - theta_b) - g mu_cc l_c sin theta_c.
Eigen::VectorXd ChainPendulumAngles::momentum_rate(const Eigen::VectorXd& theta,
                                                   const Eigen::VectorXd& omega) const {
  const int n = links();
  Eigen::VectorXd rate(n);
  for (int c = 0; c < n; ++c) {
    rate[c] = -g_ * masses_.tail(n - c).sum() * lengths_[c] * std::sin(theta[c]);
    for (int b = 0; b < n; ++b) {
      const double mu = masses_.tail(n - std::max(b, c)).sum();
      rate[c] -=
          mu * lengths_[c] * lengths_[b] * omega[c] * omega[b] * std::sin(theta[c] - theta[b]);
    }
  }
  return rate;
}

// d omega/dt from p = M omega: M alpha = dp/dt - (dM/dt) omega, where
// dM_ab/dt = -mu_ab l_a l_b sin(theta_a - theta_b) (omega_a - omega_b).
Eigen::VectorXd ChainPendulumAngles::angular_acceleration(const Eigen::VectorXd& theta,
                                                          const Eigen::VectorXd& omega) const {
  const int n = links();
  Eigen::MatrixXd m_dot(n, n);
  for (int a = 0; a < n; ++a)
    for (int b = 0; b < n; ++b)
      m_dot(a, b) = -masses_.tail(n - std::max(a, b)).sum() * lengths_[a] * lengths_[b] *
                    std::sin(theta[a] - theta[b]) * (omega[a] - omega[b]);
  return mass_matrix(theta).ldlt().solve(momentum_rate(theta, omega) - m_dot * omega);
}

void ChainPendulumAngles::vector_field(const BatchView& x, Batch& dxdt) const {
  const int n = links();
  dxdt.resize(x.rows(), 2 * n);
  for (Eigen::Index r = 0; r < x.rows(); ++r) {
    const Eigen::VectorXd theta = x.row(r).head(n).transpose(), p = x.row(r).tail(n).transpose();
    const Eigen::VectorXd omega = mass_matrix(theta).ldlt().solve(p);
    dxdt.row(r).head(n) = omega.transpose();
    dxdt.row(r).tail(n) = momentum_rate(theta, omega).transpose();
  }
}

ChainPendulumVelocities::ChainPendulumVelocities(ChainPendulumAngles canonical)
    : canonical_(std::move(canonical)) {}

Eigen::VectorXd ChainPendulumVelocities::hamiltonian_batch(const BatchView& x) const {
  return canonical_.hamiltonian_batch(canonical_.momenta_from_velocities(x));
}

void ChainPendulumVelocities::vector_field(const BatchView& x, Batch& dxdt) const {
  const int n = canonical_.links();
  dxdt.resize(x.rows(), 2 * n);
  for (Eigen::Index r = 0; r < x.rows(); ++r) {
    const Eigen::VectorXd theta = x.row(r).head(n).transpose(),
                          omega = x.row(r).tail(n).transpose();
    dxdt.row(r).head(n) = omega.transpose();
    dxdt.row(r).tail(n) = canonical_.angular_acceleration(theta, omega).transpose();
  }
}

Batch ChainPendulumVelocities::sample_initial_states(int n, std::mt19937_64& rng) const {
  return chain_angles(canonical_.links(), canonical_.cartesian().sample_initial_states(n, rng));
}

Batch ChainPendulumVelocities::to_cartesian(const Batch& x) const {
  return chain_cartesian(canonical_.lengths(), x);
}

Batch ChainPendulumAngles::momenta_from_velocities(const Batch& angles_and_rates) const {
  const int n = links();
  Batch x = angles_and_rates;
  for (Eigen::Index r = 0; r < x.rows(); ++r)
    x.row(r).tail(n) =
        (mass_matrix(x.row(r).head(n).transpose()) * x.row(r).tail(n).transpose()).transpose();
  return x;
}

Batch ChainPendulumAngles::velocities_from_momenta(const Batch& x) const {
  const int n = links();
  Batch out = x;
  for (Eigen::Index r = 0; r < x.rows(); ++r)
    out.row(r).tail(n) = mass_matrix(x.row(r).head(n).transpose())
                             .ldlt()
                             .solve(x.row(r).tail(n).transpose())
                             .transpose();
  return out;
}

Batch ChainPendulumAngles::to_cartesian(const Batch& x) const {
  return chain_cartesian(lengths_, velocities_from_momenta(x));
}

Batch ChainPendulumAngles::from_cartesian(const Batch& z) const {
  return momenta_from_velocities(chain_angles(links(), z));
}

Batch ChainPendulumAngles::sample_initial_states(int n, std::mt19937_64& rng) const {
  return from_cartesian(cartesian_.sample_initial_states(n, rng));
}

}  // namespace hnn::physics::constrained
