// Benchmarks of the autodiff engine: the spring task's HNN training step (forward and double
// backward of a 2-W-W-1 tanh MLP) in float and double, and the gradient of a known Hamiltonian
// by autodiff, by central finite differences over a sweep of steps h, and analytically, with
// each method's error against the analytic gradient. Run with --benchmark_format=json for the
// speed-against-accuracy charts. Then the Lagrangian network's ops: batched_solve forward and
// backward, and the per-row Hessians of an MLP by row_hessian. Last, the fused kernels' matrix
// product at the steps' shapes: the engine's AVX-512 kernel against OpenBLAS's GEMM.

#include <benchmark/benchmark.h>

#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "autodiff/autodiff.h"
#include "autodiff/gemm.h"

namespace ad = hnn::ad;
using ad::Matrix;
using ad::Var;

namespace {

Matrix<double> Uniform(Eigen::Index rows, Eigen::Index cols, unsigned seed, double lo, double hi) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> uniform(lo, hi);
  Matrix<double> m(rows, cols);
  for (Eigen::Index i = 0; i < m.size(); ++i) m.data()[i] = uniform(rng);
  return m;
}

// Orthonormal rows or columns (the reference code's orthogonal initialisation).
Matrix<double> Orthogonal(Eigen::Index rows, Eigen::Index cols, unsigned seed) {
  const bool tall = rows >= cols;
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal;
  Eigen::MatrixXd g(tall ? rows : cols, tall ? cols : rows);
  for (Eigen::Index i = 0; i < g.size(); ++i) g.data()[i] = normal(rng);
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(g);
  const Eigen::MatrixXd q = qr.householderQ() * Eigen::MatrixXd::Identity(g.rows(), g.cols());
  return tall ? Matrix<double>(q) : Matrix<double>(q.transpose());
}

// ---- 1. the spring HNN training step ---------------------------------------------------------

template <typename T>
Var<T> Mlp(const std::vector<Var<T>>& p, Var<T> x) {
  for (std::size_t l = 0; l + 2 < p.size(); l += 2) x = ad::tanh(ad::linear(x, p[l], p[l + 1]));
  return ad::linear(x, p[p.size() - 2], p.back());
}

// Args: batch size, hidden width. One iteration = one full training step in its own TapeScope:
// energy = sum H(x), dH = grad(energy, x, create_graph), field = (dH/dp, -dH/dq),
// loss = mean((field - target)^2), grads = grad(loss, params).
template <typename T>
void BM_SpringTrainingStep(benchmark::State& state) {
  const Eigen::Index batch = state.range(0), width = state.range(1);
  const std::vector<Eigen::Index> sizes = {2, width, width, 1};
  std::vector<Var<T>> params;
  for (std::size_t l = 0; l + 1 < sizes.size(); ++l) {
    params.push_back(Var<T>::leaf(Orthogonal(sizes[l], sizes[l + 1], 10 + l).cast<T>()));
    params.push_back(Var<T>::leaf(Matrix<T>::Zero(1, sizes[l + 1])));
  }
  const Matrix<double> x0 = Uniform(batch, 2, 1, -1, 1);
  Matrix<double> dxdt(batch, 2);
  dxdt.col(0) = 2 * x0.col(1);
  dxdt.col(1) = -2 * x0.col(0);
  const Var<T> x = Var<T>::leaf(x0.cast<T>());
  const Var<T> target = Var<T>::leaf(dxdt.cast<T>(), /*requires_grad=*/false);

  T loss_value = 0;
  for (auto _ : state) {
    ad::TapeScope scope;
    const Var<T> energy = ad::sum(Mlp(params, x));
    const Var<T> dh = ad::grad<T>({energy}, {x}, {.create_graph = true})[0];
    const Var<T> field = ad::concat_cols<T>({ad::slice_cols(dh, 1, 1), -ad::slice_cols(dh, 0, 1)});
    const Var<T> loss = ad::mean(ad::square(field - target));
    // The output bias does not reach the field: allow_unused gives it zeros.
    const std::vector<Var<T>> grads = ad::grad<T>({loss}, params, {.allow_unused = true});
    loss_value = loss.item();
    benchmark::DoNotOptimize(grads.front().value().data());
  }
  state.SetItemsProcessed(state.iterations() * batch);
  state.counters["loss"] = double(loss_value);
  state.counters["tape_nodes"] = double(ad::Tape<T>::current().capacity());
}

BENCHMARK_TEMPLATE(BM_SpringTrainingStep, float)
    ->ArgNames({"batch", "width"})
    ->Args({750, 200})
    ->Args({750, 100})
    ->Args({750, 50})
    ->Unit(benchmark::kMillisecond);
