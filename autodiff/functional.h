#pragma once
// Derivatives of whole functions, built on grad(): Jacobians, Hessians, Hessian-vector products.
// Matrices are flattened row-major, the order the engine stores them in.

#include <functional>

#include "autodiff/grad.h"
#include "autodiff/var.h"

namespace hnn::ad {

template <typename T>
using VarFunction = std::function<Var<T>(const Var<T>&)>;

/// J[i][j] = d f(x)_i / d x_j, with f(x) and x flattened.
template <typename T>
Matrix<T> jacobian(const VarFunction<T>& f, const Matrix<T>& x);

/// The Hessian of a scalar f at x (x.size() x x.size()), by differentiating the gradient.
template <typename T>
Matrix<T> hessian(const VarFunction<T>& f, const Matrix<T>& x);

/// H(x) v for a scalar f, by one reverse-over-reverse pass (v has x's shape).
template <typename T>
Matrix<T> hvp(const VarFunction<T>& f, const Matrix<T>& x, const Matrix<T>& v);

// ---- row-wise derivatives of a batch of independent samples -----------------------------------

/// The per-row Jacobians of y = f(x) for a batch whose row r of y depends on row r of x only:
/// R x (m n), row r = dy_r / dx_r (m x n, flattened row-major; m = y.cols(), n = x.cols()).
/// Costs m reverse passes, one per column j of y, seeded with ones in that column. With
/// options.create_graph the result is on the tape and can be differentiated again;
/// options.allow_unused gives zeros for an x that y does not depend on.
///
/// The independence of the rows is the caller's promise, and is not checked (that would cost
/// the full R m x R n Jacobian). What is computed is, in every case, row r, entry (i, j) =
/// sum over rows r' of d y[r', i] / d x[r, j]: when rows are coupled (a batch norm, a mean over
/// the batch) the cross-row terms are silently summed into the blocks.
template <typename T>
Var<T> row_jacobian(const Var<T>& y, const Var<T>& x, const GradOptions& options = {});

/// The per-row Hessians of a batch of scalars l (R x 1), row r depending on row r of x only:
/// R x n^2, row r = d^2 l_r / dx_r^2 flattened row-major. row_jacobian of grad(l, x), with the
/// same independence assumption; the gradient is always recorded, the Hessian only with
/// options.create_graph. An l linear in x gives zero blocks.
template <typename T>
Var<T> row_hessian(const Var<T>& l, const Var<T>& x, const GradOptions& options = {});

}  // namespace hnn::ad
