#include "nn/sampled/rcond_choice.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>

#include "nn/sampled/sketch.h"

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

// |system's A c - B|², with `fitted` as the buffer for A c.
double squared_residual(const LinearSystem& system, const ColMat& c, ColMat& fitted) {
  fitted.resize(system.equations(), system.rhs_columns());
  system.apply(c, fitted);
  return (fitted - system.rhs()).squaredNorm();
}

// A summed squared residual relative to the summed squared targets.
double relative_error(double squared, double target) {
  return std::sqrt(squared / (target > 0 ? target : 1.0));
}

// One fold: its training points' reduced problem (qr, ridge) or sketch (sketch, which keeps
// their system: its LSQR reads it), and the system of its held-out points.
struct Fold {
  ColMat a, b;
  std::unique_ptr<LinearSystem> train, held_out;
  std::optional<SketchedRidge> sketch;
  ColMat fitted;

  Fold(const SystemOn& system_on, const PointSplit& split, const SampledFitConfig& config) {
    train = system_on(split.train);
    if (config.solver == LeastSquaresSolver::kSketch) {
      sketch.emplace(*train, sketch_seed(config.seed));
    } else {
      train->reduced(a, b);
      train.reset();  // the training system goes before the held-out's
    }
    held_out = system_on(split.held_out);
  }
  // The squared held-out residual of the last layer c.
  double error_of(const ColMat& c) { return squared_residual(*held_out, c, fitted); }
};

// qr: one SVD of the fold's reduced problem, each cutoff a truncated product with its factors.
void svd_rungs(Fold& fold, const std::vector<double>& ladder, std::vector<double>& squared,
               std::vector<int>& ranks) {
  Svd svd = thin_svd(std::move(fold.a));
  const ColMat g = svd.u.transpose() * fold.b.topRows(svd.u.rows());  // b in the SVD's basis
  svd.u = ColMat();
  const double largest = svd.s.size() > 0 ? svd.s(0) : 0;
  ColMat c, y;
  Index previous_rank = -1;
  double error = 0;
  for (std::size_t i = 0; i < ladder.size(); ++i) {
    const auto rank = Index((svd.s.array() > ladder[i] * largest).count());
    if (rank != previous_rank) {  // the same rank gives the same solution
      y = g.topRows(rank);
      y.array().colwise() /= svd.s.head(rank).array();
      c = svd.vt.topRows(rank).transpose() * y;
      error = fold.error_of(c);
      previous_rank = rank;
    }
    squared[i] += error;
    ranks[i] = std::max(ranks[i], int(rank));
  }
}

// ridge and sketch damp rather than drop: every rank is the width. Each fold is solved once per
// cutoff (ridge: a dtpqrt of its triangle, no SVD; sketch: its sketch's merge and LSQR), walked
// from the smallest cutoff and stopped once the held-out error, summed over the folds, passes
// kRidgeStop times the best so far: on exact derivatives it rises tenfold a cutoff from the
// smallest (after three or four cutoffs), on noisy ones it wanders within a few times the best
// and falls to a large cutoff (a stop two cutoffs after the best chose 1e-12 on the pendulum
// task, whose best is 1e-4). The cutoffs not reached count as infinitely bad.
constexpr double kRidgeStop = 100;

void damped_walk(std::vector<Fold>& folds, const SampledFitConfig& config,
                 const std::vector<double>& ladder, std::vector<double>& squared,
                 std::vector<int>& ranks) {
  std::vector<double> largest(folds.size(), 0.0);
  for (std::size_t f = 0; f < folds.size(); ++f) {
    if (folds[f].sketch) continue;
    reduce_to_triangle(folds[f].a, folds[f].b);
    largest[f] = largest_singular_value(folds[f].a);
  }
  const auto solve_at = [&](std::size_t f, double rcond) {
    Fold& fold = folds[f];
    if (fold.sketch) return fold.sketch->solve(rcond, config.tolerance, config.max_iterations).c;
    ColMat r = fold.a, c = fold.b;
    ridge_triangle(r, c, rcond * largest[f]);
    return c;
  };
  double best = std::numeric_limits<double>::infinity();
  std::size_t i = 0;
  while (i < ladder.size()) {
    for (std::size_t f = 0; f < folds.size(); ++f) {
      squared[i] += folds[f].error_of(solve_at(f, ladder[i]));
      ranks[i] = int(folds[f].held_out->unknowns());
    }
    best = std::min(best, squared[i]);
    // squared errors: the stop's factor squared
    if (squared[i++] > kRidgeStop * kRidgeStop * best) break;
  }
  for (; i < ladder.size(); ++i) squared[i] = std::numeric_limits<double>::infinity();
}