BENCHMARK_TEMPLATE(BM_SpringTrainingStep, double)
    ->ArgNames({"batch", "width"})
    ->Args({750, 200})
    ->Args({750, 100})
    ->Args({750, 50})
    ->Unit(benchmark::kMillisecond);

// ---- 2. grad H: autodiff vs finite differences vs analytic ----------------------------------

// The pendulum H = 3 (1 - cos q) + p^2 of docs/tasks.md, x = (q, p).
struct Pendulum {
  static constexpr Eigen::Index kDim = 2;
  template <typename T>
  static Var<T> Energy(const Var<T>& x) {
    return ad::scale(T(1) - ad::cos(ad::slice_cols(x, 0, 1)), T(3)) +
           ad::square(ad::slice_cols(x, 1, 1));
  }
  template <typename T>
  static Matrix<T> Gradient(const Matrix<T>& x) {
    Matrix<T> g(x.rows(), 2);
    g.col(0) = T(3) * x.col(0).array().sin();
    g.col(1) = T(2) * x.col(1);
    return g;
  }
  static Matrix<double> Sample(Eigen::Index rows) { return Uniform(rows, 2, 2, -2, 2); }
};

// The two-body H = sum |p_i|^2 / 2 - 1/|q1 - q2|, x = (qx1, qx2, qy1, qy2, px1, px2, py1, py2).
struct TwoBody {
  static constexpr Eigen::Index kDim = 8;
  template <typename T>
  static Var<T> Energy(const Var<T>& x) {
    const Var<T> dx = ad::slice_cols(x, 0, 1) - ad::slice_cols(x, 1, 1);
    const Var<T> dy = ad::slice_cols(x, 2, 1) - ad::slice_cols(x, 3, 1);
    const Var<T> kinetic = ad::scale(ad::sum_cols(ad::square(ad::slice_cols(x, 4, 4))), T(0.5));
    return kinetic - ad::pow(ad::square(dx) + ad::square(dy), T(-0.5));
  }
  template <typename T>
  static Matrix<T> Gradient(const Matrix<T>& x) {
    Matrix<T> g(x.rows(), 8);
    using Column = Eigen::Array<T, Eigen::Dynamic, 1>;
    const Column dx = x.col(0) - x.col(1), dy = x.col(2) - x.col(3);
    const Column inv_r3 = (dx.square() + dy.square()).pow(T(-1.5));
    g.col(0) = dx * inv_r3;
    g.col(1) = -dx * inv_r3;
    g.col(2) = dy * inv_r3;
    g.col(3) = -dy * inv_r3;
    g.rightCols(4) = x.rightCols(4);
    return g;
  }
  // As the task draws them: body 1 at pos ~ U[0.5, 1.5]^2, body 2 at -pos, near-circular momenta.
  static Matrix<double> Sample(Eigen::Index rows) {
    const Matrix<double> pos = Uniform(rows, 2, 3, 0.5, 1.5), noise = Uniform(rows, 4, 4, -1, 1);
    Matrix<double> x(rows, 8);
    for (Eigen::Index i = 0; i < rows; ++i) {
      const double r15 = std::pow(pos.row(i).norm(), 1.5);
      const double vx = -pos(i, 1) / (2 * r15), vy = pos(i, 0) / (2 * r15);
      x.row(i) << pos(i, 0), -pos(i, 0), pos(i, 1), -pos(i, 1), vx, -vx, vy, -vy;
      x.row(i).tail(4) += 0.05 * noise.row(i);
    }
    return x;
  }
};

constexpr Eigen::Index kGradBatch = 750;

// Error of a computed gradient against the analytic one, evaluated in double at the same
// (T-rounded) states: the largest absolute error, and that relative to the largest |dH/dx|.
template <typename System, typename T>
void ReportError(benchmark::State& state, const Matrix<T>& x, const Matrix<T>& g) {
  const Matrix<double> exact = System::Gradient(Matrix<double>(x.template cast<double>()));
  const double error = (g.template cast<double>() - exact).cwiseAbs().maxCoeff();
  state.counters["max_error"] = error;
  state.counters["rel_error"] = error / exact.cwiseAbs().maxCoeff();
  state.SetItemsProcessed(state.iterations() * x.rows());
}

template <typename T, typename System>
void BM_GradH_Autodiff(benchmark::State& state) {
  const Var<T> x = Var<T>::leaf(System::Sample(kGradBatch).template cast<T>());
  Matrix<T> g;
  for (auto _ : state) {
    ad::TapeScope scope;
    g = ad::grad<T>({ad::sum(System::template Energy<T>(x))}, {x})[0].value();
    benchmark::DoNotOptimize(g.data());
  }
  ReportError<System>(state, x.value(), g);
}

