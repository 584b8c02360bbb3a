// docs/inputs.md, "Shapes" and "Integrations": a shape mismatch names the op and both shapes; an
// integration that blows up stops and reports the time it reached, from the library and from
// `hnn rollout`; a stiff learned rollout is recorded as failed.

#include <gtest/gtest.h>

#include "autodiff/autodiff.h"
#include "physics/integrator.h"
#include "physics/oscillators.h"
#include "physics/types.h"
#include "reliability_util.h"
#include "tasks/evaluate/field_evaluation.h"
#include "tasks/evaluate/rollouts.h"

namespace hnn::reliability {
namespace {

TEST(EngineShapes, MismatchNamesTheOpAndBothShapes) {
  using V = ad::Var<double>;
  const V a = V::leaf(ad::Matrix<double>::Ones(2, 3)), b = V::leaf(ad::Matrix<double>::Ones(2, 3));
  const auto message = [](const auto& f) {
    try {
      f();
    } catch (const ad::Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const std::string matmul = message([&] { ad::matmul(a, b); });
  EXPECT_EQ(matmul, "matmul: shapes 2x3 and 2x3 do not agree");
  const V c = V::leaf(ad::Matrix<double>::Ones(3, 2));
  const std::string add = message([&] { return a + c; });
  EXPECT_NE(add.find("2x3"), std::string::npos) << add;
  EXPECT_NE(add.find("3x2"), std::string::npos) << add;
}

// dx/dt = x^2 from x = 1 is 1 / (1 - t): it leaves every bound at t = 1.
TEST(Integrations, BlowUpStopsWithTheTimeReached) {
  const physics::VectorField f = [](double, const physics::Batch& x, physics::Batch& dxdt) {
    dxdt = x.array().square().matrix();
  };
  const physics::Batch x0 = physics::Batch::Ones(1, 1);
  for (const char* method : {"euler", "rk4", "dopri5", "midpoint"}) {
    const auto integrator = physics::make_integrator(method, {.dt = 1e-3});
    try {
      integrator->integrate(f, x0, {0.0, 2.0});
      ADD_FAILURE() << method << ": integrated past the blow-up";
    } catch (const physics::IntegrationError& e) {
      EXPECT_GT(e.time(), 0.9) << method << ": " << e.what();
      EXPECT_LT(e.time(), 1.1) << method << ": " << e.what();
      EXPECT_NE(std::string(e.what()).find(fmt::format("t = {}", e.time())), std::string::npos)
          << method << ": " << e.what();
    }
  }
}

TEST(Integrations, RolloutThatBlowsUpIsOneLineWithTheTime) {
  const TempDir dir;
  const fs::path run = dir / "run";
  ASSERT_EQ(run_hnn({"train", "spring", "--steps", "5", "--hidden", "8", "--quiet", "--out",
                     run.string()},
                    dir.path())
                .code,
            0);
  const Result r = run_hnn({"rollout", run.string(), "--integrator", "euler", "--dt", "10",
                            "--t-end", "100000", "--points", "2"},
                           dir.path());
  EXPECT_EQ(r.code, 1);
  EXPECT_EQ(lines(r.err).size(), 1u) << r.err;
  EXPECT_TRUE(
      r.err.starts_with("hnn: error: euler: the state became non-finite in the step "
                        "from t = "))
      << r.err;
  EXPECT_FALSE(fs::exists(run / "rollout_euler.csv"));
}

// A badly trained field can be stiff enough to need ~1e8 adaptive steps per rollout, hours: each
// learned rollout stops at RolloutConfig::max_learned_steps (kMaxLearnedSteps by default) and is
// recorded with the time reached. Here a field decaying at rate 1e6, which explicit dopri5 can
// follow only in steps of about 3e-6, meets a limit of 2,000 steps; the true spring does not.
TEST(Integrations, StiffLearnedRolloutIsRecordedAsFailedWithTheTime) {
  EXPECT_EQ(tasks::RolloutConfig{}.max_learned_steps, tasks::kMaxLearnedSteps);
  const tasks::LearnedField stiff{
      .field = [](double, const physics::Batch& x, physics::Batch& dxdt) { dxdt = -1e6 * x; }};
  const physics::Spring spring;
  const physics::Batch x0{{0.5, 0.0}, {0.0, 0.7}};
  const tasks::Rollouts r = tasks::make_rollouts(
      spring, stiff, x0, {.trajectories = 2, .t_end = 1.0, .points = 5, .max_learned_steps = 2000});
  EXPECT_EQ(r.failed, std::vector<bool>({true, true}));
  const nlohmann::json m = tasks::rollout_metrics(r);
  ASSERT_EQ(m["rollout_failures"].size(), 2u) << m.dump();
  EXPECT_EQ(m["n_rollouts"].get<int>(), 0);
  for (const auto& failure : m["rollout_failures"]) {
    const std::string text = failure.get<std::string>();
    EXPECT_NE(text.find(": dopri5: max_steps = 2000 reached at t = "), std::string::npos) << text;
  }
}

}  // namespace
}  // namespace hnn::reliability
