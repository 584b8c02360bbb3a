// A rollout-loss training step (sample, loss through the integrator, gradients, Adam) allocates
// nothing on the heap once warmed up, for the explicit integrators; the implicit midpoint's
// off-tape solve still does (counted, reported). Counted by tests/malloc_counter.cpp, as
// tests/nn/allocation_test.cpp counts the HNN step.

#include <gtest/gtest.h>

#include <cstdlib>
#include <random>

#include "autodiff/autodiff.h"
#include "malloc_counter.h"
#include "nn/hnn.h"
#include "nn/optim.h"
#include "tasks/train/rollout_objective.h"

namespace hnn::tasks {
namespace {

// Heap allocations of `steps` rollout-loss steps (horizon 3, batch 32) after `warmup` steps, on
// `threads` threads.
long allocations(RolloutIntegrator method, int warmup, int steps, int threads = 2) {
  const int previous = ad::num_threads();
  ad::set_num_threads(threads);
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
    const long before = hnn::testing::allocation_count();
    {
      ad::TapeScope scope;
      objective.sampler().next();
      const ad::Var<double> loss = objective.batch_loss();
      ad::grad_into(loss, adam.parameters(), grads);
      adam.step(grads);
    }
    if (step >= warmup) counted += hnn::testing::allocation_count() - before;
  }
  ad::set_num_threads(previous);
  return counted;
}

TEST(RolloutAllocations, ExplicitIntegratorStepsAllocateNothingAfterWarmUp) {
#if !HNN_COUNTS_ALLOCATIONS
  GTEST_SKIP() << "malloc belongs to the sanitizer in this build";
#endif
  for (RolloutIntegrator method :
       {RolloutIntegrator::kLeapfrog, RolloutIntegrator::kYoshida4, RolloutIntegrator::kRk4}) {
    EXPECT_EQ(allocations(method, 3, 10), 0) << to_string(method);
  }
  EXPECT_EQ(allocations(RolloutIntegrator::kLeapfrog, 3, 10, /*threads=*/1), 0) << "1 thread";
  // The midpoint's solve works on plain matrices: it allocates, and says how much.
  const long midpoint = allocations(RolloutIntegrator::kMidpoint, 3, 10);
  RecordProperty("midpoint_allocations_per_step", std::to_string(midpoint / 10));
  EXPECT_GT(midpoint, 0);
}

}  // namespace
}  // namespace hnn::tasks
