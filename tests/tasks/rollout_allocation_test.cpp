// A rollout-loss training step (sample, loss through the integrator, gradients, Adam) allocates
// nothing on the heap once warmed up, for the explicit integrators; the implicit midpoint's
// off-tape solve still does (counted, reported). Counted by interposing malloc in this test
// program, as tests/nn/allocation_test.cpp does for the HNN step.

#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <random>

#include "autodiff/autodiff.h"
#include "nn/hnn.h"
#include "nn/malloc_counter.h"
#include "nn/optim.h"
#include "tasks/train/rollout_objective.h"

namespace {
std::atomic<long> g_allocations{0};
}  // namespace

long hnn::testing::allocation_count() { return g_allocations.load(); }

#if HNN_COUNTS_ALLOCATIONS
#define HNN_COUNT_ALLOCATIONS 1

extern "C" {
void* __libc_malloc(std::size_t);
void* __libc_calloc(std::size_t, std::size_t);
void* __libc_realloc(void*, std::size_t);
void* __libc_memalign(std::size_t, std::size_t);

void* malloc(std::size_t n) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  return __libc_malloc(n);
}
void* calloc(std::size_t n, std::size_t size) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  return __libc_calloc(n, size);
}
void* realloc(void* p, std::size_t n) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  return __libc_realloc(p, n);
}
void* aligned_alloc(std::size_t alignment, std::size_t n) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  return __libc_memalign(alignment, n);
}
void* memalign(std::size_t alignment, std::size_t n) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  return __libc_memalign(alignment, n);
}
int posix_memalign(void** out, std::size_t alignment, std::size_t n) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  *out = __libc_memalign(alignment, n);
  return *out ? 0 : 12;  // ENOMEM
}
}
#endif

namespace hnn::tasks {
namespace {

// Heap allocations of `steps` rollout-loss steps (horizon 3, batch 32) after `warmup` steps.
long allocations(RolloutIntegrator method, int warmup, int steps) {
  std::mt19937_64 rng(3);
  std::vector<Stretch> stretches;
  Eigen::VectorXd t = Eigen::VectorXd::LinSpaced(8, 0.0, 3.5);
  for (int k = 0; k < 10; ++k) stretches.push_back({t, nn::random_normal<double>(8, 2, rng, 0, 1)});
  const auto model =
      nn::make_model<double>({.model = nn::ModelKind::kHnn, .dim = 2, .hidden = {32, 32}}, rng);
  RolloutObjective<double> objective(*model, rollout_windows(stretches, 3), {}, 32, {.lr = 1e-3}, 1,
                                     method);
  nn::Adam<double> adam(model->parameters(), {.lr = 1e-3});
  std::vector<ad::Var<double>> grads;
  long counted = 0;
  for (int step = 0; step < warmup + steps; ++step) {
    const long before = g_allocations.load();
    {
      ad::TapeScope scope;
      objective.sampler().next();
      const ad::Var<double> loss = objective.batch_loss();
      ad::grad_into(loss, adam.parameters(), grads);
      adam.step(grads);
    }
    if (step >= warmup) counted += g_allocations.load() - before;
  }
  return counted;
}

TEST(RolloutAllocations, ExplicitIntegratorStepsAllocateNothingAfterWarmUp) {
#ifndef HNN_COUNT_ALLOCATIONS
  GTEST_SKIP() << "malloc belongs to the sanitizer in this build";
#endif
  for (RolloutIntegrator method :
       {RolloutIntegrator::kLeapfrog, RolloutIntegrator::kYoshida4, RolloutIntegrator::kRk4}) {
    EXPECT_EQ(allocations(method, 3, 10), 0) << to_string(method);
  }
  // The midpoint's solve works on plain matrices: it allocates, and says how much.
  const long midpoint = allocations(RolloutIntegrator::kMidpoint, 3, 10);
  RecordProperty("midpoint_allocations_per_step", std::to_string(midpoint / 10));
  EXPECT_GT(midpoint, 0);
}

}  // namespace
}  // namespace hnn::tasks
