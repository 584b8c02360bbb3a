// What a parallel region of the engine costs on this machine (autodiff/parallel.h), the figure
// the thread policy is decided from (docs/threads.md):
//  - Empty: parallel_for(2) of parts that do nothing, back to back: the pure hand-off, with
//    the worker still watching for the next job (Note [Brief spin] in parallel.cpp).
//  - AfterGap: the same after the caller has worked alone for `gap` microseconds, so the worker
//    has gone to sleep when the gap is longer than its watch: the cost of a wake-up.
//  - Matmul: one matmul op (rows x 256 times 256 x 256, the D-HNN's hidden layer) on one and
//    on two threads, over the row counts the training steps use: where splitting starts to pay.
// Run with --benchmark_filter and compare the 1-thread and 2-thread rows of each size.

#include <benchmark/benchmark.h>

#include <chrono>

#include "autodiff/autodiff.h"
#include "autodiff/parallel.h"

namespace ad = hnn::ad;

namespace {

void Empty(benchmark::State& state) {
  ad::set_num_threads(int(state.range(0)));
  for (auto _ : state) {
    ad::parallel_for(2, [](int) {});
  }
}
BENCHMARK(Empty)->Arg(1)->Arg(2)->UseRealTime();

void BusyWait(std::chrono::microseconds d) {
  const auto until = std::chrono::steady_clock::now() + d;
  while (std::chrono::steady_clock::now() < until) {
  }
}

// Reports the region's cost alone: the gap is paused out of the timing.
void AfterGap(benchmark::State& state) {
  ad::set_num_threads(2);
  const std::chrono::microseconds gap(state.range(0));
  for (auto _ : state) {
    state.PauseTiming();
    BusyWait(gap);
    state.ResumeTiming();
    ad::parallel_for(2, [](int) {});
  }
}
BENCHMARK(AfterGap)->Arg(10)->Arg(40)->Arg(100)->Arg(1000)->UseRealTime();

// One matmul op as a step records it (inside a TapeScope), so the split is the op's own.
template <typename T>
void Matmul(benchmark::State& state) {
  const Eigen::Index rows = state.range(0), width = 256;
  ad::set_num_threads(int(state.range(1)));
  const ad::Var<T> a = ad::Var<T>::constant(ad::Matrix<T>::Random(rows, width));
  const ad::Var<T> w = ad::Var<T>::constant(ad::Matrix<T>::Random(width, width));
  for (auto _ : state) {
    ad::TapeScope scope;
    benchmark::DoNotOptimize(ad::matmul(a, w).value().data());
  }
  state.counters["flops"] = benchmark::Counter(2.0 * double(rows * width * width),
                                               benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(Matmul<float>)->ArgsProduct({{32, 64, 128, 256, 512}, {1, 2}})->UseRealTime();
BENCHMARK(Matmul<double>)->ArgsProduct({{32, 64, 128, 256, 512}, {1, 2}})->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
