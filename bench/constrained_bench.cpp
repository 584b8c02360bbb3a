// One training step of the CHNN and CLNN (nn/constrained/) on the 2-chain pendulum in Cartesian
// coordinates at the peer's sizes (Finzi, Wang & Wilson 2020: a 3 x 256 tanh MLP for V, batch
// 200): the field loss (mse of dz/dt), and the rollout loss of their protocol (a 5-point chunk,
// 4 fixed RK4 steps from its first state, through which the gradient flows; mse here, L1 there,
// a difference the timing does not see). Forward, parameter gradients and Adam; float and
// double; 1 and 2 threads (wall time).

#include <benchmark/benchmark.h>

#include <cmath>
#include <numbers>
#include <random>

#include "autodiff/autodiff.h"
#include "nn/nn.h"

namespace ad = hnn::ad;
namespace nn = hnn::nn;

namespace {

constexpr Eigen::Index kBatch = 200;
constexpr double kDt = 0.03;  // the peer's ChainPendulum time step

// Two unit masses on rods of length 1 from the origin, in 2-D.
nn::ConstraintSpec two_chain() {
  nn::ConstraintSpec spec;
  spec.points = 2;
  spec.dim = 2;
  spec.mass = Eigen::MatrixXd::Identity(2, 2);
  spec.anchors.push_back({0, {0.0, 0.0}, 1.0});
  spec.links.push_back({0, 1, 1.0});
  return spec;
}

// States on the constraints from random angles and angular rates.
nn::Matrix<double> chain_states() {
  std::mt19937_64 rng(0);
  std::uniform_real_distribution<double> angle(-std::numbers::pi, std::numbers::pi), rate(-2, 2);
  nn::Matrix<double> z(kBatch, 8);
  for (Eigen::Index r = 0; r < kBatch; ++r) {
    const double t1 = angle(rng), t2 = angle(rng), w1 = rate(rng), w2 = rate(rng);
    z.row(r) << std::sin(t1), -std::cos(t1), std::sin(t1) + std::sin(t2),
        -std::cos(t1) - std::cos(t2), w1 * std::cos(t1), w1 * std::sin(t1),
        w1 * std::cos(t1) + w2 * std::cos(t2), w1 * std::sin(t1) + w2 * std::sin(t2);
  }
  return z;
}

template <typename T>
std::unique_ptr<nn::DynamicsModel<T>> peer_model(nn::ModelKind kind, std::uint64_t seed) {
  nn::DynamicsConfig config;
  config.model = kind;
  config.dim = kind == nn::ModelKind::kHnn ? 4 : 8;
  config.hidden = {256, 256, 256};
  if (kind != nn::ModelKind::kHnn) config.constraints = two_chain();
  std::mt19937_64 rng(seed);
  return nn::make_model<T>(config, rng);
}

// One RK4 step of the model's field, on the tape.
template <typename T>
ad::Var<T> rk4_step(const nn::DynamicsModel<T>& model, const ad::Var<T>& z) {
  const T h = T(kDt);
  const ad::Var<T> k1 = model.time_derivative(z);
  const ad::Var<T> k2 = model.time_derivative(z + k1 * (h / 2));
  const ad::Var<T> k3 = model.time_derivative(z + k2 * (h / 2));
  const ad::Var<T> k4 = model.time_derivative(z + k3 * h);
  return z + (k1 + k2 * T(2) + k3 * T(2) + k4) * (h / 6);
}

template <typename T>
void training_step(benchmark::State& state, nn::ModelKind kind, bool rollout) {
  ad::set_num_threads(int(state.range(0)));
  const auto model = peer_model<T>(kind, 1);
  const nn::Matrix<T> z0 = chain_states().leftCols(model->dim()).template cast<T>();
  // Targets: the field, or 4 states along the chunk, of another random model of the same shape
  // (their values do not change the work of a step).
  const auto teacher = peer_model<T>(kind, 2);
  std::vector<nn::Matrix<T>> targets{teacher->field(z0)};
  if (rollout) {
    targets.assign(1, z0);
    for (int k = 0; k < 4; ++k) {
      const nn::Matrix<T>& z = targets.back();
      targets.push_back((z + T(kDt) * teacher->field(z)).eval());
    }
    targets.erase(targets.begin());
  }
  nn::Adam<T> adam(model->parameters(), {.lr = 3e-3, .weight_decay = 1e-4});
  std::vector<ad::Var<T>> grads;
  double loss = 0;
  for (auto _ : state) {
    ad::TapeScope scope;
    ad::Var<T> l;
    if (!rollout) {
      l = nn::mse(model->time_derivative(ad::Var<T>::constant(z0)),
                  ad::Var<T>::constant(targets[0]));
    } else {
      ad::Var<T> z = ad::Var<T>::constant(z0);
      for (const nn::Matrix<T>& target : targets) {
        z = rk4_step(*model, z);
        const ad::Var<T> term = nn::mse(z, ad::Var<T>::constant(target));
        l = l.defined() ? l + term : term;
      }
    }
    ad::grad_into(l, adam.parameters(), grads);
    adam.step(grads);
    loss = double(l.item());
  }
  state.counters["loss"] = loss;
}

template <typename T>
void BM_ChnnFieldStep(benchmark::State& state) {
  training_step<T>(state, nn::ModelKind::kChnn, false);
}
// An HNN with the CHNN's MLP (4 inputs -> 3 x 256 -> 1) on 4 of the state's columns: what the
// step costs without the constraint mechanics.
template <typename T>
void BM_SameMlpHnnFieldStep(benchmark::State& state) {
  training_step<T>(state, nn::ModelKind::kHnn, false);
}
template <typename T>
void BM_ChnnRk4ChunkStep(benchmark::State& state) {
  training_step<T>(state, nn::ModelKind::kChnn, true);
}
template <typename T>
void BM_ClnnRk4ChunkStep(benchmark::State& state) {
  training_step<T>(state, nn::ModelKind::kClnn, true);
}

}  // namespace

BENCHMARK(BM_ChnnFieldStep<float>)
    ->Unit(benchmark::kMillisecond)
    ->ArgName("threads")
    ->Arg(1)
    ->Arg(2);
BENCHMARK(BM_ChnnFieldStep<double>)
    ->Unit(benchmark::kMillisecond)
    ->ArgName("threads")
    ->Arg(1)
    ->Arg(2);
BENCHMARK(BM_SameMlpHnnFieldStep<float>)
    ->Unit(benchmark::kMillisecond)
    ->ArgName("threads")
    ->Arg(1)
    ->Arg(2);
BENCHMARK(BM_ChnnRk4ChunkStep<float>)
    ->Unit(benchmark::kMillisecond)
    ->ArgName("threads")
    ->Arg(1)
    ->Arg(2);
BENCHMARK(BM_ChnnRk4ChunkStep<double>)
    ->Unit(benchmark::kMillisecond)
    ->ArgName("threads")
    ->Arg(1)
    ->Arg(2);
BENCHMARK(BM_ClnnRk4ChunkStep<float>)
    ->Unit(benchmark::kMillisecond)
    ->ArgName("threads")
    ->Arg(1)
    ->Arg(2);

BENCHMARK_MAIN();