// Arg: k, the step h = 10^-k. Central differences, 2 * dim evaluations of H in ops (no grad).
template <typename T, typename System>
void BM_GradH_FiniteDiff(benchmark::State& state) {
  const T h = static_cast<T>(std::pow(10.0, -double(state.range(0))));
  const Matrix<T> x0 = System::Sample(kGradBatch).template cast<T>();
  Matrix<T> g(x0.rows(), System::kDim), shifted = x0;
  for (auto _ : state) {
    ad::TapeScope scope;
    ad::NoGradGuard values_only;
    for (Eigen::Index j = 0; j < System::kDim; ++j) {
      shifted.col(j).array() = x0.col(j).array() + h;
      const Matrix<T> plus = System::template Energy<T>(Var<T>::constant(shifted)).value();
      shifted.col(j).array() = x0.col(j).array() - h;
      const Matrix<T> minus = System::template Energy<T>(Var<T>::constant(shifted)).value();
      shifted.col(j) = x0.col(j);
      g.col(j) = (plus - minus) / (T(2) * h);
    }
    benchmark::DoNotOptimize(g.data());
  }
  ReportError<System>(state, x0, g);
  state.counters["h"] = double(h);
}

template <typename T, typename System>
void BM_GradH_Analytic(benchmark::State& state) {
  const Matrix<T> x = System::Sample(kGradBatch).template cast<T>();
  Matrix<T> g;
  for (auto _ : state) {
    g = System::template Gradient<T>(x);
    benchmark::DoNotOptimize(g.data());
  }
  ReportError<System>(state, x, g);
}

// Microsecond cases: 0.1 s per repetition is plenty and keeps the whole sweep short.
#define HNN_GRAD_H_BENCHMARKS(T, System)                                                         \
  BENCHMARK_TEMPLATE(BM_GradH_Analytic, T, System)->MinTime(0.1)->Unit(benchmark::kMicrosecond); \
  BENCHMARK_TEMPLATE(BM_GradH_Autodiff, T, System)->MinTime(0.1)->Unit(benchmark::kMicrosecond); \
  BENCHMARK_TEMPLATE(BM_GradH_FiniteDiff, T, System)                                             \
      ->ArgName("k")                                                                             \
      ->DenseRange(1, 10, 1)                                                                     \
      ->MinTime(0.1)                                                                             \
      ->Unit(benchmark::kMicrosecond);
HNN_GRAD_H_BENCHMARKS(float, Pendulum)
HNN_GRAD_H_BENCHMARKS(double, Pendulum)
HNN_GRAD_H_BENCHMARKS(float, TwoBody)
HNN_GRAD_H_BENCHMARKS(double, TwoBody)
#undef HNN_GRAD_H_BENCHMARKS

// ---- 3. the Lagrangian network's ops ---------------------------------------------------------

// Args: rows R, block size n. One iteration: x = batched_solve(A, b) over R diagonally dominant
// n x n blocks, and the gradient of sum(x^2) with respect to A and b (the adjoint solve and the
// outer product), in a reused TapeScope.
template <typename T>
void BM_BatchedSolve(benchmark::State& state) {
  const Eigen::Index rows = state.range(0), n = state.range(1);
  Matrix<double> a = Uniform(rows, n * n, 30, -0.5, 0.5);
  for (Eigen::Index r = 0; r < rows; ++r)
    for (Eigen::Index i = 0; i < n; ++i) a(r, i * n + i) += 2.0;
  const std::vector<Var<T>> inputs = {Var<T>::leaf(a.cast<T>()),
                                      Var<T>::leaf(Uniform(rows, n, 31, -1, 1).cast<T>())};
  std::vector<Var<T>> grads;
  for (auto _ : state) {
    ad::TapeScope scope;
    const Var<T> x = ad::batched_solve(inputs[0], inputs[1]);
    ad::grad_into(ad::sum(ad::square(x)), inputs, grads);
    benchmark::DoNotOptimize(grads.front().value().data());
  }
  state.SetItemsProcessed(state.iterations() * rows);
}

BENCHMARK_TEMPLATE(BM_BatchedSolve, double)
    ->ArgNames({"rows", "n"})
    ->Args({512, 2})
    ->Args({512, 4})
    ->Unit(benchmark::kMicrosecond);
BENCHMARK_TEMPLATE(BM_BatchedSolve, float)
    ->ArgNames({"rows", "n"})
    ->Args({512, 2})
    ->Args({512, 4})
    ->Unit(benchmark::kMicrosecond);

