// A training step allocates nothing on the heap once warmed up: the tape recycles its nodes and
// their buffers, the sweep and the fused kernels keep their scratch, GEMM packing stays in
// OpenBLAS's pool. Counted by tests/malloc_counter.cpp (not under the sanitizers, which own
// malloc); optim_test uses the same counter.

#include <gtest/gtest.h>

#include <cstdlib>
#include <random>

#include "autodiff/autodiff.h"
#include "constrained_test_util.h"
#include "malloc_counter.h"
#include "nn/nn.h"

namespace ad = hnn::ad;
namespace nn = hnn::nn;

namespace {

// Heap allocations made by `steps` training steps of the model `config` makes, after `warmup`
// steps, on a batch of `rows` random states.
template <typename T>
long allocations_per_steps(const nn::DynamicsConfig& config, int threads, long rows, int warmup,
                           int steps) {
  ad::set_num_threads(threads);
  std::mt19937_64 rng(3);
  const auto model = nn::make_model<T>(config, rng);
  nn::Adam<T> adam(model->parameters(), {.lr = 1e-3, .weight_decay = 1e-4});
  const ad::Var<T> x = ad::Var<T>::leaf(nn::random_normal<T>(rows, config.dim, rng, 0, 1), false);
  const ad::Var<T> target =
      ad::Var<T>::leaf(nn::random_normal<T>(rows, config.dim, rng, 0, 1), false);
  std::vector<ad::Var<T>> grads;
  long counted = 0;
  for (int step = 0; step < warmup + steps; ++step) {
#if HNN_COUNTS_ALLOCATIONS
    const long before = hnn::testing::allocation_count();
#endif
    {
      ad::TapeScope scope;
      const ad::Var<T> loss = nn::mse(model->time_derivative(x), target);
      ad::grad_into(loss, adam.parameters(), grads);
      adam.step(grads);
    }
#if HNN_COUNTS_ALLOCATIONS
    if (step >= warmup) counted += hnn::testing::allocation_count() - before;
#endif
  }
  ad::set_num_threads(2);
  return counted;
}

// A 2-dim model of `kind` with two hidden layers of 64.
template <typename T>
long allocations_per_steps(nn::ModelKind kind, int threads, long rows, int warmup, int steps,
                           nn::FieldType field = nn::FieldType::kSolenoidal) {
  return allocations_per_steps<T>({.model = kind, .dim = 2, .hidden = {64, 64}, .field = field},
                                  threads, rows, warmup, steps);
}

// The double-pendulum task's LNN, small: 4 inputs, angles as (cos, sin), velocities scaled by 1/10.
nn::DynamicsConfig small_lnn(nn::Activation activation) {
  return {.model = nn::ModelKind::kLnn,
          .dim = 4,
          .hidden = {32, 32},
          .activation = activation,
          .angles = 2,
          .input_scale = {1, 1, 10, 10}};
}

}  // namespace

TEST(Allocations, TrainingStepsAllocateNothingAfterWarmUp) {
#if !HNN_COUNTS_ALLOCATIONS
  GTEST_SKIP() << "malloc belongs to the sanitizer in this build";
#endif
  for (int threads : {1, 2}) {
    EXPECT_EQ((allocations_per_steps<double>(nn::ModelKind::kHnn, threads, 300, 3, 20)), 0)
        << "HNN, double, " << threads << " thread(s)";
    EXPECT_EQ((allocations_per_steps<float>(nn::ModelKind::kHnn, threads, 300, 3, 20)), 0)
        << "HNN, float, " << threads << " thread(s)";
    EXPECT_EQ((allocations_per_steps<double>(nn::ModelKind::kBaseline, threads, 300, 3, 20)), 0)
        << "baseline, double, " << threads << " thread(s)";
    EXPECT_EQ((allocations_per_steps<double>(nn::ModelKind::kHnn, threads, 300, 3, 20,
                                             nn::FieldType::kBoth)),
              0)
        << "dissipative HNN (kBoth), double, " << threads << " thread(s)";
  }
}

TEST(Allocations, DissipativeAndLagrangianStepsAllocateNothingAfterWarmUp) {
#if !HNN_COUNTS_ALLOCATIONS
  GTEST_SKIP() << "malloc belongs to the sanitizer in this build";
#endif
  const nn::DynamicsConfig dhnn{
      .model = nn::ModelKind::kDhnn, .dim = 2, .hidden = {64, 64}, .field = nn::FieldType::kBoth};
  for (int threads : {1, 2}) {
    EXPECT_EQ(allocations_per_steps<float>(dhnn, threads, 128, 3, 20), 0)
        << "D-HNN (kDhnn), float, " << threads << " thread(s)";
    for (nn::Activation act : {nn::Activation::kTanh, nn::Activation::kSoftplus}) {
      EXPECT_EQ(allocations_per_steps<double>(small_lnn(act), threads, 64, 3, 10), 0)
          << "LNN, " << nn::to_string(act) << ", double, " << threads << " thread(s)";
      EXPECT_EQ(allocations_per_steps<float>(small_lnn(act), threads, 64, 3, 10), 0)
          << "LNN, " << nn::to_string(act) << ", float, " << threads << " thread(s)";
    }
    // Big enough that the elementwise ops split their rows across the threads too.
    nn::DynamicsConfig wide = small_lnn(nn::Activation::kSoftplus);
    wide.hidden = {128, 128};
    EXPECT_EQ(allocations_per_steps<float>(wide, threads, 512, 2, 3), 0)
        << "LNN 128-128, 512 rows, float, " << threads << " thread(s)";
  }
}

TEST(Allocations, ConstrainedStepsAllocateNothingAfterWarmUp) {
#if !HNN_COUNTS_ALLOCATIONS
  GTEST_SKIP() << "malloc belongs to the sanitizer in this build";
#endif
  // A 3-chain in 2-D: the Gram blocks of its multipliers are 3x3.
  const nn::ConstraintSpec spec =
      nn::testing::chain_spec({1.0, 0.8, 0.6}, 2, Eigen::MatrixXd::Identity(3, 3), {0.0, 0.0});
  for (nn::ModelKind kind : {nn::ModelKind::kChnn, nn::ModelKind::kClnn}) {
    const nn::DynamicsConfig config = nn::testing::constrained_config(kind, spec, {32, 32});
    for (int threads : {1, 2}) {
      EXPECT_EQ(allocations_per_steps<double>(config, threads, 64, 3, 10), 0)
          << nn::to_string(kind) << ", double, " << threads << " thread(s)";
      EXPECT_EQ(allocations_per_steps<float>(config, threads, 64, 3, 10), 0)
          << nn::to_string(kind) << ", float, " << threads << " thread(s)";
    }
  }
}

TEST(Allocations, TheCounterSeesAllocations) {
#if !HNN_COUNTS_ALLOCATIONS
  GTEST_SKIP() << "malloc belongs to the sanitizer in this build";
#else
  const long before = hnn::testing::allocation_count();
  std::vector<double>* volatile v = new std::vector<double>(1000);  // volatile: not elided
  const long after = hnn::testing::allocation_count();
  delete v;
  EXPECT_GE(after - before, 2);  // the vector object and its buffer
#endif
}
