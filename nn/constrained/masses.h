#pragma once
// Learned masses, as Finzi et al.'s CHNN and CLNN learn them (their CH.d_moments): the inverse
// mass matrix of point masses and rigid bodies is a sum of fixed basis matrices with positive
// coefficients, M^-1 = sum_k c_k B_k, c_k = exp(-theta_k), theta learned.
// - A point mass i: B = e_i e_i^T, c = 1 / m_i.
// - A rigid body of d + 1 points, its centre c and one point per principal axis j (as
//   physics/constrained/rigid_bodies.h builds it, M = [[m + sum I, -I_j], [-I_j, diag I_j]]):
//   B = 1 1^T over its points with c = 1 / m, and B = e_j e_j^T with c = 1 / I_j.

#include <Eigen/Core>
#include <vector>

#include "nn/constrained/constraints.h"

namespace hnn::nn {

/// The basis of spec.mass's inverse, body by body in the order of their first points, each
/// N x N. Throws std::invalid_argument when spec.mass is not made of point masses and rigid
/// bodies (a body whose points are coupled other than through one centre, or whose inverse is
/// not a positive sum of the basis).
std::vector<Eigen::MatrixXd> inverse_mass_basis(const ConstraintSpec& spec);

/// The coefficients c (size K) with sum_k c_k B_k = spec.mass^-1, all > 0: the true values of
/// what a model with learned masses learns. Throws as inverse_mass_basis does.
Eigen::VectorXd inverse_mass_coefficients(const ConstraintSpec& spec);

/// How far the mass matrix `mass` is from `truth` (both M (x) I_d, N d x N d: ConstrainedMechanics'
/// mass_matrix and mass) where the motion can tell: on the tangent space of the position
/// constraints at each row of `positions` (R x N d), the reduced mass matrices T^T M T (T an
/// orthonormal basis of the tangent space), compared after the one best scale for all rows (M and
/// V scaled together move alike): sqrt(sum_r |a M_r - M_r(truth)|^2 / sum_r |M_r(truth)|^2).
/// Zero for masses that move the system as the truth does: a pinned rigid body's mass and
/// moments, say, matter only through its inertia about the pivot. Throws std::invalid_argument
/// for shapes that do not fit the spec.
double tangent_mass_error(const ConstraintSpec& spec, const Eigen::MatrixXd& mass,
                          const Eigen::MatrixXd& truth, const Eigen::MatrixXd& positions);

}  // namespace hnn::nn
