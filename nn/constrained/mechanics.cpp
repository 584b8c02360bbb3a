#include "nn/constrained/mechanics.h"

#include <Eigen/Cholesky>

#include "autodiff/ops.h"

namespace hnn::nn {

namespace {

using Eigen::Index;

// C x N: +1 at a constraint's first point, -1 at a link's second point.
Eigen::MatrixXd signed_incidence(const ConstraintSpec& spec) {
  Eigen::MatrixXd b = Eigen::MatrixXd::Zero(spec.constraints(), spec.points);
  Index c = 0;
  for (const Link& link : spec.links) {
    b(c, link.i) = 1;
    b(c++, link.j) = -1;
  }
  for (const Anchor& anchor : spec.anchors) b(c++, anchor.i) = 1;
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

// (C d)^2 x C^2: S = outer(E, E) * gram has S_cc' = B_cc' sum_k e_c[k] e_c'[k].
Eigen::MatrixXd gram_operator(const Eigen::MatrixXd& b, Index d) {
  const Index c_count = b.rows(), width = c_count * d;
  Eigen::MatrixXd gram = Eigen::MatrixXd::Zero(width * width, c_count * c_count);
  for (Index c = 0; c < c_count; ++c)
    for (Index c2 = 0; c2 < c_count; ++c2)
      for (Index k = 0; k < d; ++k)
        gram((c * d + k) * width + c2 * d + k, c * c_count + c2) = b(c, c2);
  return gram;
}

template <typename T>
ad::Var<T> constant(const Matrix<T>& m) {
  return ad::Var<T>::constant(m);
}

}  // namespace

template <typename T>
struct ConstrainedMechanics<T>::Geometry {
  ad::Var<T> x, v;         // R x N d
  ad::Var<T> e, w;         // R x C d: e_c and w_c = de_c/dt
  ad::Var<T> gram;         // the constant (C d)^2 x C^2 operator
  ad::Var<T> s;            // R x C^2: S = G M^-1 G^T
  ad::Var<T> to_velocity;  // the constant M^-1 D^T, N d x C d
};

template <typename T>
ConstrainedMechanics<T>::ConstrainedMechanics(const ConstraintSpec& spec) : spec_(spec) {
  validate(spec_);
  const Index d = spec_.dim, width = spec_.constraints() * d;
  const Eigen::MatrixXd b = signed_incidence(spec_);
  const Eigen::MatrixXd minv = symmetric_inverse(spec_.mass);
  const Eigen::MatrixXd b_gram = b * minv * b.transpose();
  const Eigen::MatrixXd incidence = per_axis(b, d).transpose(), inverse = per_axis(minv, d);
  mass_ = per_axis(spec_.mass, d).cast<T>();
  inverse_ = inverse.cast<T>();
  incidence_ = incidence.cast<T>();
  inverse_incidence_ = (inverse * incidence).cast<T>();
  anchors_ = Matrix<T>::Zero(1, width);
  for (std::size_t a = 0; a < spec_.anchors.size(); ++a)
    for (Index k = 0; k < d; ++k)
      anchors_(0, (Index(spec_.links.size() + a)) * d + k) =
          T(spec_.anchors[a].point[std::size_t(k)]);
  group_ = Matrix<T>::Zero(width, spec_.constraints());
  for (Index c = 0; c < spec_.constraints(); ++c)
    for (Index k = 0; k < d; ++k) group_(c * d + k, c) = T(1);
  gram_ = gram_operator(0.5 * (b_gram + b_gram.transpose()), d).cast<T>();
}

template <typename T>
typename ConstrainedMechanics<T>::Geometry ConstrainedMechanics<T>::geometry(
    const ad::Var<T>& z) const {
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
  if (!spec_.anchors.empty()) g.e = g.e - constant(anchors_);
  g.w = ad::matmul(g.v, incidence);
  g.gram = constant(gram_);
  g.s = ad::matmul(ad::batched_outer(g.e, g.e), g.gram);
  g.to_velocity = constant(inverse_incidence_);
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
ad::Var<T> ConstrainedMechanics<T>::hamiltonian_field(const ad::Var<T>& z,
                                                      const ad::Var<T>& dv) const {
  const Geometry g = geometry(z);
  const ad::Var<T> free_acceleration = -ad::matmul(dv, constant(inverse_));
  if (spec_.constraints() == 0) return ad::concat_cols<T>({g.v, free_acceleration});
  // DPsi f = (r1, r2) = (G v, Gdot v - G M^-1 dV).
  const ad::Var<T> r1 = group(g.e * g.w);
  const ad::Var<T> r2 = group(g.w * g.w - g.e * ad::matmul(dv, g.to_velocity));
  const ad::Var<T> k =
      ad::matmul(ad::batched_outer(g.w, g.e) - ad::batched_outer(g.e, g.w), g.gram);
  const ad::Var<T> nu = ad::batched_spd_solve(g.s, r1);  // S nu = r1
  const ad::Var<T> mu = ad::batched_spd_solve(g.s, ad::batched_matvec(k, nu) - r2);
  // z' = f - J DPsi^T (mu, nu): x' = v - M^-1 G^T nu, p' = -dV + G^T mu + Gdot^T nu.
  const ad::Var<T> nu_e = g.e * expand(nu);
  const ad::Var<T> x_dot = g.v - ad::matmul(nu_e, g.to_velocity, false, true);
  const ad::Var<T> v_dot = free_acceleration + ad::matmul(g.e * expand(mu) + g.w * expand(nu),
                                                          g.to_velocity, false, true);
  return ad::concat_cols<T>({x_dot, v_dot});
}

template <typename T>
ad::Var<T> ConstrainedMechanics<T>::lagrangian_field(const ad::Var<T>& z,
                                                     const ad::Var<T>& dv) const {
  const Geometry g = geometry(z);
  const ad::Var<T> free_acceleration = -ad::matmul(dv, constant(inverse_));
  if (spec_.constraints() == 0) return ad::concat_cols<T>({g.v, free_acceleration});
  const ad::Var<T> rhs = group(g.w * g.w - g.e * ad::matmul(dv, g.to_velocity));
  const ad::Var<T> lambda = ad::batched_spd_solve(g.s, rhs);
  const ad::Var<T> a =
      free_acceleration - ad::matmul(g.e * expand(lambda), g.to_velocity, false, true);
  return ad::concat_cols<T>({g.v, a});
}

template <typename T>
Matrix<T> ConstrainedMechanics<T>::kinetic_energy(const Matrix<T>& v) const {
  return (T(0.5) * (v * mass_).cwiseProduct(v).rowwise().sum()).eval();
}

template class ConstrainedMechanics<float>;
template class ConstrainedMechanics<double>;

}  // namespace hnn::nn
