#pragma once
// The solvers of the last layer's least-squares problem (LeastSquaresSolver in sampled_fit.h).

#include <string>

#include "nn/sampled/sampled_fit.h"
#include "nn/sampled/systems.h"

namespace hnn::nn::sampled {

struct LeastSquaresResult {
  ColMat c;                  // unknowns x m
  double gram_seconds = 0;   // A^T A (part of forming what the solver reads)
  double solve_seconds = 0;  // factorisation and iterations
  int iterations = 0;
  double regularization = 0;  // the lambda the Cholesky factorisation took
  double residual_rms = 0;    // |A c - B| / sqrt(equations * m)
  std::size_t bytes = 0;      // the solver's own matrices
};

/// The whole problem already reduced to a triangle (n x n) and its right-hand side (n x m): what
/// --rcond auto's validation leaves (rcond_choice.h), so the fit at the chosen cutoff need not
/// reduce the system again.
struct ReducedProblem {
  ColMat r, c;
  bool empty() const { return r.size() == 0; }
};

/// Solves min |A C - B| by config.solver; throws std::invalid_argument when the system is
/// singular beyond what the regularisation repairs, or when the solution is not finite. qr and
/// ridge start from `reduced` when it is not empty (and consume it).
LeastSquaresResult solve_least_squares(const LinearSystem& system, const SampledFitConfig& config,
                                       ReducedProblem* reduced = nullptr);

}  // namespace hnn::nn::sampled
