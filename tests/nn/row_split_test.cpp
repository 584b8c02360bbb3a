// Steps split by rows (nn/row_split.h): the same loss and gradients as the unsplit step up to
// rounding, bits that depend only on the number of parts, replicas that follow the model's
// parameters from step to step, no allocation once warmed up.

#include "nn/row_split.h"

#include <gtest/gtest.h>

#include <random>
#include <stdexcept>

#include "autodiff/autodiff.h"
#include "malloc_counter.h"
#include "nn/nn.h"

namespace hnn::nn {
namespace {

// Restores the engine's thread count when a test ends.
class SplitThreads {
 public:
  explicit SplitThreads(int n) : previous_(ad::num_threads()) { ad::set_num_threads(n); }
  ~SplitThreads() { ad::set_num_threads(previous_); }
  SplitThreads(const SplitThreads&) = delete;
  SplitThreads& operator=(const SplitThreads&) = delete;

 private:
  int previous_;
};

// An HNN's field against random targets, `rows` random states.
struct SplitProblem {
  explicit SplitProblem(Index rows, std::uint64_t seed = 3) : rng(seed) {
    model = make_model<double>({.model = ModelKind::kHnn, .dim = 2, .hidden = {32, 32}}, rng);
    x = random_normal<double>(rows, 2, rng, 0, 1);
    target = random_normal<double>(rows, 2, rng, 0, 1);
  }
  // The mean squared error of rows `block`, computed by `m`.
  ad::Var<double> loss(const DynamicsModel<double>& m, ad::RowBlock block) const {
    const auto rows = [&](const Matrix<double>& a) {
      return ad::Var<double>::constant(a.middleRows(block.begin, block.size()));
    };
    return mse(m.time_derivative(rows(x)), rows(target));
  }
  std::mt19937_64 rng;
  std::unique_ptr<DynamicsModel<double>> model;
  Matrix<double> x, target;
};

// The unsplit step's loss and gradients.
double unsplit_step(const SplitProblem& p, std::vector<ad::Var<double>>& grads) {
  const ad::Var<double> loss = p.loss(*p.model, {0, p.x.rows()});
  ad::grad_into(loss, p.model->parameters(), grads);
  return loss.item();
}

double split_difference(const Matrix<double>& a, const Matrix<double>& b) {
  return (a - b).norm() / b.norm();
}

TEST(RowSplit, GivesTheUnsplitLossAndGradientsStepAfterStep) {
  const SplitThreads threads(2);
  SplitProblem split(203), whole(203);  // the same model and data; 203 rows: unequal blocks
  for (int parts : {2, 3}) {
    RowSplit<double> rows(*split.model, parts);
    Adam<double> adam_split(split.model->parameters(), {.lr = 1e-2});
    Adam<double> adam_whole(whole.model->parameters(), {.lr = 1e-2});
    std::vector<ad::Var<double>> g_split, g_whole;
    // Three Adam steps each: the replicas must take the model's new values every step.
    for (int step = 0; step < 3; ++step) {
      ad::TapeScope scope;
      const auto loss = [&](const DynamicsModel<double>& m, ad::RowBlock b) {
        return split.loss(m, b);
      };
      const double l_split = rows.loss_and_gradients(split.x.rows(), loss, g_split);
      const double l_whole = unsplit_step(whole, g_whole);
      EXPECT_NEAR(l_split, l_whole, 1e-14 * l_whole) << parts << " parts, step " << step;
      ASSERT_EQ(g_split.size(), g_whole.size());
      for (std::size_t i = 0; i < g_split.size(); ++i) {
        EXPECT_LT(split_difference(g_split[i].value(), g_whole[i].value()), 1e-12)
            << "parameter " << i << ", " << parts << " parts, step " << step;
      }
      adam_split.step(g_split);
      adam_whole.step(g_whole);
    }
  }
}

TEST(RowSplit, BitsDependOnTheNumberOfPartsAlone) {
  // Two parts on two threads (either may run either part), then on one (both in turn).
  std::vector<Matrix<double>> results[2];
  for (int run = 0; run < 2; ++run) {
    const SplitThreads threads(2 - run);
    const SplitProblem p(256);
    RowSplit<double> rows(*p.model, 2);
    std::vector<ad::Var<double>> grads;
    for (int step = 0; step < 5; ++step) {
      ad::TapeScope scope;
      const auto loss = [&](const DynamicsModel<double>& m, ad::RowBlock b) {
        return p.loss(m, b);
      };
      results[run].push_back(
          Matrix<double>::Constant(1, 1, rows.loss_and_gradients(256, loss, grads)));
      for (const ad::Var<double>& g : grads) results[run].push_back(g.value());
    }
  }
  ASSERT_EQ(results[0].size(), results[1].size());
  for (std::size_t i = 0; i < results[0].size(); ++i) {
    EXPECT_EQ(results[0][i], results[1][i]) << "result " << i;
  }
}

TEST(RowSplit, APartsErrorReachesTheCaller) {
  const SplitThreads threads(2);
  const SplitProblem p(128);
  RowSplit<double> rows(*p.model, 2);
  std::vector<ad::Var<double>> grads;
  const auto loss = [&](const DynamicsModel<double>& m, ad::RowBlock b) {
    if (b.begin > 0) throw std::runtime_error("the second block's field failed");
    return p.loss(m, b);
  };
  EXPECT_THROW(rows.loss_and_gradients(128, loss, grads), std::runtime_error);
}

TEST(RowSplit, PartsKeepAtLeastTheMinimumRows) {
  EXPECT_EQ(row_split_parts(2 * kMinSplitRows - 1, 2), 1);
  EXPECT_EQ(row_split_parts(2 * kMinSplitRows, 2), 2);
  EXPECT_EQ(row_split_parts(1000, 1), 1);
  EXPECT_EQ(row_split_parts(1000, 8), 8);
  EXPECT_EQ(row_split_parts(5 * kMinSplitRows, 8), 5);
  EXPECT_EQ(row_split_parts(0, 2), 1);
}

TEST(RowSplit, StepsAllocateNothingAfterWarmUp) {
#if !HNN_COUNTS_ALLOCATIONS
  GTEST_SKIP() << "malloc belongs to the sanitizer in this build";
#endif
  const SplitThreads threads(2);
  for (Index batch : {Index(200), Index(201)}) {  // equal blocks, and blocks of 101 and 100
    const SplitProblem p(batch);
    RowSplit<double> rows(*p.model, 2);
    Adam<double> adam(p.model->parameters(), {.lr = 1e-3});
    std::vector<ad::Var<double>> grads;
    const auto step = [&] {
      ad::TapeScope scope;
      const auto loss = [&](const DynamicsModel<double>& m, ad::RowBlock b) {
        return p.loss(m, b);
      };
      rows.loss_and_gradients(batch, loss, grads);
      adam.step(grads);
    };
    // Warmed up when the worker has run its own part 10 steps in a row: on a loaded machine
    // (ctest runs tests side by side) the caller may run a late worker's part for it
    // (Note [Pinned parts]), and the worker's tape has then not been filled yet.
    int calm = 0;
    for (int warm = 0; calm < 10 && warm < 500; ++warm) {
      const long stolen = ad::stolen_parts();
      step();
      calm = ad::stolen_parts() == stolen ? calm + 1 : 0;
    }
    if (calm < 10) continue;  // never warmed up: the machine is too loaded to tell
    long counted = 0;
    const long stolen = ad::stolen_parts();
    for (int i = 0; i < 20; ++i) {
      const long before = hnn::testing::allocation_count();
      step();
      counted += hnn::testing::allocation_count() - before;
    }
    // A part taken for a late worker resizes both threads' buffers when the blocks differ.
    if (batch % 2 == 1 && ad::stolen_parts() != stolen) continue;
    EXPECT_EQ(counted, 0) << "batch " << batch;
  }
}

}  // namespace
}  // namespace hnn::nn
