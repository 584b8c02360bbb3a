#include "nn/sampled/blas.h"

#include <cblas.h>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "autodiff/parallel.h"

// LAPACK's Fortran entry points (OpenBLAS carries them; Debian ships no lapacke.h beside it).
extern "C" {
void dpotrf_(const char* uplo, const int* n, double* a, const int* lda, int* info);
void dgeqrf_(const int* m, const int* n, double* a, const int* lda, double* tau, double* work,
             const int* lwork, int* info);
void dormqr_(const char* side, const char* trans, const int* m, const int* n, const int* k,
             const double* a, const int* lda, const double* tau, double* c, const int* ldc,
             double* work, const int* lwork, int* info);
void dgelsd_(const int* m, const int* n, const int* nrhs, double* a, const int* lda, double* b,
             const int* ldb, double* s, const double* rcond, int* rank, double* work,
             const int* lwork, int* iwork, int* info);
void dgeqrt_(const int* m, const int* n, const int* nb, double* a, const int* lda, double* t,
             const int* ldt, double* work, int* info);
void dgemqrt_(const char* side, const char* trans, const int* m, const int* n, const int* k,
              const int* nb, const double* v, const int* ldv, const double* t, const int* ldt,
              double* c, const int* ldc, double* work, int* info);
void dtpqrt_(const int* m, const int* n, const int* l, const int* nb, double* a, const int* lda,
             double* b, const int* ldb, double* t, const int* ldt, double* work, int* info);
void dtpmqrt_(const char* side, const char* trans, const int* m, const int* n, const int* k,
              const int* l, const int* nb, const double* v, const int* ldv, const double* t,
              const int* ldt, double* a, const int* lda, double* b, const int* ldb, double* work,
              int* info);
}

