#pragma once
// The constrained equations of motion of a ConstraintSpec (nn/constrained/constraints.h), given
// the potential's gradient: the Hamiltonian form of Finzi, Wang & Wilson 2020 (CHNN: the
// unconstrained field J dH projected onto the tangent space of Psi(z) = (Phi(x), DPhi M^-1 p) = 0)
// and the Lagrangian one (CLNN: M a = -dV/dx - DPhi^T lambda with d^2 Phi / dt^2 = 0). Both are
// written in ad ops on a batch of states, so training differentiates through them to any order.
//
// Note [Constraint blocks]. Each constraint block is a d-vector linear in x, e_b = x_i - x_j (a
// link), x_i - a (an anchor) or sum_j w_j x_j - a (a pin), so e = x D^T - a with D the blocks'
// incidence on the points (+-1, or a pin's weights) times I_d, a constant. A link or an anchor is
// one constraint phi_c = (|e_c|^2 - l_c^2) / 2, a pin d constraints e_p = 0. Per state, with E the
// rows e_c and W = v D^T the rows w_c = de_c/dt (a pin's E is 1 and its W 0 in the formulas):
//   G = DPhi, (G u)_c = e_c . (D u)_c, a pin's rows (D u)_p;  Gdot, (Gdot u)_c = w_c . (D u)_c;
//   S = G M^-1 G^T, S_cc' = B_cc' e_c . e_c',  B = D M^-1 D^T per block (blocks x blocks),
// so the Gram blocks are one batched outer product of E times a constant: no Jacobian is formed.

#include "nn/constrained/constraints.h"
#include "nn/module.h"

namespace hnn::nn {

template <typename T>
class ConstrainedMechanics {
 public:
  /// Validates `spec` (std::invalid_argument) and forms its constant operators; with
  /// spec.learned_masses also the basis of M^-1 (nn/constrained/masses.h).
  explicit ConstrainedMechanics(const ConstraintSpec& spec);

  /// The operators through which M^-1 enters the fields, all linear in it: M^-1 (x) I_d
  /// (N d x N d), M^-1 D^T (N d x blocks d) and the Gram operator of S (see gram_operator).
  struct MassOperators {
    ad::Var<T> inverse, to_velocity, gram;
  };
  /// The spec's masses, as constants.
  MassOperators known_masses() const;
  /// M^-1 = sum_k c_k B_k for c (1 x K, on the tape: gradients reach it), B_k the
  /// spec's inverse_mass_basis. Needs spec.learned_masses.
  MassOperators learned_masses(const ad::Var<T>& c) const;
  /// K, the size of c (0 unless spec.learned_masses).
  Eigen::Index mass_coefficients() const { return Eigen::Index(point_basis_.size()); }
  /// M (x) I_d for coefficients c (values), to weigh kinetic energies.
  Matrix<T> mass_matrix(const Matrix<T>& c) const;

  /// The CHNN field in (x, v) coordinates for states z (R x 2 N d) and dV/dx (R x N d):
  /// z' = f - J DPsi^T (DPsi J DPsi^T)^-1 DPsi f in (x, p = M v), f = J dH, then v' = M^-1 p'.
  /// DPsi J DPsi^T = [[0, S], [-S, K]], K = Gdot M^-1 G^T - G M^-1 Gdot^T, is solved by two SPD
  /// solves of S (ad::batched_spd_solve). On the constraint manifold x' = v; off it, x' is
  /// projected too, and DPsi z' = 0 still holds.
  ad::Var<T> hamiltonian_field(const ad::Var<T>& z, const ad::Var<T>& dv,
                               const MassOperators& masses) const;
  /// The CLNN field (v, a): M a = -dV/dx - G^T lambda, lambda = S^-1 (Gdot v - G M^-1 dV/dx), so
  /// that G a + Gdot v = 0. Equal to hamiltonian_field on the constraint manifold.
  ad::Var<T> lagrangian_field(const ad::Var<T>& z, const ad::Var<T>& dv,
                              const MassOperators& masses) const;

  /// The kinetic energy 1/2 sum_k v[:, k]^T M v[:, k], R x 1 (values), for M (x) I_d = `mass`:
  /// mass() or a mass_matrix(c).
  static Matrix<T> kinetic_energy(const Matrix<T>& v, const Matrix<T>& mass);
  /// The spec's M (x) I_d.
  const Matrix<T>& mass() const { return mass_; }

  const ConstraintSpec& spec() const { return spec_; }

 private:
  struct Geometry;  // E, W and the Gram blocks of one batch
  Geometry geometry(const ad::Var<T>& z, const MassOperators& masses) const;
  ad::Var<T> group(const ad::Var<T>& y) const;   // R x blocks d -> R x C: sums a distance's axes
  ad::Var<T> expand(const ad::Var<T>& l) const;  // R x C -> R x blocks d: its adjoint

  ConstraintSpec spec_;
  Matrix<T> mass_;               // M (x) I_d, N d x N d
  Matrix<T> inverse_;            // M^-1 (x) I_d, N d x N d
  Matrix<T> incidence_;          // D^T without the pins' columns, N d x blocks d: E and W
  Matrix<T> full_incidence_;     // D^T, N d x blocks d
  Matrix<T> inverse_incidence_;  // M^-1 D^T, N d x blocks d
  Matrix<T> offsets_;            // 1 x blocks d: an anchor's point, -1 on a pin's axes (E = 1)
  Matrix<T> group_;  // blocks d x C: 1 where block b's axis k meets its constraint's row
  Matrix<T> gram_;   // (blocks d)^2 x C^2: see gram_operator in mechanics.cpp
  // With learned masses: row k holds inverse_, inverse_incidence_ and gram_ of B_k, flattened
  // column-major, so that c times them is each operator at M^-1 = sum_k c_k B_k.
  Matrix<T> inverse_basis_, to_velocity_basis_, gram_basis_;
  std::vector<Eigen::MatrixXd> point_basis_;  // B_k, N x N
};

}  // namespace hnn::nn
