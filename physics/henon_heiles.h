// The Hénon–Heiles system, the sampled-HNN paper's chaotic benchmark (Rahma, Datar & Dietrich
// 2024; their code's hamiltonian/henon_heiles.py), with the constants and domain of its protocol.
#pragma once

#include "physics/system.h"

namespace hnn::physics {

/// x = (q1, q2, p1, p2), H = (p1^2 + p2^2)/2 + (q1^2 + q2^2)/2 + alpha (q1^2 q2 - q2^3/3).
/// Separable: dq/dt = p, dp/dt = -(q1 + 2 alpha q1 q2, q2 + alpha (q1^2 - q2^2)). Chaotic above
/// H = 1/(6 alpha^2) and unbounded beyond it, so the paper learns it on a box of states rather
/// than along trajectories.
class HenonHeiles : public SeparableSystem {
 public:
  /// alpha >= 0 scales the cubic potential (the paper's 1; 0 is two uncoupled oscillators).
  /// States are sampled uniformly in [-half_width, half_width]^4 (the paper's 5).
  explicit HenonHeiles(double alpha = 1.0, double half_width = 5.0);

  int dim() const override { return 4; }
  std::string name() const override { return "henon_heiles"; }
  Eigen::VectorXd hamiltonian_batch(const BatchView& x) const override;
  void velocity(const BatchView& p, BatchSpan dq) const override;
  void force(const BatchView& q, BatchSpan dp) const override;
  /// Uniform in [-half_width, half_width]^4.
  Batch sample_initial_states(int n, std::mt19937_64& rng) const override;

  double alpha() const { return alpha_; }

 private:
  double alpha_, half_width_;
};

}  // namespace hnn::physics
