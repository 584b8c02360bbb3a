#include "nn/sampled/least_squares.h"

#include <fmt/format.h>

#include <chrono>
#include <cmath>
#include <stdexcept>

namespace hnn::nn::sampled {

using Eigen::Index;

namespace {

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// The Cholesky factor L of A^T A + lambda I, lambda = regularization * mean(diag(A^T A)).
void factor_regularised(ColMat& g, double regularization) {
  const double lambda = regularization * g.diagonal().mean();
  g.diagonal().array() += lambda;
  if (!cholesky_lower(g)) {
    throw std::invalid_argument(
        fmt::format("sampled fit: the last layer's normal matrix is singular (Cholesky failed at "
                    "regularisation {:g}); raise the regularisation or lower the width",
                    regularization));
  }
}

// LSQR (Paige & Saunders 1982) on A L^-T, started from c0: it solves for the correction, and
// the preconditioned matrix is well conditioned where A's singular values exceed sqrt(lambda),
// so it converges in a few iterations there; smaller ones it resolves slowly, which stopping
// early turns into a truncation like rcond's.
struct Lsqr {
  const LinearSystem& a;
  const ColMat& l;
  ColMat u, v, w, x, av, atu;

  Lsqr(const LinearSystem& system, const ColMat& factor)
      : a(system),
        l(factor),
        u(system.equations(), system.rhs_columns()),
        v(system.unknowns(), system.rhs_columns()),
        w(v),
        x(v),
        av(u),
        atu(v) {}

  void forward(const ColMat& y, ColMat& out) {  // out = A L^-T y
    atu = y;
    solve_lower(l, true, atu);
    a.apply(atu, out);
  }
  void backward(const ColMat& r, ColMat& out) {  // out = L^-1 A^T r
    a.apply_t(r, out);
    solve_lower(l, false, out);
  }

  // Returns the iterations; c += L^-T x.
  int run(ColMat& c, double tolerance, int max_iterations) {
    a.apply(c, u);
    u = a.rhs() - u;
    double beta = u.norm();
    if (beta == 0) return 0;
    u /= beta;
    backward(u, v);
    double alpha = v.norm();
    if (alpha == 0) return 0;
    v /= alpha;
    w = v;
    x.setZero();
    double phibar = beta, rhobar = alpha, anorm2 = 0;
    int it = 0;
    while (it < max_iterations) {
      ++it;
      forward(v, av);
      u = av - alpha * u;
      beta = u.norm();
      if (beta > 0) u /= beta;
      anorm2 += alpha * alpha + beta * beta;
      backward(u, atu);
      v = atu - beta * v;
      alpha = v.norm();
      if (alpha > 0) v /= alpha;
      const double rho = std::hypot(rhobar, beta), cs = rhobar / rho, sn = beta / rho;
      const double theta = sn * alpha, phi = cs * phibar;
      rhobar = -cs * alpha;
      phibar = sn * phibar;
      x += (phi / rho) * w;
      w = v - (theta / rho) * w;
      // |(A L^-T)^T r| = phibar alpha |cs|, against |A L^-T| |r| (Paige & Saunders' test 2).
      if (phibar * alpha * std::abs(cs) <= tolerance * std::sqrt(anorm2) * phibar || alpha == 0) {
        break;
      }
    }
    solve_lower(l, true, x);
    c += x;
    return it;
  }
};

void check_finite(const ColMat& c) {
  if (!c.allFinite()) {
    throw std::invalid_argument(
        "sampled fit: the least-squares solution is not finite (a singular system)");
  }
}

}  // namespace

LeastSquaresResult solve_least_squares(const LinearSystem& system, const SampledFitConfig& config) {
  const BlasThreads threads;
  LeastSquaresResult out;
  const Index p = system.unknowns();
  if (config.solver == LeastSquaresSolver::kQr) {
    auto start = std::chrono::steady_clock::now();
    ColMat a = system.formed();
    ColMat b = system.rhs();
    out.gram_seconds = seconds_since(start);
    out.bytes = std::size_t(a.size() + b.size()) * sizeof(double);
    start = std::chrono::steady_clock::now();
    lstsq_svd(a, b, config.rcond);
    out.c = b.topRows(p);
    out.solve_seconds = seconds_since(start);
  } else {
    auto start = std::chrono::steady_clock::now();
    ColMat g(p, p);
    system.gram(g);
    ColMat atb(p, system.rhs_columns());
    system.apply_t(system.rhs(), atb);
    out.gram_seconds = seconds_since(start);
    out.bytes = std::size_t(g.size()) * sizeof(double);
    start = std::chrono::steady_clock::now();
    factor_regularised(g, config.regularization);
    out.c = atb;
    solve_lower(g, false, out.c);
    solve_lower(g, true, out.c);
    check_finite(out.c);
    if (config.solver == LeastSquaresSolver::kLsqr) {
      Lsqr lsqr(system, g);
      out.bytes += std::size_t(lsqr.u.size() * 2 + lsqr.v.size() * 4) * sizeof(double);
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
