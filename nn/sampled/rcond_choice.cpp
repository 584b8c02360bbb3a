#include "nn/sampled/rcond_choice.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

// LAPACK's divide-and-conquer SVD (OpenBLAS carries it; see nn/sampled/blas.cpp).
extern "C" {
void dgesdd_(const char* jobz, const int* m, const int* n, double* a, const int* lda, double* s,
             double* u, const int* ldu, double* vt, const int* ldvt, double* work, const int* lwork,
             int* iwork, int* info);
}

namespace hnn::nn::sampled {

using Eigen::Index;

namespace {

// a = U diag(s) V^T, thin: U rows x k, vt k x cols, k = min(rows, cols).
struct Svd {
  ColMat u, vt;
  Eigen::VectorXd s;
};

// dgesdd with jobz 'O': a's memory returns U (tall a) or V^T (wide a), so the factors cost one
// more square matrix than a itself.
Svd thin_svd(ColMat a) {
  const int m = int(a.rows()), n = int(a.cols()), k = std::min(m, n);
  Svd out;
  out.s.resize(k);
  ColMat square(k, k);  // V^T (tall a) or U (wide a)
  double unused = 0;
  const bool tall = m >= n;
  const int ldu = tall ? 1 : m, ldvt = tall ? n : 1;
  double* u = tall ? &unused : square.data();
  double* vt = tall ? square.data() : &unused;
  std::vector<int> iwork(std::size_t(8) * std::size_t(std::max(k, 1)));
  int info = 0, lwork = -1;
  double query = 0;
  dgesdd_("O", &m, &n, a.data(), &m, out.s.data(), u, &ldu, vt, &ldvt, &query, &lwork, iwork.data(),
          &info);
  lwork = int(query);
  std::vector<double> work(std::size_t(std::max(lwork, 1)));
  dgesdd_("O", &m, &n, a.data(), &m, out.s.data(), u, &ldu, vt, &ldvt, work.data(), &lwork,
          iwork.data(), &info);
  if (info != 0) {
    throw std::runtime_error(fmt::format("sampled fit: LAPACK dgesdd failed (info {})", info));
  }
  if (tall) {
    out.u = std::move(a);
    out.vt = std::move(square);
  } else {
    out.u = std::move(square);
    out.vt = a.topRows(k);
  }
  return out;
}

}  // namespace

std::vector<double> rcond_ladder() {
  std::vector<double> ladder;
  for (int e = -14; e <= -1; ++e) ladder.push_back(std::pow(10.0, e));
  return ladder;
}

std::vector<PointSplit> validation_folds(Index points) {
  if (points < 2) {
    throw std::invalid_argument(fmt::format(
        "sampled fit: --rcond auto holds out points to choose the cutoff and needs at least 2, "
        "got {}; give --rcond",
        points));
  }
  const Index tenths = std::min<Index>(10, points);
  const Index per_fold = points / tenths;
  const Index used = std::clamp<Index>((kHeldOutPoints + per_fold - 1) / per_fold, 1, tenths);
  std::vector<PointSplit> out;
  for (Index f = 0; f < used; ++f) {
    const Index k = f * tenths / used;  // spread over the data
    const Index begin = points * k / tenths, end = points * (k + 1) / tenths;
    PointSplit split;
    for (Index i = 0; i < points; ++i)
      (i >= begin && i < end ? split.held_out : split.train).push_back(i);
    out.push_back(std::move(split));
  }
  return out;
}

namespace {

// Adds each cutoff's squared held-out residual of the fit on split.train to `squared`, and the
// held-out targets' squared norm to `target`.
void validate_fold(const SystemOn& system_on, const PointSplit& split,
                   const std::vector<double>& ladder, std::vector<double>& squared,
                   std::vector<int>& ranks, double& target) {
  Svd svd;
  ColMat g;  // U^T b: the targets in the SVD's basis
  {
    const std::unique_ptr<LinearSystem> train = system_on(split.train);
    ColMat a, b;
    train->reduced(a, b);
    svd = thin_svd(std::move(a));
    g = svd.u.transpose() * b.topRows(svd.u.rows());
    svd.u = ColMat();
  }  // the training part's matrices go back before the held-out part's are formed
  const std::unique_ptr<LinearSystem> held_out = system_on(split.held_out);
  target += held_out->rhs().squaredNorm();
  ColMat fitted(held_out->equations(), held_out->rhs_columns()), c, y;
  const double largest = svd.s.size() > 0 ? svd.s(0) : 0;
  Index previous_rank = -1;
  double error = 0;
  for (std::size_t i = 0; i < ladder.size(); ++i) {
    const auto rank = Index((svd.s.array() > ladder[i] * largest).count());
    if (rank != previous_rank) {  // the same rank gives the same solution
      y = g.topRows(rank);
      y.array().colwise() /= svd.s.head(rank).array();
      c = svd.vt.topRows(rank).transpose() * y;
      held_out->apply(c, fitted);
      error = (fitted - held_out->rhs()).squaredNorm();
      previous_rank = rank;
    }
    squared[i] += error;
    ranks[i] = std::max(ranks[i], int(rank));
  }
}

}  // namespace

double choose_rcond(const SystemOn& system_on, const std::vector<PointSplit>& folds,
                    std::vector<RcondTrial>& curve) {
  const BlasThreads threads;
  const std::vector<double> ladder = rcond_ladder();
  std::vector<double> squared(ladder.size(), 0.0);
  std::vector<int> ranks(ladder.size(), 0);
  double target = 0;
  for (const PointSplit& fold : folds)
    validate_fold(system_on, fold, ladder, squared, ranks, target);
  double best = std::numeric_limits<double>::infinity(), chosen = ladder.front();
  curve.clear();
  for (std::size_t i = 0; i < ladder.size(); ++i) {
    const double error = std::sqrt(squared[i] / (target > 0 ? target : 1.0));
    curve.push_back({ladder[i], error, ranks[i]});
    if (error < best) {
      best = error;
      chosen = ladder[i];
    }
  }
  return chosen;
}

}  // namespace hnn::nn::sampled
