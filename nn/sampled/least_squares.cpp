#include "nn/sampled/least_squares.h"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "nn/sampled/lsqr.h"
#include "nn/sampled/sketch.h"

namespace hnn::nn::sampled {

using Eigen::Index;

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// A column of A that is zero (a neuron whose input gradient vanishes at every data point)
// leaves its unknown without an equation: the system is singular, whatever the solver.
void check_columns(const Eigen::VectorXd& squared_norms) {
  for (Index j = 0; j < squared_norms.size(); ++j) {
    if (!(squared_norms(j) > 0)) {
      throw std::invalid_argument(fmt::format(
          "sampled fit: the last layer's system is singular: unknown {} has no equation (its "
          "neuron's input gradient is zero at every data point)",
          j));
    }
  }
}

// The normal equations' factor: columns scaled to unit norm (s = diag(A^T A)^-1/2: SWIM's
// neurons differ in slope by orders of magnitude), then R^T R = S A^T A S + lambda I, lambda
// raised tenfold while the factorisation fails (the scaled Gram's rounding is about 1e-16, so
// a lambda near it may not make the computed matrix positive definite).
constexpr double kLargestRegularization = 1e-6;

Preconditioner cholesky_preconditioner(const ColMat& gram, double regularization, double& used) {
  const Index p = gram.rows();
  check_columns(gram.diagonal());
  Preconditioner m{ColMat(p, p), {}};
  m.s = gram.diagonal().cwiseMax(std::numeric_limits<double>::min()).cwiseSqrt().cwiseInverse();
  // A lambda the user asks above the cap is tried as given (the cap bounds the retries only).
  const double largest = std::max(kLargestRegularization, regularization);
  for (used = regularization; used <= largest; used *= 10) {
    m.r = m.s.asDiagonal() * gram * m.s.asDiagonal();
    m.r.diagonal().array() += used;
    if (cholesky_upper(m.r)) {
      m.r.triangularView<Eigen::StrictlyLower>().setZero();
      return m;
    }
    if (used == 0) used = 1e-16;
  }
  throw std::invalid_argument(
      fmt::format("sampled fit: the last layer's normal matrix is singular (Cholesky failed up to "
                  "regularisation {:g}); lower the width or give more distinct points",
                  largest));
}

void check_finite(const ColMat& c) {
  if (!c.allFinite()) {
    throw std::invalid_argument(
        "sampled fit: the least-squares solution is not finite (a singular system)");
  }
}

// The reduced problem (the Hadamard form's: one QR of D, its triangles merged) solved at rcond:
// dgelsd (kQr, the reference) or Tikhonov on the triangle (kRidge), at the memory of the
// reduction.
void solve_reduced(const LinearSystem& system, LeastSquaresSolver solver, double rcond,
                   ReducedProblem* reduced, LeastSquaresResult& out) {
  auto start = Clock::now();
  ColMat a, b;
  if (reduced != nullptr && !reduced->empty()) {
    a.swap(reduced->r);
    b.swap(reduced->c);
  } else {
    system.reduced(a, b);
  }
  out.gram_seconds = seconds_since(start);
  out.bytes = std::size_t(a.size() + b.size()) * sizeof(double);
  check_columns(a.colwise().squaredNorm().transpose());  // the reduction keeps column norms
  start = Clock::now();
  if (solver == LeastSquaresSolver::kQr) {
    lstsq_svd(a, b, rcond);
  } else {
    reduce_to_triangle(a, b);
    ridge_triangle(a, b, rcond * largest_singular_value(a));
  }
  out.c = b.topRows(system.unknowns());
  out.solve_seconds = seconds_since(start);
}

// sketch: the sketch's reduction is its assembly, the damped merge and LSQR its solve.
void solve_sketched(const LinearSystem& system, const SampledFitConfig& config,
                    LeastSquaresResult& out) {
  auto start = Clock::now();
  const SketchedRidge sketch(system, sketch_seed(config.seed));
  out.gram_seconds = seconds_since(start);
  start = Clock::now();
  SketchedRidge::Solution solved =
      sketch.solve(config.rcond.value(), config.tolerance, config.max_iterations);
  out.c.swap(solved.c);
  out.iterations = solved.iterations;
  out.bytes = solved.bytes;
  out.solve_seconds = seconds_since(start);
}

}  // namespace

LeastSquaresResult solve_least_squares(const LinearSystem& system, const SampledFitConfig& config,
                                       ReducedProblem* reduced) {
  const BlasThreads threads;
  LeastSquaresResult out;
  const Index p = system.unknowns();
  if (config.solver == LeastSquaresSolver::kSketch) {
    solve_sketched(system, config, out);
  } else if (config.solver != LeastSquaresSolver::kLsqr &&
             config.solver != LeastSquaresSolver::kCholesky) {
    solve_reduced(system, config.solver, config.rcond.value(), reduced, out);
  } else {
    auto start = Clock::now();
    ColMat g(p, p);
    system.gram(g);
    ColMat atb(p, system.rhs_columns());
    system.apply_t(system.rhs(), atb);
    out.gram_seconds = seconds_since(start);
    out.bytes = std::size_t(g.size()) * sizeof(double);
    start = Clock::now();
    const Preconditioner m = cholesky_preconditioner(g, config.regularization, out.regularization);
    g = ColMat();  // the factor is a copy: the Gram's memory goes back before LSQR allocates
    ColMat y(p, atb.cols());
    m.apply_t(atb, y);
    out.c.resize(p, atb.cols());
    m.apply(y, out.c);
    check_finite(out.c);
    if (config.solver == LeastSquaresSolver::kLsqr) {
      Lsqr lsqr(system, m);
      out.bytes += lsqr.bytes();
      out.iterations = lsqr.run(out.c, config.tolerance, config.max_iterations);
    }
    out.solve_seconds = seconds_since(start);
  }
  check_finite(out.c);
  ColMat r(system.equations(), system.rhs_columns());
  system.apply(out.c, r);
  r -= system.rhs();
  out.residual_rms = r.norm() / std::sqrt(double(r.size()));
  return out;
}

}  // namespace hnn::nn::sampled
