// One full-batch training step of the paper's models on the mass-spring task (750 x 2 inputs,
// 2-200-200-out tanh MLP): forward, the HNN's inner gradient, loss, parameter gradients and
// Adam, in float and double, on 1 and 2 threads (wall time: the workers' CPU time is not the
// caller's). Also the learned field's evaluation, as rollouts call it, and one training step of
// the rollout loss (tasks/train/rollout_objective.h) through each integrator, and Adam alone on
// the pixel model's 0.7 M parameters, where its passes over memory are a fifth of the step.

#include <benchmark/benchmark.h>

#include <cmath>
#include <random>

#include "autodiff/autodiff.h"
#include "nn/nn.h"
#include "tasks/train/rollout_objective.h"

namespace ad = hnn::ad;
namespace nn = hnn::nn;

namespace {

// 25 noisy mass-spring trajectories of 30 points: x (750 x 2) and exact dx/dt.
struct Data {
  nn::Matrix<double> x{750, 2}, dxdt{750, 2};
};

Data spring_data() {
  std::mt19937_64 rng(0);
  Data d;
  for (int k = 0; k < 25; ++k) {
    const double angle = 2 * M_PI * nn::uniform01(rng), r = 0.1 + 0.9 * nn::uniform01(rng);
    const nn::Matrix<double> noise = nn::random_normal<double>(30, 2, rng, 0.0, 0.1);
    for (int i = 0; i < 30; ++i) {
      const double t = 3.0 * i / 29, q = r * std::cos(angle - 2 * t),
                   p = r * std::sin(angle - 2 * t);
      d.x.row(k * 30 + i) << q + noise(i, 0), p + noise(i, 1);
      d.dxdt.row(k * 30 + i) << 2 * p, -2 * q;
    }
  }
  return d;
}

template <typename T>
void training_step(benchmark::State& state, nn::ModelKind kind,
                   nn::FieldType field = nn::FieldType::kSolenoidal) {
  ad::set_num_threads(int(state.range(0)));
  const Data data = spring_data();
  nn::DynamicsConfig config;  // the paper's: 2-200-200-out, tanh, orthogonal
  config.model = kind;
  config.field = field;
  std::mt19937_64 rng(1);
  const auto model = nn::make_model<T>(config, rng);
  nn::Adam<T> adam(model->parameters(), {.lr = 1e-3, .weight_decay = 1e-4});
  const ad::Var<T> x = ad::Var<T>::leaf(data.x.cast<T>());
  const ad::Var<T> target = ad::Var<T>::leaf(data.dxdt.cast<T>(), /*requires_grad=*/false);
  double loss = 0;
  std::vector<ad::Var<T>> grads;
  for (auto _ : state) {
    ad::TapeScope scope;  // the step's graph is recycled at the end of each iteration
    const ad::Var<T> l = nn::mse(model->time_derivative(x), target);
    ad::grad_into(l, adam.parameters(), grads);
    adam.step(grads);
    loss = double(l.item());
  }
  benchmark::DoNotOptimize(loss);
  state.counters["loss"] = loss;
}

template <typename T>
void BM_HnnStep(benchmark::State& state) {
  training_step<T>(state, nn::ModelKind::kHnn);
}

// The dissipative HNN (H and D from one MLP, field S_H + grad D): two fused input gradients.
template <typename T>
void BM_DissipativeHnnStep(benchmark::State& state) {
  training_step<T>(state, nn::ModelKind::kHnn, nn::FieldType::kBoth);
}

template <typename T>
void BM_BaselineStep(benchmark::State& state) {
  training_step<T>(state, nn::ModelKind::kBaseline);
}

// field() on 750 states: what an integrator stage costs for a batch of rollouts.
template <typename T>
void BM_HnnField(benchmark::State& state) {
  const Data data = spring_data();
  std::mt19937_64 rng(1);
  const nn::Hnn<T> model(nn::DynamicsConfig{}, rng);
  const nn::Matrix<T> x = data.x.cast<T>();
  ad::set_num_threads(int(state.range(0)));
  for (auto _ : state) benchmark::DoNotOptimize(model.field(x));
}

// One rollout-loss training step of the spring HNN (2-200-200-1): a batch of 128 windows of
// horizon 4 from the 25 trajectories, integrated by the method (range 1), loss, parameter
// gradients through the steps and Adam. Double, 2 threads.
void BM_RolloutStep(benchmark::State& state) {
  ad::set_num_threads(2);
  const Data data = spring_data();
  std::vector<hnn::tasks::Stretch> stretches;
  Eigen::VectorXd t(30);
  for (int i = 0; i < 30; ++i) t(i) = 3.0 * i / 29;
  for (int k = 0; k < 25; ++k) stretches.push_back({t, data.x.middleRows(k * 30, 30)});
  std::mt19937_64 rng(1);
  const auto model = nn::make_model<double>(nn::DynamicsConfig{}, rng);
  const auto method = hnn::tasks::RolloutIntegrator(state.range(0));
  hnn::tasks::RolloutObjective<double> objective(*model, hnn::tasks::rollout_windows(stretches, 4),
                                                 {}, 128, {.lr = 1e-3}, 2, method);
  nn::Adam<double> adam(model->parameters(), {.lr = 1e-3});
  std::vector<ad::Var<double>> grads;
  double loss = 0;
  for (auto _ : state) {
    ad::TapeScope scope;
    objective.sampler().next();
    const ad::Var<double> l = objective.batch_loss();
    ad::grad_into(l, adam.parameters(), grads);
    adam.step(grads);
    loss = l.item();
  }
  state.SetLabel(std::string(hnn::tasks::to_string(method)));
  state.counters["loss"] = loss;
}

// One Adam update of the pixel task's autoencoder (1568-200-200-200-2 and back, weights and
// biases: 0.71 M parameters), with its L2 weight decay. Its buffers (parameters, gradients and
// two moments: 11 MB in float) outgrow the caches, so this measures the passes over memory.
template <typename T>
void BM_AdamUpdate(benchmark::State& state) {
  ad::set_num_threads(int(state.range(0)));
  std::mt19937_64 rng(2);
  std::vector<ad::Var<T>> parameters, grads;
  for (const auto& [rows, cols] : {std::pair{1568, 200},
                                   {200, 200},
                                   {200, 200},
                                   {200, 2},
                                   {2, 200},
                                   {200, 200},
                                   {200, 200},
                                   {200, 1568}}) {
    for (const int r : {rows, 1}) {  // the weight, then its bias
      parameters.push_back(ad::Var<T>::leaf(nn::random_normal<T>(r, cols, rng, 0.0, 0.1)));
      grads.push_back(ad::Var<T>::constant(nn::random_normal<T>(r, cols, rng, 0.0, 1e-3)));
    }
  }
  nn::Adam<T> adam(parameters, {.lr = 1e-3, .weight_decay = 1e-5});
  for (auto _ : state) adam.step(grads);
  std::size_t n = 0;
  for (const auto& p : parameters) n += std::size_t(p.value().size());
  // Read p, g, m, v and write p, m, v: seven streams of the parameters' size at the least.
  state.SetBytesProcessed(std::int64_t(state.iterations() * 7 * n * sizeof(T)));
}

}  // namespace

