#pragma once
// The last layer's least-squares problem min |A C - B| in two forms: a formed matrix, and for an
// HNN with one hidden layer the Hadamard form that never forms A (docs/sampled.md).

#include <cstddef>
#include <vector>

#include "nn/sampled/blas.h"

namespace hnn::nn::sampled {

class SparseSign;

/// A problem with `unknowns()` x `rhs_columns()` unknowns C and equations()-row targets B.
class LinearSystem {
 public:
  virtual ~LinearSystem() = default;
  virtual Eigen::Index equations() const = 0;
  virtual Eigen::Index unknowns() const = 0;
  Eigen::Index rhs_columns() const { return rhs().cols(); }
  virtual const ColMat& rhs() const = 0;
  /// g = A^T A (unknowns x unknowns), g already sized.
  virtual void gram(ColMat& g) const = 0;
  /// out = A c (equations x m) and out = A^T r (unknowns x m), out already sized.
  virtual void apply(const ColMat& c, ColMat& out) const = 0;
  virtual void apply_t(const ColMat& r, ColMat& out) const = 0;
  /// A itself, equations x unknowns (the tests').
  virtual ColMat formed() const = 0;
  /// a and b with the least-squares problem of A and B (the same solutions, the residual
  /// smaller by a constant): the SVD solver's input. A and B themselves unless overridden.
  virtual void reduced(ColMat& a, ColMat& b) const {
    a = formed();
    b = rhs();
  }
  /// The rows a sketch mixes (sketch.h): the equations, or the points they come in blocks of.
  virtual Eigen::Index sketch_rows() const { return equations(); }
  /// The sketched problem S A, S B, reduced like reduced() when the system has a cheaper form.
  virtual void sketched(const SparseSign& sketch, ColMat& a, ColMat& b) const;
  /// Bytes of the matrices the system holds.
  virtual std::size_t bytes() const = 0;
};

/// A formed: the baseline's hidden outputs (B = dx/dt, one column per output), or an HNN's
/// field rows from tangents carried through every layer (B one column).
class DenseSystem final : public LinearSystem {
 public:
  DenseSystem(ColMat a, ColMat b) : a_(std::move(a)), b_(std::move(b)) {}
  Eigen::Index equations() const override { return a_.rows(); }
  Eigen::Index unknowns() const override { return a_.cols(); }
  const ColMat& rhs() const override { return b_; }
  void gram(ColMat& g) const override;
  void apply(const ColMat& c, ColMat& out) const override;
  void apply_t(const ColMat& r, ColMat& out) const override;
  ColMat formed() const override { return a_; }
  void sketched(const SparseSign& sketch, ColMat& a, ColMat& b) const override;
  std::size_t bytes() const override;

 private:
  ColMat a_, b_;
};

/// One hidden layer, field rows f_i = sum_s D diag(v_is) c_s, with D = act'(Z) (N x width): row
/// block i of A is [D diag(v_i0), D diag(v_i1), ...], so A^T A = (D^T D) o (V^T V) tiled over
/// the column blocks s, one syrk of D instead of one of A (dim times taller).
class HadamardSystem final : public LinearSystem {
 public:
  /// d: N x width; v: dim x (blocks * width), row i holding v_i0, v_i1, ...; dxdt: N x dim.
  HadamardSystem(ColMat d, ColMat v, const ColMat& dxdt);
  Eigen::Index equations() const override { return b_.rows(); }
  Eigen::Index unknowns() const override { return v_.cols(); }
  const ColMat& rhs() const override { return b_; }
  void gram(ColMat& g) const override;
  void apply(const ColMat& c, ColMat& out) const override;
  void apply_t(const ColMat& r, ColMat& out) const override;
  ColMat formed() const override;
  /// With D = QR (N x width): row block i becomes R diag(v_i), its targets the first width
  /// entries of Q^T b_i, as Q is the same for every block: dim * width rows instead of dim * N.
  /// With one column block (an HNN) the triangular row blocks are merged: width rows.
  void reduced(ColMat& a, ColMat& b) const override;
  /// The sketch's rows are the points (one S for every coordinate's row block).
  Eigen::Index sketch_rows() const override { return d_.rows(); }
  void sketched(const SparseSign& sketch, ColMat& a, ColMat& b) const override;
  std::size_t bytes() const override;

 private:
  void reduce_points(ColMat q, ColMat qtb, ColMat& a, ColMat& b) const;
  void merge_blocks(const ColMat& r, const ColMat& qtb, ColMat& a, ColMat& b) const;

  ColMat d_, v_, b_;          // b_: N * dim x 1, coordinate-major (row i * N + n)
  mutable ColMat y_, q_, p_;  // apply's (y_: dim x width) and apply_t's work, allocated once
};

}  // namespace hnn::nn::sampled