// Args: rows R. One iteration: the R per-row 4x4 Hessians of a 4-128-128-1 softplus MLP
// (a gradient with create_graph, then 4 reverse passes over it), values only.
template <typename T>
void BM_RowHessian(benchmark::State& state) {
  const Eigen::Index rows = state.range(0);
  const std::vector<Eigen::Index> sizes = {4, 128, 128, 1};
  std::vector<Var<T>> params;
  for (std::size_t l = 0; l + 1 < sizes.size(); ++l) {
    params.push_back(Var<T>::leaf(Orthogonal(sizes[l], sizes[l + 1], 40 + l).cast<T>()));
    params.push_back(Var<T>::leaf(Uniform(1, sizes[l + 1], 50 + l, -0.1, 0.1).cast<T>()));
  }
  const Var<T> x = Var<T>::leaf(Uniform(rows, 4, 60, -1, 1).cast<T>());
  for (auto _ : state) {
    ad::TapeScope scope;
    Var<T> h = x;
    for (std::size_t l = 0; l + 2 < params.size(); l += 2)
      h = ad::softplus(ad::linear(h, params[l], params[l + 1]));
    const Var<T> blocks = ad::row_hessian(ad::linear(h, params[4], params[5]), x);
    benchmark::DoNotOptimize(blocks.value().data());
  }
  state.SetItemsProcessed(state.iterations() * rows);
}

BENCHMARK_TEMPLATE(BM_RowHessian, double)->ArgName("rows")->Arg(512)->Unit(benchmark::kMillisecond);
BENCHMARK_TEMPLATE(BM_RowHessian, float)->ArgName("rows")->Arg(512)->Unit(benchmark::kMillisecond);

// ---- 4. the fused kernels' matrix product ----------------------------------------------------

// Args: backend (0 the engine's kernel, 1 OpenBLAS), orientation (0 A B, 1 A B^T, 2 A^T B), and
// C's m x n with the shared k. One iteration: one product on one thread, beta 0. The counter is
// GFLOP/s (2mnk per product); roofline_bench's BM_FmaPeak gives the core's peak to divide by.
template <typename T>
void BM_Gemm(benchmark::State& state) {
  const bool blas = state.range(0) == 1;
  const bool ta = state.range(1) == 2, tb = state.range(1) == 1;
  const Eigen::Index m = state.range(2), n = state.range(3), k = state.range(4);
  const Matrix<T> a = Uniform(ta ? k : m, ta ? m : k, 70, -1, 1).cast<T>();
  const Matrix<T> b = Uniform(tb ? n : k, tb ? k : n, 71, -1, 1).cast<T>();
  Matrix<T> c(m, n);
  const hnn::ad::detail::GemmOperands<T> g{m,        n,        k,  a.data(), a.cols(), ta,
                                           b.data(), b.cols(), tb, c.data(), n,        T(0)};
  if (!blas && !hnn::ad::detail::simd_gemm(g)) {
    state.SkipWithError("the engine's kernel does not take this product in this build");
    return;
  }
  for (auto _ : state) {
    if (blas) {
#ifdef HNN_HAVE_OPENBLAS
      hnn::ad::detail::blas_gemm(g);
#else
      state.SkipWithError("this build has no OpenBLAS");
      return;
#endif
    } else {
      hnn::ad::detail::simd_gemm(g);
    }
    benchmark::DoNotOptimize(c.data());
  }
  state.counters["GFLOP/s"] = benchmark::Counter(double(2 * m * n * k) * double(state.iterations()),
                                                 benchmark::Counter::kIsRate);
}

// The CHNN and D-HNN steps' float products (a thread's 100 rows of a 256-wide layer) and the
// spring step's double ones (375 rows of a 200-wide layer), in all three orientations.
void GemmShapes(benchmark::internal::Benchmark* b, std::int64_t m, std::int64_t width) {
  b->ArgNames({"blas", "orient", "m", "n", "k"});
  for (int orientation : {0, 1, 2}) {
    for (int backend : {0, 1}) {
      if (orientation == 2) {
        b->Args({backend, orientation, width, width, m});
      } else {
        b->Args({backend, orientation, m, width, width});
      }
    }
  }
  b->Unit(benchmark::kMicrosecond);
}

BENCHMARK_TEMPLATE(BM_Gemm, float)->Apply([](auto* b) { GemmShapes(b, 100, 256); });
BENCHMARK_TEMPLATE(BM_Gemm, double)->Apply([](auto* b) { GemmShapes(b, 375, 200); });

}  // namespace

BENCHMARK_MAIN();