BENCHMARK(BM_RolloutStep)
    ->Unit(benchmark::kMillisecond)
    ->ArgName("integrator")
    ->DenseRange(0, 3)
    ->UseRealTime();
BENCHMARK(BM_HnnStep<float>)
    ->Unit(benchmark::kMillisecond)
    ->ArgName("threads")
    ->Arg(1)
    ->Arg(2)
    ->UseRealTime();
BENCHMARK(BM_HnnStep<double>)
    ->Unit(benchmark::kMillisecond)
    ->ArgName("threads")
    ->Arg(1)
    ->Arg(2)
    ->UseRealTime();
BENCHMARK(BM_DissipativeHnnStep<float>)
    ->Unit(benchmark::kMillisecond)
    ->ArgName("threads")
    ->Arg(1)
    ->Arg(2)
    ->UseRealTime();
BENCHMARK(BM_DissipativeHnnStep<double>)
    ->Unit(benchmark::kMillisecond)
    ->ArgName("threads")
    ->Arg(1)
    ->Arg(2)
    ->UseRealTime();
BENCHMARK(BM_BaselineStep<float>)
    ->Unit(benchmark::kMillisecond)
    ->ArgName("threads")
    ->Arg(1)
    ->Arg(2)
    ->UseRealTime();
BENCHMARK(BM_BaselineStep<double>)
    ->Unit(benchmark::kMillisecond)
    ->ArgName("threads")
    ->Arg(1)
    ->Arg(2)
    ->UseRealTime();
BENCHMARK(BM_HnnField<float>)
    ->Unit(benchmark::kMillisecond)
    ->ArgName("threads")
    ->Arg(1)
    ->Arg(2)
    ->UseRealTime();
BENCHMARK(BM_AdamUpdate<float>)
    ->Unit(benchmark::kMillisecond)
    ->ArgName("threads")
    ->Arg(1)
    ->Arg(2)
    ->UseRealTime();
BENCHMARK(BM_HnnField<double>)
    ->Unit(benchmark::kMillisecond)
    ->ArgName("threads")
    ->Arg(1)
    ->Arg(2)
    ->UseRealTime();

BENCHMARK_MAIN();
