#include "nn/sampled/sketch.h"

#include <algorithm>
#include <cmath>
#include <random>

#include "autodiff/parallel.h"
#include "nn/sampled/lsqr.h"

namespace hnn::nn::sampled {

using Eigen::Index;

SparseSign::SparseSign(Index rows_in, Index rows_out, std::uint64_t seed)
    : rows_in_(rows_in),
      rows_out_(rows_out),
      per_row_(int(std::min<Index>(kSketchNonzeros, rows_out))),
      targets_(std::size_t(rows_in * per_row_)),
      weights_(targets_.size()) {
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<std::int32_t> row(0, std::int32_t(rows_out - 1));
  const double weight = 1 / std::sqrt(double(per_row_));
  for (std::size_t i = 0; i < std::size_t(rows_in); ++i) {
    std::int32_t* chosen = targets_.data() + i * std::size_t(per_row_);
    for (int k = 0; k < per_row_; ++k) {
      do chosen[k] = row(rng);
      while (std::find(chosen, chosen + k, chosen[k]) != chosen + k);
      weights_[i * std::size_t(per_row_) + std::size_t(k)] = (rng() & 1) ? weight : -weight;
    }
  }
}

ColMat SparseSign::apply(const ColMat& x) const {
  ColMat out = ColMat::Zero(rows_out_, x.cols());
  const int parts = int(std::min<Index>(x.cols(), ad::num_threads()));
  ad::parallel_for(parts, [&](int part) {
    const ad::RowBlock cols = ad::row_block(x.cols(), parts, part);
    for (Index j = cols.begin; j < cols.end; ++j) {
      const double* in = x.col(j).data();
      double* to = out.col(j).data();
      const std::int32_t* target = targets_.data();
      const double* weight = weights_.data();
      for (Index i = 0; i < rows_in_; ++i) {
        for (int k = 0; k < per_row_; ++k) to[*target++] += *weight++ * in[i];
      }
    }
  });
  return out;
}

namespace {

// Power steps for A's largest singular value on A^T A itself, from the sketch's top right singular
// vector. The sketch's own estimate is off by the embedding's distortion (10% on a pendulum test),
// and where the cutoff limits the error, the error is about proportional to mu: ridge and sketch
// would solve different problems. From that start a few steps (each one pass over A and one back)
// agree with ridge's 20 steps on R^T R (the same matrix) to about 1e-4.
constexpr int kLargestSteps = 3;

double largest_singular_value(const LinearSystem& system, const Eigen::VectorXd& start) {
  ColMat v = start, av(system.equations(), 1), atav(system.unknowns(), 1);
  double sigma = 0;
  for (int i = 0; i < kLargestSteps && v.norm() > 0; ++i) {
    v.normalize();
    system.apply(v, av);
    system.apply_t(av, atav);
    sigma = std::sqrt(atav.norm());
    v.swap(atav);
  }
  return sigma;
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
  largest_ = largest_singular_value(system, top);
}

std::size_t SketchedRidge::bytes() const {
  return std::size_t(r_.size() + b_.size()) * sizeof(double);
}

SketchedRidge::Solution SketchedRidge::solve(double rcond, double tolerance,
                                             int max_iterations) const {
  const double mu = rcond * largest_;
  Preconditioner m{r_, Eigen::VectorXd::Ones(r_.cols())};
  Solution out{b_};
  ridge_triangle(m.r, out.c, mu);  // m.r: the triangle of [R; mu I]
  Lsqr lsqr(system_, m, mu);
  out.iterations = lsqr.run(out.c, tolerance, max_iterations);
  out.bytes = bytes() + std::size_t(m.r.size()) * sizeof(double) + lsqr.bytes();
  return out;
}

}  // namespace hnn::nn::sampled
