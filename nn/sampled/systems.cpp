#include "nn/sampled/systems.h"

#include <algorithm>
#include <vector>

#include "autodiff/parallel.h"
#include "nn/sampled/narrow.h"
#include "nn/sampled/sparse_sign.h"

namespace hnn::nn::sampled {

using Eigen::Index;

void LinearSystem::sketched(const SparseSign& sketch, ColMat& a, ColMat& b) const {
  a = sketch.apply(formed());
  b = sketch.apply(rhs());
}

void DenseSystem::sketched(const SparseSign& sketch, ColMat& a, ColMat& b) const {
  a = sketch.apply(a_);
  b = sketch.apply(b_);
}

void DenseSystem::gram(ColMat& g) const {
  blas_gram(a_.data(), a_.rows(), a_.cols(), a_.rows(), g, 0);
}

void DenseSystem::apply(const ColMat& c, ColMat& out) const { blas_gemm(a_, false, c, false, out); }

void DenseSystem::apply_t(const ColMat& r, ColMat& out) const {
  blas_gemm(a_, true, r, false, out);
}

std::size_t DenseSystem::bytes() const {
  return std::size_t(a_.size() + b_.size()) * sizeof(double);
}

HadamardSystem::HadamardSystem(ColMat d, ColMat v, const ColMat& dxdt)
    : d_(std::move(d)), v_(std::move(v)), b_(dxdt.size(), 1) {
  b_ = dxdt.reshaped();  // column-major: coordinate i's targets, then i + 1's
  y_.resize(v_.rows(), d_.cols());
  q_.resize(v_.rows(), d_.cols());
  p_.resize(d_.rows(), v_.rows());
}

void HadamardSystem::gram(ColMat& g) const {
  const Index w = d_.cols(), blocks = v_.cols() / w;
  // D^T D into the first block; the others copy it before it is scaled.
  ColMat k_block(0, 0);
  ColMat* k = &g;
  if (blocks > 1) {
    k_block.resize(w, w);
    k = &k_block;
  }
  blas_gram(d_.data(), d_.rows(), w, d_.rows(), *k, 0);
  for (Index s = 0; s < blocks; ++s) {
    for (Index t = 0; t < blocks; ++t) {
      for (Index col = 0; col < w; ++col) {
        for (Index row = 0; row < w; ++row) {
          const double m = v_.col(s * w + row).dot(v_.col(t * w + col));
          g(s * w + row, t * w + col) = (*k)(row, col) * m;
        }
      }
    }
  }
}

// A c: the field rows of coordinate i are D (sum_s v_is o c_s).
void HadamardSystem::apply(const ColMat& c, ColMat& out) const {
  const Index w = d_.cols(), blocks = v_.cols() / w, dim = v_.rows();
  y_.setZero();
  for (Index i = 0; i < dim; ++i) {
    for (Index s = 0; s < blocks; ++s) {
      y_.row(i).array() +=
          v_.row(i).segment(s * w, w).array() * c.col(0).segment(s * w, w).transpose().array();
    }
  }
  narrow_product(d_, y_, p_);
  out.col(0) = Eigen::Map<const Eigen::VectorXd>(p_.data(), p_.size());
}

// A^T r: block s of the result is sum_i v_is o (D^T r_i).
void HadamardSystem::apply_t(const ColMat& r, ColMat& out) const {
  const Index w = d_.cols(), blocks = v_.cols() / w, dim = v_.rows();
  p_ = Eigen::Map<const ColMat>(r.data(), d_.rows(), dim);
  narrow_product_t(d_, p_, q_);
  out.setZero();
  for (Index s = 0; s < blocks; ++s) {
    for (Index i = 0; i < dim; ++i) {
      out.col(0).segment(s * w, w).array() +=
          v_.row(i).segment(s * w, w).transpose().array() * q_.row(i).transpose().array();
    }
  }
}

ColMat HadamardSystem::formed() const {
  const Index n = d_.rows(), w = d_.cols(), blocks = v_.cols() / w, dim = v_.rows();
  ColMat a(n * dim, v_.cols());
  for (Index i = 0; i < dim; ++i) {
    for (Index col = 0; col < blocks * w; ++col) {
      a.col(col).segment(i * n, n) = d_.col(col % w) * v_(i, col);
    }
  }
  return a;
}

void HadamardSystem::reduced(ColMat& a, ColMat& b) const {
  const Index n = d_.rows(), w = d_.cols();
  if (n < w) {  // fewer points than neurons: D has no square R, and A is no taller than R's form
    LinearSystem::reduced(a, b);
    return;
  }
  reduce_points(d_, b_.reshaped(n, v_.rows()), a, b);
}

// q: the points' matrix (D or S D), overwritten by its QR; qtb: their targets, a column per
// coordinate.
void HadamardSystem::reduce_points(ColMat q, ColMat qtb, ColMat& a, ColMat& b) const {
  const Index w = d_.cols(), dim = v_.rows();
  const ColMat r = qr_apply(q, qtb);
  q = ColMat();
  if (v_.cols() == w) {
    merge_blocks(r, qtb, a, b);
    return;
  }
  a.resize(dim * w, v_.cols());
  b.resize(dim * w, 1);
  for (Index i = 0; i < dim; ++i) {
    for (Index col = 0; col < v_.cols(); ++col) {
      a.col(col).segment(i * w, w) = r.col(col % w) * v_(i, col);
    }
    b.col(0).segment(i * w, w) = qtb.col(i).head(w);
  }
}

// One column block: every row block R diag(v_i) is upper triangular, so the stack's QR merges
// them pairwise (dtpqrt), and the reduction is w x w. A level's merges run side by side on the
// engine's threads with one OpenBLAS thread each: LAPACK's dtpqrt gains little from OpenBLAS's
// second thread (docs/sampled.md), so two merges take about the time of one.
void HadamardSystem::merge_blocks(const ColMat& r, const ColMat& qtb, ColMat& a, ColMat& b) const {
  const Index w = d_.cols(), dim = v_.rows();
  const auto count = std::size_t(dim);
  std::vector<ColMat> triangle(count), target(count);
  for (Index i = 0; i < dim; ++i) {
    triangle[std::size_t(i)] = r * v_.row(i).asDiagonal();
    target[std::size_t(i)] = qtb.col(i).head(w);
  }
  for (Index step = 1; step < dim; step *= 2) {
    const int pairs =
        int((dim - 1 - step) / (2 * step) + 1);  // i = 0, 2 step, ... with i + step < dim
    const BlasThreads blas(pairs > 1 ? 1 : 0);
    ad::parallel_for(pairs, [&](int pair) {
      const auto i = std::size_t(2 * step * pair), j = i + std::size_t(step);
      qr_merge_triangle(triangle[i], triangle[j], target[i], target[j]);
      triangle[j] = ColMat();
    });
  }
  a = std::move(triangle.front());
  b = std::move(target.front());
}

// One sketch S of the points for every coordinate's row block: S embeds D's column space, so
// I (x) S embeds A's, and the sketched problem is the Hadamard form of S D, reduced like this
// one (a QR of S D and dim - 1 triangle merges). Sketching A's 4N rows directly to the same cost
// (one QR of 2-4 times the unknowns, no merges) needed 45-85 LSQR iterations against this one's
// 29 on the double pendulum at width 3000 (docs/sampled.md).
void HadamardSystem::sketched(const SparseSign& sketch, ColMat& a, ColMat& b) const {
  reduce_points(sketch.apply(d_), sketch.apply(b_.reshaped(d_.rows(), v_.rows())), a, b);
}

std::size_t HadamardSystem::bytes() const {
  return std::size_t(d_.size() + v_.size() + b_.size() + y_.size() + q_.size() + p_.size()) *
         sizeof(double);
}

}  // namespace hnn::nn::sampled
