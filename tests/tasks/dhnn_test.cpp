// The dissipative HNN as a model the program trains (--model dhnn), and the damped-spring task
// of its paper: a dhnn fits the damped field that an HNN cannot, and reports its two parts.

#include <gtest/gtest.h>

#include "nn/hnn.h"
#include "physics/oscillators.h"
#include "tasks/experiments/registry.h"
#include "tasks/field/field_task.h"
#include "test_configs.h"

namespace hnn::tasks {
namespace {

using testing::TempDir;

TEST(Dhnn, IsAnHnnWithBothPartsAndRefusesOtherFieldTypes) {
  EXPECT_EQ(parse_model("dhnn"), nn::ModelKind::kDhnn);
  std::mt19937_64 rng(0);
  nn::DynamicsConfig config{.model = nn::ModelKind::kDhnn, .hidden = {8}};
  EXPECT_THROW(nn::make_model<double>(config, rng), std::invalid_argument);  // solenoidal
  config.field = nn::FieldType::kBoth;
  const auto model = nn::make_model<double>(config, rng);
  EXPECT_NE(dynamic_cast<const nn::Hnn<double>*>(model.get()), nullptr);
  EXPECT_EQ(model->mlp().output_dim(), 2);
  EXPECT_EQ(nn::cast_model<float>(*model)->config().model, nn::ModelKind::kDhnn);
}

TEST(DampedSpring, IsTheD_HnnPapersGridWithTheExactField) {
  const Dataset d = build_dataset("damped-spring", 42);
  EXPECT_EQ(d.train_x.rows(), 531);  // 85% of 25 x 25
  EXPECT_EQ(d.test_x.rows(), 94);
  EXPECT_DOUBLE_EQ(d.train_x.cwiseAbs().maxCoeff(), 1.2);
  Batch f;
  physics::DampedSpring().vector_field(d.test_x, f);
  EXPECT_EQ(f, d.test_dxdt);
  // dq/dt = 2p - 2q, dp/dt = -2q.
  EXPECT_DOUBLE_EQ(f(0, 0), 2 * d.test_x(0, 1) - 2 * d.test_x(0, 0));
}

TEST(DampedSpring, ADhnnFitsWhatAnHnnCannotAndReportsItsDissipation) {
  TempDir dir("runs");
  std::map<std::string, nlohmann::json> m;
  for (const char* model : {"dhnn", "hnn"}) {
    RunOptions o = testing::small_run("damped-spring", model, dir / model, 400);
    o.hidden = std::vector<int>{32, 32};
    m[model] = run_training(o);
  }
  EXPECT_LT(m["dhnn"]["test_loss"].get<double>() * 20, m["hnn"]["test_loss"].get<double>());
  EXPECT_LT(m["dhnn"]["state_mse"].get<double>() * 20, m["hnn"]["state_mse"].get<double>())
      << m["dhnn"].dump();
  const double share = m["dhnn"]["dissipation_share"];
  EXPECT_GT(share, 0.02);  // the damping is a visible part of the motion
  EXPECT_LT(share, 0.9);
  EXPECT_FALSE(m["hnn"].contains("dissipation_share"));
  // Saved and loaded as any run.
  EXPECT_EQ(evaluate_run(dir / "dhnn", "", false)["test_loss"], m["dhnn"]["test_loss"]);
}

}  // namespace
}  // namespace hnn::tasks
