#pragma once
// The constrained equations of motion of a ConstraintSpec (nn/constrained/constraints.h), given
// the potential's gradient: the Hamiltonian form of Finzi, Wang & Wilson 2020 (CHNN: the
// unconstrained field J dH projected onto the tangent space of Psi(z) = (Phi(x), DPhi M^-1 p) = 0)
// and the Lagrangian one (CLNN: M a = -dV/dx - DPhi^T lambda with d^2 Phi / dt^2 = 0). Both are
// written in ad ops on a batch of states, so training differentiates through them to any order.
//
// Note [Distance constraints]. Each constraint is phi_c = (|e_c|^2 - l_c^2) / 2 with e_c = x_i -
// x_j (a link) or x_i - a (an anchor), so e = x D^T - a, D the signed incidence of the
// constraints on the points times I_d (constant). Then, per state, with E the rows e_c and
// W = v D^T the rows w_c = de_c/dt:
//   G = DPhi, (G u)_c = e_c . (D u)_c;     Gdot, (Gdot u)_c = w_c . (D u)_c;
//   S = G M^-1 G^T, S_cc' = B_cc' e_c . e_c';  B = (incidence) M^-1 (incidence)^T, C x C,
// so the Gram blocks are one batched outer product of E times a constant: no Jacobian is formed.

#include "nn/constrained/constraints.h"
#include "nn/module.h"

namespace hnn::nn {

template <typename T>
class ConstrainedMechanics {
 public:
  /// Validates `spec` (std::invalid_argument) and forms its constant operators.
  explicit ConstrainedMechanics(const ConstraintSpec& spec);

  /// The CHNN field in (x, v) coordinates for states z (R x 2 N d) and dV/dx (R x N d):
  /// z' = f - J DPsi^T (DPsi J DPsi^T)^-1 DPsi f in (x, p = M v), f = J dH, then v' = M^-1 p'.
  /// DPsi J DPsi^T = [[0, S], [-S, K]], K = Gdot M^-1 G^T - G M^-1 Gdot^T, is solved by two SPD
  /// solves of S (ad::batched_spd_solve). On the constraint manifold x' = v; off it, x' is
  /// projected too, and DPsi z' = 0 still holds.
  ad::Var<T> hamiltonian_field(const ad::Var<T>& z, const ad::Var<T>& dv) const;
  /// The CLNN field (v, a): M a = -dV/dx - G^T lambda, lambda = S^-1 (Gdot v - G M^-1 dV/dx), so
  /// that G a + Gdot v = 0. Equal to hamiltonian_field on the constraint manifold.
  ad::Var<T> lagrangian_field(const ad::Var<T>& z, const ad::Var<T>& dv) const;

  /// The kinetic energy 1/2 sum_k v[:, k]^T M v[:, k], R x 1 (values).
  Matrix<T> kinetic_energy(const Matrix<T>& v) const;

  const ConstraintSpec& spec() const { return spec_; }

 private:
  struct Geometry;  // E, W and the Gram blocks of one batch
  Geometry geometry(const ad::Var<T>& z) const;
  ad::Var<T> group(const ad::Var<T>& y) const;   // R x C d -> R x C: sum over each e_c's axes
  ad::Var<T> expand(const ad::Var<T>& l) const;  // R x C -> R x C d: l_c on each of e_c's axes

  ConstraintSpec spec_;
  Matrix<T> mass_;               // M (x) I_d, N d x N d
  Matrix<T> inverse_;            // M^-1 (x) I_d, N d x N d
  Matrix<T> incidence_;          // D^T, N d x C d
  Matrix<T> inverse_incidence_;  // M^-1 D^T, N d x C d
  Matrix<T> anchors_;            // a, 1 x C d (zero for links)
  Matrix<T> group_;              // C d x C: 1 where row c d + k meets column c
  Matrix<T> gram_;               // (C d)^2 x C^2: B_cc' where (c d + k, c' d + k) meets (c, c')
};

}  // namespace hnn::nn
