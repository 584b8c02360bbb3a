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

BlasThreads::BlasThreads(int threads) : previous_(openblas_get_num_threads()) {
  openblas_set_num_threads(threads > 0 ? threads : ad::num_threads());
}
BlasThreads::~BlasThreads() { openblas_set_num_threads(previous_); }

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

ColMat qr_apply(ColMat& a, ColMat& b) {
  const auto m = int(a.rows()), n = int(a.cols()), nrhs = int(b.cols()), k = std::min(m, n);
  // dgeqrt's block size: its panels are recursive (dgeqrt3) and its trailing updates GEMMs of
  // this depth. 128 took 11.0-11.5 s on the Henon-Heiles D (20000 x 5000) against dgeqrf's
  // 14.3 s (LAPACK's default block of 32, panels by level-2 Householder steps): docs/sampled.md.
  const int nb = std::min(128, std::max(k, 1));
  std::vector<double> t(std::size_t(nb) * std::size_t(std::max(k, 1)));
  std::vector<double> work(std::size_t(nb) * std::size_t(std::max(n, nrhs)));
  int info = 0;
  dgeqrt_(&m, &n, &nb, a.data(), &m, t.data(), &nb, work.data(), &info);
  if (info == 0) {
    dgemqrt_("L", "T", &m, &nrhs, &k, &nb, a.data(), &m, t.data(), &nb, b.data(), &m, work.data(),
             &info);
  }
  if (info != 0) {
    throw std::runtime_error(
        fmt::format("sampled fit: LAPACK dgeqrt/dgemqrt failed (info {})", info));
  }
  return a.topRows(n).triangularView<Eigen::Upper>();
}

void qr_merge_triangle(ColMat& r, ColMat& t, ColMat& c, ColMat& d) {
  const auto n = int(r.cols()), nrhs = int(c.cols());
  // The block size of dtpqrt's compact WY form: its trailing updates are GEMMs of this depth.
  const int nb = std::min(n, 128);  // 32, 64 and 256 measured no faster (docs/sampled.md)
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
  if (y.cols() == 1) {  // dtrsv: dtrsm packs the triangle first, twice the time for one column
    cblas_dtrsv(CblasColMajor, CblasUpper, transpose ? CblasTrans : CblasNoTrans, CblasNonUnit,
                int(r.rows()), r.data(), int(r.rows()), y.data(), 1);
    return;
  }
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

double largest_singular_value(const NormalProduct& normal, Eigen::VectorXd v, int iterations,
                              Eigen::VectorXd* vector) {
  Eigen::VectorXd product(v.size());
  double sigma = 0;
  for (int i = 0; i < iterations && v.norm() > 0; ++i) {
    v.normalize();
    normal(v, product);
    sigma = std::sqrt(product.norm());
    v.swap(product);
  }
  if (vector != nullptr) *vector = v.norm() > 0 ? Eigen::VectorXd(v.normalized()) : v;
  return sigma;
}

double largest_singular_value(const ColMat& r, int iterations, Eigen::VectorXd* vector) {
  const auto upper = r.triangularView<Eigen::Upper>();
  Eigen::VectorXd u;
  const auto normal = [&](const Eigen::VectorXd& v, Eigen::VectorXd& out) {
    u.noalias() = upper * v;
    out.noalias() = upper.transpose() * u;
  };
  return largest_singular_value(normal, Eigen::VectorXd::Ones(r.cols()), iterations, vector);
}

}  // namespace hnn::nn::sampled
