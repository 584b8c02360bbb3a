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

/// Solves min |A C - B| by config.solver; throws std::invalid_argument when the system is
/// singular beyond what the regularisation repairs, or when the solution is not finite.
LeastSquaresResult solve_least_squares(const LinearSystem& system, const SampledFitConfig& config);

}  // namespace hnn::nn::sampled
