#pragma once
// The machine's raw FMA peak, measured: FMAs on independent accumulators in registers, on as
// many threads at once as asked. roofline_bench (BM_FmaPeak) and bench/compare's hnn_train_step
// (--fma-peak) report steps as fractions of it.

#include <immintrin.h>

#include <algorithm>
#include <chrono>
#include <thread>
#include <type_traits>
#include <vector>

namespace hnn::bench {

// FMAs on independent accumulators in registers (enough of them to cover the FMA latency on
// two pipes); returns the FLOPs done.
template <typename T>
double fma_loop(long iterations) {
#if defined(__AVX512F__)
  constexpr int lanes = 64 / sizeof(T);
  const auto fma = [](auto a, auto b, auto c) {
    if constexpr (std::is_same_v<T, float>)
      return _mm512_fmadd_ps(a, b, c);
    else
      return _mm512_fmadd_pd(a, b, c);
  };
  const auto set = [](T v) {
    if constexpr (std::is_same_v<T, float>)
      return _mm512_set1_ps(v);
    else
      return _mm512_set1_pd(v);
  };
  using V = decltype(set(T(0)));
#elif defined(__AVX2__) && defined(__FMA__)
  constexpr int lanes = 32 / sizeof(T);
  const auto fma = [](auto a, auto b, auto c) {
    if constexpr (std::is_same_v<T, float>)
      return _mm256_fmadd_ps(a, b, c);
    else
      return _mm256_fmadd_pd(a, b, c);
  };
  const auto set = [](T v) {
    if constexpr (std::is_same_v<T, float>)
      return _mm256_set1_ps(v);
    else
      return _mm256_set1_pd(v);
  };
  using V = decltype(set(T(0)));
#else
#error "the FMA peak needs AVX2+FMA or AVX-512 (build with -march=native)"
#endif
  constexpr int kAcc = 12;
  V acc[kAcc];
  for (int i = 0; i < kAcc; ++i) acc[i] = set(T(i));
  const V a = set(T(0.999999)), b = set(T(1e-7));
  for (long it = 0; it < iterations; ++it) {
    for (int i = 0; i < kAcc; ++i) acc[i] = fma(acc[i], a, b);  // not foldable: kept
  }
  // The result must be observable, or the loop is dead code.
  asm volatile("" : : "r"(&acc) : "memory");
  return 2.0 * lanes * kAcc * double(iterations);
}

// Peak FLOP/s of `threads` threads running the FMA loop at once (best of a few tries).
template <typename T>
double fma_peak(int threads) {
  constexpr long kIterations = 20'000'000;
  double best = 0;
  for (int attempt = 0; attempt < 5; ++attempt) {
    const auto start = std::chrono::steady_clock::now();
    std::vector<double> done(std::size_t(threads), 0.0);
    std::vector<std::thread> pool;
    for (int t = 0; t < threads; ++t) {
      pool.emplace_back([&done, t] { done[std::size_t(t)] = fma_loop<T>(kIterations); });
    }
    for (std::thread& t : pool) t.join();
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    double flops = 0;
    for (double f : done) flops += f;
    best = std::max(best, flops / seconds);
  }
  return best;
}

}  // namespace hnn::bench
