#include "nn/constrained/mechanics.h"

#include <fmt/format.h>

#include <Eigen/Cholesky>
#include <stdexcept>

#include "autodiff/ops.h"
#include "nn/constrained/masses.h"

namespace hnn::nn {

namespace {

using Eigen::Index;

// Block b's axis k is the constraint row(b, k): a link's or an anchor's one row for all its axes
// (phi = |e|^2 / 2), a pin's own row per axis (e = 0).
struct BlockRows {
  Index distances, d;
  Index row(Index b, Index k) const {
    return b < distances ? b : distances + (b - distances) * d + k;
  }
};

BlockRows block_rows(const ConstraintSpec& spec) {
  return {Index(spec.links.size() + spec.anchors.size()), spec.dim};
}

// blocks x N: e_b = sum_j b(b, j) x_j - offset_b. +1 at a distance's first point, -1 at a link's
// second; a pin's weights, or zeros (`with_pins` false: a pin's e is a constant, and Gdot's rows
// for it vanish).
Eigen::MatrixXd incidence(const ConstraintSpec& spec, bool with_pins) {
  Eigen::MatrixXd b = Eigen::MatrixXd::Zero(spec.blocks(), spec.points);
  Index c = 0;
  for (const Link& link : spec.links) {
    b(c, link.i) = 1;
    b(c++, link.j) = -1;
  }
  for (const Anchor& anchor : spec.anchors) b(c++, anchor.i) = 1;
  for (const Pin& pin : spec.pins) {
    if (with_pins) b.row(c) = Eigen::Map<const Eigen::RowVectorXd>(pin.weights.data(), spec.points);
    ++c;
  }
  return b;
}

// a (x) I_d in the point-major layout of a state (point i's axis k at i d + k).
Eigen::MatrixXd per_axis(const Eigen::MatrixXd& a, Index d) {
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(a.rows() * d, a.cols() * d);
  for (Index i = 0; i < a.rows(); ++i)
    for (Index j = 0; j < a.cols(); ++j)
      for (Index k = 0; k < d; ++k) out(i * d + k, j * d + k) = a(i, j);
  return out;
}

Eigen::MatrixXd symmetric_inverse(const Eigen::MatrixXd& m) {
  const Eigen::MatrixXd inverse = m.llt().solve(Eigen::MatrixXd::Identity(m.rows(), m.cols()));
  return (0.5 * (inverse + inverse.transpose())).eval();
}

// (blocks d)^2 x C^2: S = outer(E, E) * gram has S(row(b, k), row(b', k)) += B_bb' e_b[k] e_b'[k],
// where a pin's e is 1 on every axis: e_c . e_c' B_cc' between distances, e_c[k] B_cp between a
// distance and a pin's axis k, B_pp' between a pin's and another's same axis.
Eigen::MatrixXd gram_operator(const Eigen::MatrixXd& b_gram, const BlockRows& rows, Index c_count) {
  const Index blocks = b_gram.rows(), d = rows.d, width = blocks * d;
  Eigen::MatrixXd gram = Eigen::MatrixXd::Zero(width * width, c_count * c_count);
  for (Index b = 0; b < blocks; ++b)
    for (Index b2 = 0; b2 < blocks; ++b2)
      for (Index k = 0; k < d; ++k)
        gram((b * d + k) * width + b2 * d + k, rows.row(b, k) * c_count + rows.row(b2, k)) =
            b_gram(b, b2);
  return gram;
}

// The operators through which M^-1 (N x N) enters the fields; each linear in M^-1.
struct MassMatrices {
  Eigen::MatrixXd inverse, to_velocity, gram;
};

MassMatrices mass_matrices(const Eigen::MatrixXd& minv, const Eigen::MatrixXd& b,
                           const BlockRows& rows, Index c_count) {
  const Eigen::MatrixXd b_gram = b * minv * b.transpose(), inverse = per_axis(minv, rows.d);
  return {inverse, inverse * per_axis(b, rows.d).transpose(),
          gram_operator(0.5 * (b_gram + b_gram.transpose()), rows, c_count)};
}

// Row k: basis[k]'s operator `part`, flattened column-major.
template <typename T>
Matrix<T> flattened(const std::vector<MassMatrices>& basis, Eigen::MatrixXd MassMatrices::*part) {
  const Eigen::MatrixXd& first = basis.front().*part;
  Matrix<T> out(Index(basis.size()), first.size());
  for (std::size_t k = 0; k < basis.size(); ++k)
    out.row(Index(k)) = (basis[k].*part).reshaped().transpose().template cast<T>();
  return out;
}

template <typename T>
ad::Var<T> constant(const Matrix<T>& m) {
  return ad::Var<T>::constant(m);
}

}  // namespace

template <typename T>
struct ConstrainedMechanics<T>::Geometry {
  ad::Var<T> x, v;  // R x N d
  ad::Var<T> e, w;  // R x blocks d: e_b and w_b = de_b/dt
  ad::Var<T> s;     // R x C^2: S = G M^-1 G^T
};

template <typename T>
ConstrainedMechanics<T>::ConstrainedMechanics(const ConstraintSpec& spec) : spec_(spec) {
  validate(spec_);
  const Index d = spec_.dim, c_count = spec_.constraints();
  const BlockRows rows = block_rows(spec_);
  const Eigen::MatrixXd b = incidence(spec_, true);
  const MassMatrices known = mass_matrices(symmetric_inverse(spec_.mass), b, rows, c_count);
  mass_ = per_axis(spec_.mass, d).cast<T>();
  inverse_ = known.inverse.cast<T>();
  incidence_ = per_axis(incidence(spec_, false), d).transpose().cast<T>();
  full_incidence_ = per_axis(b, d).transpose().cast<T>();
  inverse_incidence_ = known.to_velocity.cast<T>();
  gram_ = known.gram.cast<T>();
  offsets_ = Matrix<T>::Zero(1, spec_.blocks() * d);
  group_ = Matrix<T>::Zero(spec_.blocks() * d, c_count);
  for (Index block = 0; block < spec_.blocks(); ++block) {
    const Index anchor = block - Index(spec_.links.size());  // an anchor's index when >= 0
    for (Index k = 0; k < d; ++k) {
      if (block >= rows.distances)
        offsets_(0, block * d + k) = T(-1);  // a pin's e is 1
      else if (anchor >= 0)
        offsets_(0, block * d + k) = T(spec_.anchors[std::size_t(anchor)].point[std::size_t(k)]);
      group_(block * d + k, rows.row(block, k)) = T(1);
    }
  }
  if (!spec_.learned_masses) return;
  point_basis_ = inverse_mass_basis(spec_);
  std::vector<MassMatrices> basis;
  for (const Eigen::MatrixXd& b_k : point_basis_)
    basis.push_back(mass_matrices(b_k, b, rows, c_count));
  inverse_basis_ = flattened<T>(basis, &MassMatrices::inverse);
  to_velocity_basis_ = flattened<T>(basis, &MassMatrices::to_velocity);
  gram_basis_ = flattened<T>(basis, &MassMatrices::gram);
}

template <typename T>
typename ConstrainedMechanics<T>::MassOperators ConstrainedMechanics<T>::known_masses() const {
  return {constant(inverse_), constant(inverse_incidence_), constant(gram_)};
}

template <typename T>
typename ConstrainedMechanics<T>::MassOperators ConstrainedMechanics<T>::learned_masses(
    const ad::Var<T>& c) const {
  HNN_AD_CHECK(spec_.learned_masses && c.rows() == 1 && c.cols() == mass_coefficients(),
               "constrained masses: coefficients {} for {} learned masses", c.shape(),
               mass_coefficients());
  const auto combine = [&](const Matrix<T>& basis, const Matrix<T>& like) {
    return ad::reshape(ad::matmul(c, constant(basis)), like.rows(), like.cols());
  };
  return {combine(inverse_basis_, inverse_), combine(to_velocity_basis_, inverse_incidence_),
          combine(gram_basis_, gram_)};
}

template <typename T>
Matrix<T> ConstrainedMechanics<T>::mass_matrix(const Matrix<T>& c) const {
  if (c.rows() != 1 || c.cols() != mass_coefficients()) {
    throw std::invalid_argument(
        fmt::format("constrained masses: coefficients {}x{} for {} learned masses", c.rows(),
                    c.cols(), mass_coefficients()));
  }
  Eigen::MatrixXd minv = Eigen::MatrixXd::Zero(spec_.points, spec_.points);
  for (std::size_t k = 0; k < point_basis_.size(); ++k)
    minv += double(c(0, Index(k))) * point_basis_[k];
  return per_axis(symmetric_inverse(minv), spec_.dim).cast<T>();
}

template <typename T>
typename ConstrainedMechanics<T>::Geometry ConstrainedMechanics<T>::geometry(
    const ad::Var<T>& z, const MassOperators& masses) const {
  const Index n = spec_.positions();
  HNN_AD_CHECK(z.cols() == 2 * n,
               "constrained field: states {} are not R x {} (x then v of {} "
               "points in {} dimensions)",
               z.shape(), 2 * n, spec_.points, spec_.dim);
  Geometry g;
  g.x = ad::slice_cols(z, 0, n);
  g.v = ad::slice_cols(z, n, n);
  const ad::Var<T> incidence = constant(incidence_);
  g.e = ad::matmul(g.x, incidence);
  if (!spec_.anchors.empty() || !spec_.pins.empty()) g.e = g.e - constant(offsets_);
  g.w = ad::matmul(g.v, incidence);
  g.s = ad::matmul(ad::batched_outer(g.e, g.e), masses.gram);
  return g;
}

template <typename T>
ad::Var<T> ConstrainedMechanics<T>::group(const ad::Var<T>& y) const {
  return ad::matmul(y, constant(group_));
}

template <typename T>
ad::Var<T> ConstrainedMechanics<T>::expand(const ad::Var<T>& l) const {
  return ad::matmul(l, constant(group_), false, true);
}

template <typename T>
ad::Var<T> ConstrainedMechanics<T>::hamiltonian_field(const ad::Var<T>& z, const ad::Var<T>& dv,
                                                      const MassOperators& masses) const {
  const Geometry g = geometry(z, masses);
  const ad::Var<T> free_acceleration = -ad::matmul(dv, masses.inverse);
  if (spec_.constraints() == 0) return ad::concat_cols<T>({g.v, free_acceleration});
  // DPsi f = (r1, r2) = (G v, Gdot v - G M^-1 dV). A pin's G v is its e's rate, which w leaves
  // out (its Gdot is zero).
  const ad::Var<T> rate = spec_.pins.empty() ? g.w : ad::matmul(g.v, constant(full_incidence_));
  const ad::Var<T> r1 = group(g.e * rate);
  const ad::Var<T> r2 = group(g.w * g.w - g.e * ad::matmul(dv, masses.to_velocity));
  const ad::Var<T> k =
      ad::matmul(ad::batched_outer(g.w, g.e) - ad::batched_outer(g.e, g.w), masses.gram);
  const ad::Var<T> nu = ad::batched_spd_solve(g.s, r1);  // S nu = r1
  const ad::Var<T> mu = ad::batched_spd_solve_factored(g.s, ad::batched_matvec(k, nu) - r2, nu);
  // z' = f - J DPsi^T (mu, nu): x' = v - M^-1 G^T nu, p' = -dV + G^T mu + Gdot^T nu.
  const ad::Var<T> nu_e = g.e * expand(nu);
  const ad::Var<T> x_dot = g.v - ad::matmul(nu_e, masses.to_velocity, false, true);
  const ad::Var<T> v_dot = free_acceleration + ad::matmul(g.e * expand(mu) + g.w * expand(nu),
                                                          masses.to_velocity, false, true);
  return ad::concat_cols<T>({x_dot, v_dot});
}

template <typename T>
ad::Var<T> ConstrainedMechanics<T>::lagrangian_field(const ad::Var<T>& z, const ad::Var<T>& dv,
                                                     const MassOperators& masses) const {
  const Geometry g = geometry(z, masses);
  const ad::Var<T> free_acceleration = -ad::matmul(dv, masses.inverse);
  if (spec_.constraints() == 0) return ad::concat_cols<T>({g.v, free_acceleration});
  const ad::Var<T> rhs = group(g.w * g.w - g.e * ad::matmul(dv, masses.to_velocity));
  const ad::Var<T> lambda = ad::batched_spd_solve(g.s, rhs);
  const ad::Var<T> a =
      free_acceleration - ad::matmul(g.e * expand(lambda), masses.to_velocity, false, true);
  return ad::concat_cols<T>({g.v, a});
}

template <typename T>
Matrix<T> ConstrainedMechanics<T>::kinetic_energy(const Matrix<T>& v, const Matrix<T>& mass) {
  return (T(0.5) * (v * mass).cwiseProduct(v).rowwise().sum()).eval();
}

template class ConstrainedMechanics<float>;
template class ConstrainedMechanics<double>;

}  // namespace hnn::nn
