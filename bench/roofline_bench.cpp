// How close a training step is to what the hardware allows. For each task's step shape (the
// paper's tanh MLP, input -> 200 -> 200 -> out, at the task's batch) it reports:
//   flops       the step's floating-point operations, counted from the shapes (GEMMs and the
//               elementwise work of the fused kernels; Adam's few per parameter);
//   GFLOP/s     flops / step time;
//   gemm_GF/s   the rate of the engine's own GEMM (ad::matmul, same backend and thread split)
//               at the step's largest shapes, measured here, before the step;
//   of_gemm     the step's GEMM time at that rate / step time: 1 means the step is nothing but
//               GEMMs running at their standalone speed;
//   of_peak     flops / (raw FMA peak x step time), the peak measured by a register-only FMA
//               loop on as many threads (BM_FmaPeak reports it on its own).
// The pixel-pendulum step (200 pairs of frames through the 1568-200-200-200-2 autoencoder and
// back, with the latent HNN or baseline) is reported the same way (BM_PixelRoofline).
// Wall time; run with --benchmark_repetitions=5 --benchmark_report_aggregates_only=true.

#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <random>
#include <vector>

#include "autodiff/autodiff.h"
#include "bench/fma_peak.h"
#include "nn/nn.h"
#include "tasks/pixel/model.h"

namespace ad = hnn::ad;
namespace nn = hnn::nn;
namespace pixel = hnn::tasks::pixel;

using hnn::bench::fma_peak;

