#pragma once
// The dense linear algebra of the sampled fit, on Debian's OpenBLAS (pthreads build, with its
// LAPACK): column-major Eigen matrices handed to cblas and to LAPACK's Fortran routines.

#include <Eigen/Core>
#include <functional>

namespace hnn::nn::sampled {

using ColMat = Eigen::MatrixXd;

/// OpenBLAS uses `threads` threads (ad::num_threads() by default) while this lives, then as many
/// as before: the engine calls OpenBLAS's serial GEMM from its own threads (autodiff/gemm.cpp),
/// but the fit's big products run alone and are worth both cores. LSQR's iterations ask for 1:
/// there the engine's threads stream D, and OpenBLAS's idle workers, which spin in sched_yield
/// after each call, would take their cores.
class BlasThreads {
 public:
  explicit BlasThreads(int threads = 0);  // 0: ad::num_threads()
  ~BlasThreads();
  BlasThreads(const BlasThreads&) = delete;
  BlasThreads& operator=(const BlasThreads&) = delete;

 private:
  int previous_;
};

/// c = op(a) op(b) + beta c (op: transpose when the flag is set); c must have the right size.
void blas_gemm(const ColMat& a, bool ta, const ColMat& b, bool tb, ColMat& c, double beta = 0);
/// g = a^T a + beta g for the `rows` x `cols` column-major block at `a` (leading dimension
/// lda), both triangles filled: one dsyrk, the floor of the normal-equation solvers.
void blas_gram(const double* a, Eigen::Index rows, Eigen::Index cols, Eigen::Index lda, ColMat& g,
               double beta);
/// g = R^T R in place (the upper triangle holds R); false when g is not positive definite.
bool cholesky_upper(ColMat& g);
/// a = QR in place (Householder in compact WY blocks, LAPACK's dgeqrt), then b <- Q^T b; returns
/// R (a.cols() square).
ColMat qr_apply(ColMat& a, ColMat& b);
/// [r; t] = Q [r'; 0] for upper-triangular n x n r and t (LAPACK's dtpqrt, 2/3 n^3 FLOP
/// against dgeqrf's 10/3 n^3 on the formed 2n x n stack): r <- r', and [c; d] <- Q^T [c; d]
/// (n x m each). t and d are destroyed.
void qr_merge_triangle(ColMat& r, ColMat& t, ColMat& c, ColMat& d);
/// y <- R^-1 y, or y <- R^-T y (transpose), for an upper-triangular R.
void solve_upper(const ColMat& r, bool transpose, ColMat& y);
/// min |a x - b| by LAPACK's dgelsd (the SVD solver np.linalg.lstsq runs); singular values below
/// rcond times the largest are dropped. a is destroyed; b (rows x m) returns x in its first
/// a.cols() rows. Returns the effective rank; throws std::runtime_error when dgelsd fails.
int lstsq_svd(ColMat& a, ColMat& b, double rcond);
/// min |r x - b|^2 + mu^2 |x|^2 for an upper-triangular n x n r: the QR of [r; mu I] by dtpqrt
/// (2/3 n^3 FLOP, a merge of qr_merge_triangle), then one triangular solve. r is overwritten by
/// the stack's triangle; b (n x m) returns x.
void ridge_triangle(ColMat& r, ColMat& b, double mu);
/// out = A^T A v for some A: what power steps read.
using NormalProduct = std::function<void(const Eigen::VectorXd& v, Eigen::VectorXd& out)>;
/// A's largest singular value from `iterations` power steps on A^T A started at `start` (an
/// estimate from below, matrix-vector products only: enough to place a cutoff a decade apart
/// from the next), and in `vector` the last step's unit vector when given.
double largest_singular_value(const NormalProduct& normal, Eigen::VectorXd start, int iterations,
                              Eigen::VectorXd* vector = nullptr);
/// The same for an upper-triangular r (A = r), from the ones vector.
double largest_singular_value(const ColMat& r, int iterations = 20,
                              Eigen::VectorXd* vector = nullptr);
/// a <- its QR's triangle (a.cols() square) and b <- the first a.cols() rows of Q^T b, unless a
/// is upper triangular and square already (the Hadamard form's merged reduction).
void reduce_to_triangle(ColMat& a, ColMat& b);

}  // namespace hnn::nn::sampled