namespace hnn::nn::sampled {

BlasThreads::BlasThreads() { openblas_set_num_threads(ad::num_threads()); }
BlasThreads::~BlasThreads() { openblas_set_num_threads(1); }

void blas_gemm(const ColMat& a, bool ta, const ColMat& b, bool tb, ColMat& c, double beta) {
  const auto m = int(c.rows()), n = int(c.cols());
  const auto k = int(ta ? a.rows() : a.cols());
  cblas_dgemm(CblasColMajor, ta ? CblasTrans : CblasNoTrans, tb ? CblasTrans : CblasNoTrans, m, n,
              k, 1.0, a.data(), int(a.rows()), b.data(), int(b.rows()), beta, c.data(),
              int(c.rows()));
}

void blas_gram(const double* a, Eigen::Index rows, Eigen::Index cols, Eigen::Index lda, ColMat& g,
               double beta) {
  cblas_dsyrk(CblasColMajor, CblasLower, CblasTrans, int(cols), int(rows), 1.0, a, int(lda), beta,
              g.data(), int(g.rows()));
  g.triangularView<Eigen::StrictlyUpper>() = g.transpose();
}

bool cholesky_upper(ColMat& g) {
  const auto n = int(g.rows());
  int info = 0;
  dpotrf_("U", &n, g.data(), &n, &info);
  return info == 0;
}

namespace {

// The QR of the m x n block at a (leading dimension lda) in place, and b <- Q^T b for the m x
// nrhs block at b (ldb): dgeqrf (nb 0, LAPACK's own block size) or dgeqrt with block size nb.
void qr_block(double* a, int m, int n, int lda, double* b, int ldb, int nrhs, int nb) {
  const int k = std::min(m, n);
  int info = 0;
  if (nb > 0) {
    nb = std::min(nb, k);
    std::vector<double> t(std::size_t(nb) * std::size_t(k));
    std::vector<double> work(std::size_t(nb) * std::size_t(std::max(n, nrhs)));
    dgeqrt_(&m, &n, &nb, a, &lda, t.data(), &nb, work.data(), &info);
    if (info == 0)
      dgemqrt_("L", "T", &m, &nrhs, &k, &nb, a, &lda, t.data(), &nb, b, &ldb, work.data(), &info);
  } else {
    std::vector<double> tau(static_cast<std::size_t>(k));
    int lwork = -1;
    double query_qr = 0, query_q = 0;  // workspace queries (lwork -1)
    dgeqrf_(&m, &n, a, &lda, tau.data(), &query_qr, &lwork, &info);
    dormqr_("L", "T", &m, &nrhs, &k, a, &lda, tau.data(), b, &ldb, &query_q, &lwork, &info);
    lwork = std::max(1, int(std::max(query_qr, query_q)));
    std::vector<double> work(static_cast<std::size_t>(lwork));
    dgeqrf_(&m, &n, a, &lda, tau.data(), work.data(), &lwork, &info);
    if (info == 0)
      dormqr_("L", "T", &m, &nrhs, &k, a, &lda, tau.data(), b, &ldb, work.data(), &lwork, &info);
  }
  if (info != 0) {
    throw std::runtime_error(fmt::format("sampled fit: LAPACK QR failed (info {})", info));
  }
}

}  // namespace

ColMat qr_apply(ColMat& a, ColMat& b) { return qr_apply_wy(a, b, 0); }

ColMat qr_apply_wy(ColMat& a, ColMat& b, int nb) {
  qr_block(a.data(), int(a.rows()), int(a.cols()), int(a.rows()), b.data(), int(b.rows()),
           int(b.cols()), nb);
  return a.topRows(a.cols()).triangularView<Eigen::Upper>();
}

ColMat qr_two_halves(ColMat& a, ColMat& b, int nb) {
  const auto m = int(a.rows()), n = int(a.cols()), half = m / 2, nrhs = int(b.cols());
  if (half < n || ad::num_threads() < 2) return qr_apply_wy(a, b, nb);
  // In place: each half is a block of a (and b) with a's leading dimension.
  openblas_set_num_threads(1);
  ad::parallel_for(2, [&](int part) {
    const int first = part == 0 ? 0 : half, rows = part == 0 ? half : m - half;
    qr_block(a.data() + first, rows, n, m, b.data() + first, int(b.rows()), nrhs, nb);
  });
  openblas_set_num_threads(ad::num_threads());
  ColMat r = a.topRows(n).triangularView<Eigen::Upper>();
  ColMat t = a.middleRows(half, n).triangularView<Eigen::Upper>();
  ColMat c = b.topRows(n), d = b.middleRows(half, n);
  qr_merge_triangle(r, t, c, d);
  b.topRows(n) = c;
  return r;
}

void qr_merge_triangle(ColMat& r, ColMat& t, ColMat& c, ColMat& d) {
  const auto n = int(r.cols()), nrhs = int(c.cols());
  // The block size of dtpqrt's compact WY form: its trailing updates are GEMMs of this depth.
  const int nb = std::min(n, 128);
  std::vector<double> tf(std::size_t(nb) * std::size_t(n));
  std::vector<double> work(std::size_t(nb) * std::size_t(std::max(n, nrhs)));
  int info = 0;
  dtpqrt_(&n, &n, &n, &nb, r.data(), &n, t.data(), &n, tf.data(), &nb, work.data(), &info);
  if (info == 0) {
    dtpmqrt_("L", "T", &n, &nrhs, &n, &n, &nb, t.data(), &n, tf.data(), &nb, c.data(), &n, d.data(),
             &n, work.data(), &info);
  }
  if (info != 0) {
    throw std::runtime_error(
        fmt::format("sampled fit: LAPACK dtpqrt/dtpmqrt failed (info {})", info));
  }
}

void solve_upper(const ColMat& r, bool transpose, ColMat& y) {
  cblas_dtrsm(CblasColMajor, CblasLeft, CblasUpper, transpose ? CblasTrans : CblasNoTrans,
              CblasNonUnit, int(y.rows()), int(y.cols()), 1.0, r.data(), int(r.rows()), y.data(),
              int(y.rows()));
}

int lstsq_svd(ColMat& a, ColMat& b, double rcond) {
  const auto m = int(a.rows()), n = int(a.cols()), nrhs = int(b.cols());
  const int ldb = std::max(m, n);
  if (b.rows() < ldb) b.conservativeResize(ldb, Eigen::NoChange);
  std::vector<double> s(std::size_t(std::min(m, n)));
  int rank = 0, info = 0, lwork = -1;
  double query = 0;
  int iquery = 0;
  dgelsd_(&m, &n, &nrhs, a.data(), &m, b.data(), &ldb, s.data(), &rcond, &rank, &query, &lwork,
          &iquery, &info);
  lwork = int(query);
  std::vector<double> work(std::size_t(std::max(lwork, 1)));
  std::vector<int> iwork(std::size_t(std::max(iquery, 1)));
  dgelsd_(&m, &n, &nrhs, a.data(), &m, b.data(), &ldb, s.data(), &rcond, &rank, work.data(), &lwork,
          iwork.data(), &info);
  if (info != 0) {
    throw std::runtime_error(fmt::format("sampled fit: LAPACK dgelsd failed (info {})", info));
  }
  return rank;
}

void ridge_triangle(ColMat& r, ColMat& b, double mu) {
  const Eigen::Index n = r.cols();
  ColMat t = ColMat::Zero(n, n), d = ColMat::Zero(n, b.cols());
  t.diagonal().setConstant(mu);
  qr_merge_triangle(r, t, b, d);
  solve_upper(r, false, b);
}

void reduce_to_triangle(ColMat& a, ColMat& b) {
  bool triangle = a.rows() == a.cols();
  for (Eigen::Index j = 0; triangle && j < a.cols(); ++j)
    triangle = a.col(j).tail(a.rows() - j - 1).isZero(0);
  if (!triangle) {
    ColMat r = qr_apply(a, b);
    a = std::move(r);
  }
  b.conservativeResize(a.cols(), Eigen::NoChange);
}

double largest_singular_value(const ColMat& r, int iterations) {
  const auto upper = r.triangularView<Eigen::Upper>();
  Eigen::VectorXd v = Eigen::VectorXd::Ones(r.cols()), u;
  double sigma = 0;
  for (int i = 0; i < iterations && v.norm() > 0; ++i) {
    v.normalize();
    u.noalias() = upper * v;
    v.noalias() = upper.transpose() * u;
    sigma = std::sqrt(v.norm());
  }
  return sigma;
}

}  // namespace hnn::nn::sampled