// The whole problem's triangle from a fold's: its training triangle (a, b) and its held-out
// points' own, merged by one QR of the stacked triangles. The fold's a and b are consumed.
void merge_halves(Fold& fold, ReducedProblem& whole) {
  ColMat t, d;
  fold.held_out->reduced(t, d);
  if (t.rows() < t.cols()) {  // fewer held-out rows than unknowns: zero rows change nothing
    const Index rows = t.rows();
    t.conservativeResize(t.cols(), Eigen::NoChange);
    d.conservativeResize(t.cols(), Eigen::NoChange);
    t.bottomRows(t.rows() - rows).setZero();
    d.bottomRows(d.rows() - rows).setZero();
  }
  reduce_to_triangle(t, d);
  qr_merge_triangle(fold.a, t, fold.b, d);
  whole.r.swap(fold.a);
  whole.c.swap(fold.b);
}

}  // namespace

double choose_rcond(const SystemOn& system_on, const std::vector<PointSplit>& folds,
                    const SampledFitConfig& config, const std::vector<double>& ladder,
                    std::vector<RcondTrial>& curve, ReducedProblem* whole) {
  const bool damped =
      config.solver == LeastSquaresSolver::kRidge || config.solver == LeastSquaresSolver::kSketch;
  // sketch: the whole problem is sketched anew (merging the held-out points' reduction would cost
  // the QR of D that the sketch avoids)
  const bool merge =
      whole != nullptr && folds.size() == 1 && config.solver != LeastSquaresSolver::kSketch;
  const BlasThreads threads;
  std::vector<double> squared(ladder.size(), 0.0);
  std::vector<int> ranks(ladder.size(), 0);
  double target = 0;
  if (damped) {  // every fold at each cutoff, to stop early
    std::vector<Fold> prepared;
    prepared.reserve(folds.size());  // a sketch refers to its fold's training system
    for (const PointSplit& split : folds) {
      prepared.emplace_back(system_on, split, config);
      target += prepared.back().held_out->rhs().squaredNorm();
    }
    damped_walk(prepared, config, ladder, squared, ranks);  // ridge: each triangle left in a, b
    if (merge) merge_halves(prepared.front(), *whole);
  } else {  // a fold at a time: one SVD's factors held at once
    for (const PointSplit& split : folds) {
      Fold fold(system_on, split, config);
      target += fold.held_out->rhs().squaredNorm();
      if (merge) {
        reduce_to_triangle(fold.a, fold.b);
        whole->r = fold.a;
        whole->c = fold.b;
      }
      svd_rungs(fold, ladder, squared, ranks);
      if (merge) {
        fold.a.swap(whole->r);
        fold.b.swap(whole->c);
        merge_halves(fold, *whole);
      }
    }
  }
  double best = std::numeric_limits<double>::infinity(), chosen = ladder.front();
  curve.clear();
  for (std::size_t i = 0; i < ladder.size(); ++i) {
    if (!std::isfinite(squared[i])) continue;  // a cutoff ridge's walk did not reach
    const double error = relative_error(squared[i], target);
    curve.push_back({ladder[i], error, ranks[i]});
    if (error < best) {
      best = error;
      chosen = ladder[i];
    }
  }
  return chosen;
}

double held_out_error(const SystemOn& system_on, const std::vector<PointSplit>& folds,
                      const SampledFitConfig& config) {
  double squared = 0, target = 0;
  for (const PointSplit& split : folds) {
    const ColMat c = solve_least_squares(*system_on(split.train), config).c;
    const std::unique_ptr<LinearSystem> held_out = system_on(split.held_out);
    ColMat fitted;
    squared += squared_residual(*held_out, c, fitted);
    target += held_out->rhs().squaredNorm();
  }
  return relative_error(squared, target);
}

}  // namespace hnn::nn::sampled
