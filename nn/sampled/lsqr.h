#pragma once
// LSQR (Paige & Saunders 1982) on the damped, right-preconditioned least-squares problem
// min |A c - B|² + mu² |c|², c = M y with M = S R^-1: the iterative half of the lsqr solver
// (R from the normal equations) and of the sketch solver (R from the QR of a sketch).

#include "nn/sampled/systems.h"

namespace hnn::nn::sampled {

/// The right preconditioner M = S R^-1: R upper triangular, S a column scaling (none when s is
/// empty).
struct Preconditioner {
  ColMat r;
  Eigen::VectorXd s{};

  void apply(const ColMat& y, ColMat& c) const;    // c = S R^-1 y, in c's own memory
  void apply_t(const ColMat& c, ColMat& y) const;  // y = R^-T S c
};

/// The iteration's vectors, allocated once: the iterations allocate nothing.
class Lsqr {
 public:
  /// mu: the damping (ridge) weight; 0 for the undamped problem.
  Lsqr(const LinearSystem& system, const Preconditioner& preconditioner, double mu = 0);

  /// Improves c in place (it solves for the correction from c); stops when the preconditioned
  /// normal-equation residual |(A M)^T r| falls below tolerance |A M| |r| (Paige & Saunders'
  /// test 2) or after max_iterations. Returns the iterations run.
  int run(ColMat& c, double tolerance, int max_iterations);

  /// Bytes of the iteration's vectors.
  std::size_t bytes() const;

 private:
  void forward(const ColMat& y);  // (av, av_damped) = [A; mu I] M y
  void backward(ColMat& out);     // out = M^T [A; mu I]^T (u, u_damped)
  double u_norm() const;

  const LinearSystem& a_;
  const Preconditioner& m_;
  double mu_;
  // u and av live in the equations' space, u_damped and av_damped in the damping rows' (the
  // unknowns'); v, w, x, atu in the preconditioned unknowns'; c_space is one of M's outputs.
  ColMat u_, av_, u_damped_, av_damped_, v_, w_, x_, atu_, c_space_;
};

}  // namespace hnn::nn::sampled
