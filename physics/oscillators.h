// One-degree-of-freedom systems of tasks 1-3: the ideal mass-spring and the
// ideal pendulum, plus the evaluation sampler the reference used for both.
#pragma once

#include "physics/system.h"

namespace hnn::physics {

/// H = stiffness q^2 + kinetic p^2. The defaults are the reference code's
/// H = q^2 + p^2 (twice the textbook kq^2/2 + p^2/2m): dq/dt = 2p, dp/dt = -2q.
class Spring : public SeparableSystem {
 public:
  explicit Spring(double stiffness = 1.0, double kinetic = 1.0);

  int dim() const override { return 2; }
  std::string name() const override { return "spring"; }
  Eigen::VectorXd hamiltonian_batch(const BatchView& x) const override;
  void velocity(const BatchView& p, BatchSpan dq) const override;
  void force(const BatchView& q, BatchSpan dp) const override;
  /// Direction uniform in [-1,1]^2, normalised to radius r ~ U[0.1, 1.0].
  Batch sample_initial_states(int n, std::mt19937_64& rng) const override;
  /// Rotation in phase space at omega().
  std::optional<Batch> exact_flow(const Batch& x0, double t) const override;

  /// Angular frequency 2 sqrt(stiffness * kinetic) (2 by default: period pi).
  double omega() const;
  double stiffness() const { return stiffness_; }
  double kinetic() const { return kinetic_; }

 private:
  double stiffness_;
  double kinetic_;
};

/// H = potential (1 - cos q) + kinetic p^2. The defaults are task 2's
/// H = 3(1 - cos q) + p^2; the real-pendulum fit is Pendulum(2.4).
class Pendulum : public SeparableSystem {
 public:
  explicit Pendulum(double potential = 3.0, double kinetic = 1.0);

  int dim() const override { return 2; }
  std::string name() const override { return "pendulum"; }
  Eigen::VectorXd hamiltonian_batch(const BatchView& x) const override;
  void velocity(const BatchView& p, BatchSpan dq) const override;
  void force(const BatchView& q, BatchSpan dp) const override;
  /// Direction uniform in [-1,1]^2, normalised to radius r ~ U[1.3, 2.3].
  Batch sample_initial_states(int n, std::mt19937_64& rng) const override;

  /// Small-amplitude angular frequency sqrt(2 potential kinetic) (sqrt(6) by default).
  double small_angle_omega() const;
  double potential() const { return potential_; }
  double kinetic() const { return kinetic_; }

 private:
  double potential_;
  double kinetic_;
};

/// The damped spring of the dissipative-HNN paper (Sosanya & Greydanus 2022): the spring's
/// H = q^2 + p^2 plus the gradient field dD/dx of D = -rho q^2 / 2 (their code damps the
/// coordinate): dq/dt = 2p - rho q, dp/dt = -2q. Not conservative: hamiltonian_batch is the H
/// of its conservative part, which decays along the flow.
class DampedSpring : public System {
 public:
  explicit DampedSpring(double rho = 2.0);

  int dim() const override { return 2; }
  std::string name() const override { return "damped-spring"; }
  Eigen::VectorXd hamiltonian_batch(const BatchView& x) const override;
  void vector_field(const BatchView& x, Batch& dxdt) const override;
  /// The two parts of the field: (dH/dp, -dH/dq) and dD/dx.
  Batch conservative_part(const BatchView& x) const;
  Batch dissipative_part(const BatchView& x) const;
  /// Uniform in [-1.2, 1.2]^2 (the paper's grid range).
  Batch sample_initial_states(int n, std::mt19937_64& rng) const override;

 private:
  double rho_;
};

/// n states as the reference samples tasks 1-2: a direction uniform in
/// [-1,1]^2, normalised to a radius uniform in [r_lo, r_hi].
Batch sample_on_annulus(int n, double r_lo, double r_hi, std::mt19937_64& rng);

/// The energy-evaluation states of tasks 1-2: each component uniform in
/// [-0.8, 0.8], then pushed 0.2 away from zero (x + 0.2 sign(x)).
Batch sample_evaluation_states(int n, std::mt19937_64& rng);

}  // namespace hnn::physics