namespace {

// ---- the step's shapes and FLOPs -----------------------------------------------------------

struct StepShape {
  const char* task;
  long rows;  // the batch
  long dim;   // the state's dimension
};
constexpr StepShape kShapes[] = {{"spring", 750, 2}, {"two-body", 200, 8}, {"three-body", 600, 12}};
constexpr long kWidth = 200;

// FLOPs of one HNN step (fused forward, input gradient and their backward: see the derivation
// at the top of autodiff/mlp_kernels.cpp) or baseline step (forward and backward), with two hidden
// layers of width n. GEMM m x n x k counts 2mnk.
double step_flops(const StepShape& s, nn::ModelKind kind) {
  const double R = double(s.rows), d = double(s.dim), n = kWidth;
  const double params = d * n + n + n * n + n + n * (kind == nn::ModelKind::kHnn ? 1 : d);
  double gemm = 0, elementwise = 0;
  if (kind == nn::ModelKind::kHnn) {
    // forward h1 = x W1, h2 = h1 W2; a1 = d2 W2^T, dH/dx = d1 W1^T;
    // backward dbar1 = G W1, dW1 += G^T d1, dbar2 = abar1 W2, dW2 += abar1^T d2,
    // dW2 += h1^T zbar2, hbar1 += zbar2 W2^T, dW1 += x^T zbar1.
    gemm = 2 * R * (d * n + n * n) + 2 * R * (n * n + n * d) + 2 * R * (d * n + d * n) +
           2 * R * (4 * n * n) + 2 * R * d * n;
    elementwise = R * n * 2 * 20;  // tanh, s, d, hbar, abar, zbar, column sums: ~20 per entry
  } else {
    gemm = 2 * R * (d * n + n * n + n * d) * 3 - 2 * R * d * n;  // forward, dW, dH (no dx)
    elementwise = R * n * 2 * 12;
  }
  return gemm + elementwise + 12 * params;  // Adam: about 12 per parameter
}

// Time of the step's big GEMMs (R x n x n, four or six of them) through ad::matmul.
template <typename T>
double gemm_seconds(const StepShape& s, nn::ModelKind kind, double& rate) {
  std::mt19937_64 rng(5);
  const auto a = ad::Var<T>::constant(nn::random_normal<T>(s.rows, kWidth, rng, 0, 1));
  const auto w = ad::Var<T>::constant(nn::random_normal<T>(kWidth, kWidth, rng, 0, 1));
  const int count = kind == nn::ModelKind::kHnn ? 6 : 3;
  std::vector<double> times;
  for (int rep = 0; rep < 40; ++rep) {
    ad::TapeScope scope;
    ad::NoGradGuard values;
    const auto start = std::chrono::steady_clock::now();
    for (int g = 0; g < count; ++g) {
      // the kernels' three layouts: h W, d W^T, and h^T d
      if (g % 3 == 0) benchmark::DoNotOptimize(ad::matmul(a, w).value().data());
      if (g % 3 == 1) benchmark::DoNotOptimize(ad::matmul(a, w, false, true).value().data());
      if (g % 3 == 2) benchmark::DoNotOptimize(ad::matmul(a, a, true, false).value().data());
    }
    times.push_back(
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  }
  std::nth_element(times.begin(), times.begin() + 20, times.end());
  rate = count * 2.0 * double(s.rows) * kWidth * kWidth / times[20];
  return times[20];
}

template <typename T>
void BM_StepRoofline(benchmark::State& state, nn::ModelKind kind) {
  const StepShape& shape = kShapes[state.range(0)];
  const int threads = int(state.range(1));
  state.SetLabel(shape.task);
  ad::set_num_threads(threads);
  std::mt19937_64 rng(1);
  nn::DynamicsConfig config;
  config.model = kind;
  config.dim = int(shape.dim);
  const auto model = nn::make_model<T>(config, rng);
  nn::Adam<T> adam(model->parameters(), {.lr = 1e-3, .weight_decay = 1e-4});
  const ad::Var<T> x =
      ad::Var<T>::leaf(nn::random_normal<T>(shape.rows, shape.dim, rng, 0, 1), false);
  const ad::Var<T> target =
      ad::Var<T>::leaf(nn::random_normal<T>(shape.rows, shape.dim, rng, 0, 1), false);
  double gemm_rate = 0;
  const double gemm_time = gemm_seconds<T>(shape, kind, gemm_rate);
  std::vector<ad::Var<T>> grads;
  for (auto _ : state) {
    ad::TapeScope scope;
    const ad::Var<T> loss = nn::mse(model->time_derivative(x), target);
    ad::grad_into(loss, adam.parameters(), grads);
    adam.step(grads);
  }
  const double flops = step_flops(shape, kind);
  const double peak = fma_peak<T>(threads);
  state.counters["flops"] = flops;
  state.counters["GFLOP/s"] =
      benchmark::Counter(flops * 1e-9, benchmark::Counter::kIsIterationInvariantRate);
  state.counters["gemm_GF/s"] = gemm_rate * 1e-9;
  state.counters["peak_GF/s"] = peak * 1e-9;
  // Fractions need the step time: per-iteration seconds are only known after the loop.
  state.counters["of_gemm"] =
      benchmark::Counter(gemm_time, benchmark::Counter::kIsIterationInvariantRate);
  state.counters["of_peak"] =
      benchmark::Counter(flops / peak, benchmark::Counter::kIsIterationInvariantRate);
  ad::set_num_threads(2);
}

template <typename T>
void BM_HnnRoofline(benchmark::State& state) {
  BM_StepRoofline<T>(state, nn::ModelKind::kHnn);
}
template <typename T>
void BM_BaselineRoofline(benchmark::State& state) {
  BM_StepRoofline<T>(state, nn::ModelKind::kBaseline);
}

// ---- the pixel-pendulum step: the residual ReLU autoencoder with a latent model ------------

constexpr long kPixelRows = 200, kPixels = pixel::kPairPixels, kLatent = 2;

// GEMM FLOPs of one pixel step: two encodes (x and x_next) and one decode forward; backward
// gives every weight gradient and every input gradient but the first encoder layer's (the
// frames are constants). Plus the latent model's own step and Adam on the autoencoder.
double pixel_step_flops(nn::ModelKind kind) {
  const double R = kPixelRows, D = kPixels, n = kWidth, z = kLatent;
  const double half = 2 * (D * n + 2 * n * n + n * z);  // one encode or decode, per row
  const double forward = 3 * half;
  const double backward = 2 * forward - 2 * (2 * D * n);
  const double params = 2 * (D * n + n + 2 * (n * n + n) + n * z) + z + D;
  const StepShape latent{"latent", kPixelRows, kLatent};
  return R * (forward + backward) + step_flops(latent, kind) + 12 * params;
}

// The rate of ad::matmul at the autoencoder's big shapes (R x D x n in its three layouts).
template <typename T>
double pixel_gemm_rate() {
  std::mt19937_64 rng(5);
  const auto x = ad::Var<T>::constant(nn::random_normal<T>(kPixelRows, kPixels, rng, 0, 1));
  const auto w = ad::Var<T>::constant(nn::random_normal<T>(kPixels, kWidth, rng, 0, 1));
  const auto g = ad::Var<T>::constant(nn::random_normal<T>(kPixelRows, kWidth, rng, 0, 1));
  std::vector<double> times;
  for (int rep = 0; rep < 20; ++rep) {
    ad::TapeScope scope;
    ad::NoGradGuard values;
    const auto start = std::chrono::steady_clock::now();
    benchmark::DoNotOptimize(ad::matmul(x, w).value().data());               // x W
    benchmark::DoNotOptimize(ad::matmul(g, w, false, true).value().data());  // g W^T
    benchmark::DoNotOptimize(ad::matmul(x, g, true, false).value().data());  // x^T g
    times.push_back(
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  }
  std::nth_element(times.begin(), times.begin() + 10, times.end());
  return 3 * 2.0 * kPixelRows * kPixels * kWidth / times[10];
}

// The trainer's step (tasks/experiments/pixel_pendulum.cpp) on random frames: loss, gradients,
// Adam.
template <typename T>
void BM_PixelRoofline(benchmark::State& state) {
  const auto kind = state.range(0) == 0 ? nn::ModelKind::kHnn
                                        : nn::ModelKind::kBaseline;  // model:0 HNN, 1 baseline
  const int threads = int(state.range(1));
  state.SetLabel(kind == nn::ModelKind::kHnn ? "pixel hnn" : "pixel baseline");
  ad::set_num_threads(threads);
  std::mt19937_64 rng(1);
  pixel::PixelModel<T> model(pixel::PixelConfig{}, kind, rng);
  const std::vector<ad::Var<T>> params = model.parameters();
  nn::Adam<T> adam(params, {.lr = 1e-3, .weight_decay = 1e-5});
  const auto frames = [&] {
    ad::Matrix<T> m = nn::random_normal<T>(kPixelRows, kPixels, rng, 0, 1);
    return ad::Var<T>::constant(m.cwiseAbs().cwiseMin(T(1)));
  };
  const ad::Var<T> x = frames(), x_next = frames();
  const double gemm_rate = pixel_gemm_rate<T>();
  std::vector<ad::Var<T>> grads;
  for (auto _ : state) {
    ad::TapeScope scope;
    const ad::Var<T> loss = ad::mean(pixel::pixel_loss(model, x, x_next, 0.1).total);
    ad::grad_into(loss, params, grads);
    adam.step(grads);
  }
  const double flops = pixel_step_flops(kind);
  const double peak = fma_peak<T>(threads);
  state.counters["flops"] = flops;
  state.counters["GFLOP/s"] =
      benchmark::Counter(flops * 1e-9, benchmark::Counter::kIsIterationInvariantRate);
  state.counters["gemm_GF/s"] = gemm_rate * 1e-9;
  state.counters["peak_GF/s"] = peak * 1e-9;
  // Almost all of this step is GEMMs of those shapes: of_gemm is the whole step's FLOPs at
  // that rate over the step time.
  state.counters["of_gemm"] =
      benchmark::Counter(flops / gemm_rate, benchmark::Counter::kIsIterationInvariantRate);
  state.counters["of_peak"] =
      benchmark::Counter(flops / peak, benchmark::Counter::kIsIterationInvariantRate);
  ad::set_num_threads(2);
}

template <typename T>
void BM_FmaPeak(benchmark::State& state) {
  const int threads = int(state.range(0));
  double peak = 0;
  for (auto _ : state) peak = fma_peak<T>(threads);
  state.counters["peak_GF/s"] = peak * 1e-9;
}

void shapes_and_threads(benchmark::internal::Benchmark* b) {
  b->ArgNames({"shape", "threads"});
  for (long s = 0; s < long(std::size(kShapes)); ++s) {
    for (long t : {1, 2}) b->Args({s, t});
  }
  b->Unit(benchmark::kMillisecond)->UseRealTime();
}

}  // namespace

BENCHMARK(BM_FmaPeak<float>)->Arg(1)->Arg(2)->Iterations(1)->UseRealTime();
BENCHMARK(BM_FmaPeak<double>)->Arg(1)->Arg(2)->Iterations(1)->UseRealTime();
BENCHMARK(BM_HnnRoofline<float>)->Apply(shapes_and_threads);
BENCHMARK(BM_HnnRoofline<double>)->Apply(shapes_and_threads);
BENCHMARK(BM_BaselineRoofline<float>)->Apply(shapes_and_threads);
BENCHMARK(BM_BaselineRoofline<double>)->Apply(shapes_and_threads);

BENCHMARK(BM_PixelRoofline<float>)
    ->ArgNames({"model", "threads"})
    ->ArgsProduct({{0, 1}, {1, 2}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_PixelRoofline<double>)
    ->ArgNames({"model", "threads"})
    ->ArgsProduct({{0, 1}, {1, 2}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

BENCHMARK_MAIN();
