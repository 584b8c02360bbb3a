#include "nn/sampled/sketch.h"

#include <cmath>

#include "nn/sampled/lsqr.h"
#include "nn/sampled/sparse_sign.h"

namespace hnn::nn::sampled {

using Eigen::Index;

namespace {

// Power steps for A's largest singular value on A^T A itself, from the sketch's top right singular
// vector. The sketch's own estimate is off by the embedding's distortion (10% on a pendulum test),
// and where the cutoff limits the error, the error is about proportional to mu: ridge and sketch
// would solve different problems. From that start a few steps (each one pass over A and one back)
// agree with ridge's 20 steps on R^T R (the same matrix) to about 1e-4.
constexpr int kLargestSteps = 3;

// Power steps on R^-T R^-1 for 1 / sigma_min(R). They approach it from below, which can only cost
// iterations (below), never accuracy; a few give its order of magnitude.
constexpr int kInverseSteps = 6;

double inverse_norm(const ColMat& r) {
  ColMat column(r.rows(), 1);
  const auto normal = [&](const Eigen::VectorXd& v, Eigen::VectorXd& out) {
    column = v;
    solve_upper(r, true, column);
    solve_upper(r, false, column);
    out = column;
  };
  return largest_singular_value(normal, Eigen::VectorXd::Ones(r.rows()), kInverseSteps);
}

double largest_of(const LinearSystem& system, const Eigen::VectorXd& start) {
  ColMat in(system.unknowns(), 1), av(system.equations(), 1), atav(system.unknowns(), 1);
  const auto normal = [&](const Eigen::VectorXd& v, Eigen::VectorXd& out) {
    in = v;
    system.apply(in, av);
    system.apply_t(av, atav);
    out = atav;
  };
  return largest_singular_value(normal, start, kLargestSteps);
}

}  // namespace

SketchedRidge::SketchedRidge(const LinearSystem& system, std::uint64_t seed) : system_(system) {
  const auto rows = Index(std::ceil(kSketchRowsPerUnknown * double(system.unknowns())));
  if (system.sketch_rows() <= rows) {
    system.reduced(r_, b_);
  } else {
    system.sketched(SparseSign(system.sketch_rows(), rows, seed), r_, b_);
  }
  reduce_to_triangle(r_, b_);
  Eigen::VectorXd top;
  largest_singular_value(r_, 20, &top);
  largest_ = largest_of(system, top);
  inverse_norm_ = inverse_norm(r_);
}

std::size_t SketchedRidge::bytes() const {
  return std::size_t(r_.size() + b_.size()) * sizeof(double);
}

SketchedRidge::Solution SketchedRidge::solve(double rcond, double tolerance,
                                             int max_iterations) const {
  const double mu = rcond * largest_;
  Preconditioner m{r_};
  Solution out{b_};
  if (mu * inverse_norm_ > kNegligibleDamping) {
    ridge_triangle(m.r, out.c, mu);  // m.r: the triangle of [R; mu I]
  } else {  // R itself: [A; mu I] R^-1 is as well conditioned, without the merge
    solve_upper(m.r, false, out.c);
  }
  Lsqr lsqr(system_, m, mu);
  out.iterations = lsqr.run(out.c, tolerance, max_iterations);
  out.bytes = bytes() + std::size_t(m.r.size()) * sizeof(double) + lsqr.bytes();
  return out;
}

}  // namespace hnn::nn::sampled
