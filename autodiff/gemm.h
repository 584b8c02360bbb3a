#pragma once
// Internal: the matrix product of the fused kernels, C = op(A) op(B) + beta C on row-major
// matrices or row blocks of them. The engine's own kernel on AVX-512 builds, for the shapes where
// it beats OpenBLAS (gemm_kernel.cpp); otherwise OpenBLAS's single-threaded GEMM when the build
// found it (about 1.4x Eigen's at the MLP shapes on this project's machines; the kernels split
// batches across threads themselves), Eigen's otherwise.

#include <Eigen/Core>
#include <atomic>
#include <cstdint>

#ifdef HNN_HAVE_OPENBLAS
#include <cblas.h>
#endif

namespace hnn::ad::detail {

/// Output widths below this go through gemm's narrow path.
inline constexpr Eigen::Index kNarrow = 16;
/// Elements of the narrow path's B^T on the stack (80 KiB of double): kNarrow x 640.
inline constexpr Eigen::Index kStackedNarrow = kNarrow * 640;

/// Keeps OpenBLAS from starting threads of its own under the calling thread: gemm calls it on
/// every thread (Note [One BLAS thread per engine thread] in gemm.cpp).
void init_gemm();
/// Whether the calling thread has run init_gemm: checked inline, so a GEMM pays no call for it.
inline thread_local bool t_gemm_ready = false;

/// One product C = op(A) op(B) + beta C for simd_gemm: row-major data with their row strides.
template <typename T>
struct GemmOperands {
  Eigen::Index m, n, k;
  const T* a;
  Eigen::Index lda;
  bool ta;
  const T* b;
  Eigen::Index ldb;
  bool tb;
  T* c;
  Eigen::Index ldc;
  T beta;
};
/// The product by the engine's own register-tiled kernel on AVX-512 builds (Note [A GEMM without
/// packing] in gemm_kernel.cpp), where it suits the shape; false, doing nothing, elsewhere.
template <typename T>
bool simd_gemm(const GemmOperands<T>& g);

#ifdef HNN_HAVE_OPENBLAS
/// The product by OpenBLAS's GEMM on the calling thread alone (the general path of gemm below;
/// autodiff_bench measures the kernel against it).
template <typename T>
void blas_gemm(const GemmOperands<T>& g) {
  if (!t_gemm_ready) init_gemm();
  const auto op = [](bool t) { return t ? CblasTrans : CblasNoTrans; };
  if constexpr (std::is_same_v<T, float>) {
    cblas_sgemm(CblasRowMajor, op(g.ta), op(g.tb), int(g.m), int(g.n), int(g.k), 1.0f, g.a,
                int(g.lda), g.b, int(g.ldb), g.beta, g.c, int(g.ldc));
  } else {
    cblas_dgemm(CblasRowMajor, op(g.ta), op(g.tb), int(g.m), int(g.n), int(g.k), 1.0, g.a,
                int(g.lda), g.b, int(g.ldb), g.beta, g.c, int(g.ldc));
  }
}
#endif

/// Whether a GemmFlopCounter (flop_count.h) is alive, and its count.
extern std::atomic<bool> g_counting_flops;
void count_flops(std::uint64_t flops);

template <typename A, typename B, typename C>
void gemm(const A& a, bool ta, const B& b, bool tb, C&& c, typename A::Scalar beta = 0) {
  using T = typename A::Scalar;
  static_assert(std::is_same_v<T, typename B::Scalar> && A::IsRowMajor && B::IsRowMajor);
  const Eigen::Index m = c.rows(), n = c.cols(), k = ta ? a.rows() : a.cols();
  eigen_assert((ta ? a.cols() : a.rows()) == m && (tb ? b.rows() : b.cols()) == n &&
               (tb ? b.cols() : b.rows()) == k);
  if (g_counting_flops.load(std::memory_order_relaxed)) count_flops(std::uint64_t(2 * m * n * k));
  GemmOperands<T> g{m,
                    n,
                    k,
                    a.data(),
                    a.outerStride(),
                    ta,
                    b.data(),
                    b.outerStride(),
                    tb,
                    c.data(),
                    c.outerStride(),
                    beta};
  // One row and narrow outputs keep the paths below (GEMV; B^T for OpenBLAS's small kernel).
  if (m > 1 && n >= kNarrow && simd_gemm(g)) return;
#ifdef HNN_HAVE_OPENBLAS
  if (m == 1) {
    if (!t_gemm_ready) init_gemm();  // (blas_gemm below sees to its own)
    // One row (a rollout's single state): GEMM packs all of B for it, and its packing and kernel
    // took 83% of an evaluation on the spring's 200 x 200 layers; GEMV reads B once.
    // c^T = op(B)^T a^T.
    const int inc_a = ta ? int(g.lda) : 1;
    const auto b_op = tb ? CblasNoTrans : CblasTrans;
    const int rows_b = int(tb ? n : k), cols_b = int(tb ? k : n);
    if constexpr (std::is_same_v<T, float>) {
      cblas_sgemv(CblasRowMajor, b_op, rows_b, cols_b, 1.0f, g.b, int(g.ldb), g.a, inc_a, beta, g.c,
                  1);
    } else {
      cblas_dgemv(CblasRowMajor, b_op, rows_b, cols_b, 1.0, g.b, int(g.ldb), g.a, inc_a, beta, g.c,
                  1);
    }
    return;
  }
  if (!ta && !tb && n < kNarrow) {
    // OpenBLAS 0.3.21's small-matrix kernel for A B with a narrow B (an MLP's last layer)
    // mallocs on every call; A (B^T)^T takes another path, and B^T costs at most kNarrow x k.
    // B^T lives on the stack up to kStackedNarrow elements: a thread-local copy would be sized
    // by whichever thread first runs a part, and parts go to whoever claims them (Note [Claimed
    // parts]), so a worker could allocate it in any later step.
    using RowMatrix = Eigen::Matrix<T, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
    // (A thread-local is set up, and registered for destruction with a calloc, where control
    // first passes its declaration: hence inside the branch.)
    alignas(64) T stacked[kStackedNarrow];
    T* b_t = stacked;
    if (n * k > kStackedNarrow) {
      thread_local RowMatrix wide;  // B^T of more than kStackedNarrow elements (widths over 640)
      wide.resize(n, k);
      b_t = wide.data();
    }
    Eigen::Map<RowMatrix>(b_t, n, k) = b.transpose();
    g.b = b_t;
    g.ldb = k;
    g.tb = true;
  }
  blas_gemm(g);
#else
  const auto product = [&](auto&& lhs, auto&& rhs) {
    if (beta == T(0)) {
      c.noalias() = lhs * rhs;
    } else {
      if (beta != T(1)) c *= beta;
      c.noalias() += lhs * rhs;
    }
  };
  if (!ta && !tb) product(a, b);
  if (!ta && tb) product(a, b.transpose());
  if (ta && !tb) product(a.transpose(), b);
  if (ta && tb) product(a.transpose(), b.transpose());
#endif
}

}  // namespace hnn::ad::detail
