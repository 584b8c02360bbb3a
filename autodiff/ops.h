#pragma once
// The differentiable ops. Each is documented with its derivative; each backward is written in
// these same ops, so derivatives of any order can be recorded.
//
// Broadcasting (binary elementwise ops): an operand may be the full shape, a row vector (1xC,
// one value per feature, repeated over the batch), a column (Rx1), or a scalar (1x1). The
// gradient of a broadcast operand is summed back to its shape (sum_to).

#include <initializer_list>
#include <limits>
#include <type_traits>
#include <vector>

#include "autodiff/var.h"

namespace hnn::ad {

// ---- elementwise arithmetic (broadcasting) ---------------------------------------------------
template <typename T>
Var<T> add(const Var<T>& a, const Var<T>& b);  // d/da = 1, d/db = 1
template <typename T>
Var<T> sub(const Var<T>& a, const Var<T>& b);  // 1, -1
template <typename T>
Var<T> mul(const Var<T>& a, const Var<T>& b);  // b, a
template <typename T>
Var<T> div(const Var<T>& a, const Var<T>& b);  // 1/b, -a/b^2
template <typename T>
Var<T> neg(const Var<T>& a);  // -1
template <typename T>
Var<T> scale(const Var<T>& a, std::type_identity_t<T> s);  // s * a: d = s
template <typename T>
Var<T> shift(const Var<T>& a, std::type_identity_t<T> s);  // a + s: d = 1

// ---- elementwise functions -------------------------------------------------------------------
template <typename T>
Var<T> square(const Var<T>& x);  // 2x
template <typename T>
Var<T> pow(const Var<T>& x, std::type_identity_t<T> exponent);  // e x^(e-1)
template <typename T>
Var<T> sqrt(const Var<T>& x);  // 1 / (2 sqrt x)
template <typename T>
Var<T> exp(const Var<T>& x);  // exp x
template <typename T>
Var<T> log(const Var<T>& x);  // 1 / x
template <typename T>
Var<T> sin(const Var<T>& x);  // cos x
template <typename T>
Var<T> cos(const Var<T>& x);  // -sin x
template <typename T>
Var<T> tanh(const Var<T>& x);  // 1 - tanh^2 x (fused, below)
template <typename T>
Var<T> sigmoid(const Var<T>& x);  // s (1 - s)
template <typename T>
Var<T> relu(const Var<T>& x);  // step(x)
template <typename T>
Var<T> softplus(const Var<T>& x);  // sigmoid x
template <typename T>
Var<T> elu(const Var<T>& x, std::type_identity_t<T> alpha = T(1));  // 1 | alpha exp x
template <typename T>
Var<T> selu(const Var<T>& x);  // scale * elu(x, alpha)
template <typename T>
Var<T> swish(const Var<T>& x);  // x sigmoid x (composite)

/// Gradient of tanh given its output y: g * (1 - y^2). Itself differentiable in g and y
/// (d/dg = 1 - y^2, d/dy = -2 y g), which is what makes HNN training fast and exact.
template <typename T>
Var<T> tanh_backward(const Var<T>& g, const Var<T>& y);

/// The step function x > 0 as a constant mask (its derivative is zero almost everywhere).
template <typename T>
Var<T> step(const Var<T>& x);

// ---- linear algebra --------------------------------------------------------------------------
/// op(a) op(b), op = transpose when the flag is set; transposes are never materialised.
template <typename T>
Var<T> matmul(const Var<T>& a, const Var<T>& b, bool transpose_a = false, bool transpose_b = false);
template <typename T>
Var<T> transpose(const Var<T>& a);
/// Fused layer x W + b (b a 1xC row, optional: pass an empty Var). d/dx = g W^T,
/// d/dW = x^T g, d/db = sum_rows g.
template <typename T>
Var<T> linear(const Var<T>& x, const Var<T>& w, const Var<T>& b = {});

// ---- batched small linear algebra: one block per row of the batch -------------------------
// Row r of `a` holds a small matrix A_r flattened row-major (n x n: R x n^2), row r of a vector
// operand holds v_r. These are the per-sample Hessian blocks of a Lagrangian network.

/// batched_solve refuses a block whose reciprocal condition number 1 / (|A|_1 |A^-1|_1) is below
/// this (exact for blocks up to 4x4, Eigen's estimate above): 100 epsilons, 2.2e-14 in double
/// and 1.2e-5 in float. A solve's relative error is about eps / rcond, so below it fewer than two
/// digits of the solution are right and a NaN-free result would be a lie. (It was 1000 epsilons,
/// which refused float solves that still had three digits: a mass HNN's M^-1 = L L^T + 1e-4 I is
/// invertible by construction, yet its rcond falls below 1.2e-4 once L is degenerate in one
/// direction, and their float32 code solves it on. The gyroscope's seed 0 stopped at step 662 at
/// rcond 1.08e-4.)
template <typename T>
inline constexpr T kBatchedSolveMinRcond = T(100) * std::numeric_limits<T>::epsilon();

/// X (R x n) with A_r x_r = b_r, or A_r^T x_r = b_r with transpose_a; b is R x n, a is R x n^2.
/// Partial-pivot LU per row. Derivatives: d/db = batched_solve(a, g, !transpose_a), the
/// adjoint solve gb; d/da = -batched_outer(gb, x) (-batched_outer(x, gb) with transpose_a).
/// Throws hnn::ad::Error naming the row of a block that is singular, ill-conditioned
/// (kBatchedSolveMinRcond) or not finite, or of a non-finite right-hand side.
template <typename T>
Var<T> batched_solve(const Var<T>& a, const Var<T>& b, bool transpose_a = false);

/// op(A_r) v_r per row, v R x n. a is R x (k n): A_r is k x n, or n x k used transposed (k = n,
/// the square case, in the Lagrangian network; rectangular blocks are the gradient of
/// batched_outer). Derivatives: d/dv = batched_matvec(a, g, !transpose_a); d/da =
/// batched_outer(g, v) (batched_outer(v, g) with transpose_a).
template <typename T>
Var<T> batched_matvec(const Var<T>& a, const Var<T>& v, bool transpose_a = false);

/// u_r v_r^T per row, flattened row-major: R x n and R x m -> R x (n m). Derivatives (G_r the
/// n x m gradient block): d/du = batched_matvec(g, v) = G_r v_r, d/dv = batched_matvec(g, u,
/// true) = G_r^T u_r.
template <typename T>
Var<T> batched_outer(const Var<T>& u, const Var<T>& v);

/// X (R x n) with sym(A_r) x_r = b_r, sym(A) = (A + A^T) / 2 symmetric positive definite (the
/// Gram blocks G M^-1 G^T of constrained mechanics, nn/constrained/): Cholesky per row, half the
/// work of batched_solve's LU and allocation-free at any n. Reading only sym(A) keeps the
/// derivative exact for any input: d/db = gb = batched_spd_solve(a, g); d/da = -(batched_outer(gb,
/// x) + batched_outer(x, gb)) / 2. Throws hnn::ad::Error naming the row of a block that is not
/// finite, not positive definite, or whose 1-norm rcond is below kBatchedSolveMinRcond (computed
/// exactly from the inverse; `min_rcond` lowers it for a caller whose solution's error the
/// result does not carry, see MassHnn), or of a non-finite right-hand side.
template <typename T>
Var<T> batched_spd_solve(const Var<T>& a, const Var<T>& b,
                         double min_rcond = double(kBatchedSolveMinRcond<T>));
/// The same solve for another right-hand side, reusing the factors of `factored`, an earlier
/// batched_spd_solve(a, .) of this very `a` (checked: it throws otherwise). Constrained
/// mechanics solves S twice per field, and every solve's backward solves it once more.
template <typename T>
Var<T> batched_spd_solve_factored(const Var<T>& a, const Var<T>& b, const Var<T>& factored);

// ---- reductions and shapes -------------------------------------------------------------------
template <typename T>
Var<T> sum(const Var<T>& a);  // -> 1x1
template <typename T>
Var<T> mean(const Var<T>& a);  // -> 1x1
template <typename T>
Var<T> sum_rows(const Var<T>& a);  // sum over the batch -> 1xC
template <typename T>
Var<T> sum_cols(const Var<T>& a);  // sum over features -> Rx1
template <typename T>
Var<T> mean_rows(const Var<T>& a);
template <typename T>
Var<T> mean_cols(const Var<T>& a);
/// Repeats a row, column or scalar to rows x cols (the adjoint of sum_to).
template <typename T>
Var<T> broadcast_to(const Var<T>& a, Eigen::Index rows, Eigen::Index cols);
/// Sums a to rows x cols, where each target dimension is a's or 1 (the adjoint of broadcast_to).
template <typename T>
Var<T> sum_to(const Var<T>& a, Eigen::Index rows, Eigen::Index cols);
/// Columns [start, start + count).
template <typename T>
Var<T> slice_cols(const Var<T>& a, Eigen::Index start, Eigen::Index count);
/// a placed at columns [start, start + a.cols()) of a zero matrix with `cols` columns.
template <typename T>
Var<T> pad_cols(const Var<T>& a, Eigen::Index start, Eigen::Index cols);
/// The same entries as rows x cols, in column-major order (Eigen's reshaped()): a row of
/// rows * cols numbers becomes a matrix column by column.
template <typename T>
Var<T> reshape(const Var<T>& a, Eigen::Index rows, Eigen::Index cols);
template <typename T>
Var<T> concat_cols(const std::vector<Var<T>>& parts);
/// concat_cols of a braced list, e.g. concat_cols<T>({q, p}): no vector is built (a warmed-up
/// step allocates nothing).
template <typename T>
Var<T> concat_cols(std::initializer_list<Var<T>> parts);

// ---- operators -------------------------------------------------------------------------------
template <typename T>
Var<T> operator+(const Var<T>& a, const Var<T>& b) {
  return add(a, b);
}
template <typename T>
Var<T> operator-(const Var<T>& a, const Var<T>& b) {
  return sub(a, b);
}
template <typename T>
Var<T> operator*(const Var<T>& a, const Var<T>& b) {
  return mul(a, b);
}
template <typename T>
Var<T> operator/(const Var<T>& a, const Var<T>& b) {
  return div(a, b);
}
template <typename T>
Var<T> operator-(const Var<T>& a) {
  return neg(a);
}
template <typename T>
Var<T> operator*(const Var<T>& a, std::type_identity_t<T> s) {
  return scale(a, s);
}
template <typename T>
Var<T> operator*(std::type_identity_t<T> s, const Var<T>& a) {
  return scale(a, s);
}
template <typename T>
Var<T> operator/(const Var<T>& a, std::type_identity_t<T> s) {
  return scale(a, T(1) / s);
}
template <typename T>
Var<T> operator+(const Var<T>& a, std::type_identity_t<T> s) {
  return shift(a, s);
}
template <typename T>
Var<T> operator+(std::type_identity_t<T> s, const Var<T>& a) {
  return shift(a, s);
}
template <typename T>
Var<T> operator-(const Var<T>& a, std::type_identity_t<T> s) {
  return shift(a, -s);
}
template <typename T>
Var<T> operator-(std::type_identity_t<T> s, const Var<T>& a) {
  return shift(neg(a), s);
}

}  // namespace hnn::ad
