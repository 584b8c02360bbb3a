// The shared evaluator: losses with standard errors, rollouts of true and learned fields, the
// energy MSE and its standard error, failures of learned rollouts, and the HNN's own H.

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <random>

#include "nn/hnn.h"
#include "physics/integrator.h"
#include "tasks/evaluate/energy_errors.h"
#include "tasks/evaluate/field_evaluation.h"
#include "tasks/evaluate/loss_stats.h"
#include "tasks/evaluate/rollouts.h"
#include "tasks/evaluate/state_errors.h"
#include "tasks/experiments/registry.h"
#include "tasks/field/field_task.h"
#include "tasks/train/field_objective.h"
#include "tests/tasks/test_configs.h"

namespace hnn::tasks {
namespace {

// A model whose field is any function: the exact field (an oracle), zero, or one that blows up.
// The evaluator only needs field(); the base class also requires an MLP, which goes unused.
class FunctionModel : public nn::DynamicsModel<double> {
 public:
  using Fn = std::function<Batch(const Batch&)>;
  FunctionModel(Eigen::Index dim, Fn fn)
      : DynamicsModel(config(dim), unused_mlp(dim)), fn_(std::move(fn)) {}
  ad::Var<double> time_derivative(const ad::Var<double>&) const override {
    throw std::logic_error("FunctionModel gives values only");
  }
  nn::Matrix<double> field(const nn::MatrixView<double>& x) const override { return fn_(x); }

 private:
  static nn::DynamicsConfig config(Eigen::Index dim) {
    return {.model = nn::ModelKind::kBaseline, .dim = dim, .hidden = {2}};
  }
  static nn::Mlp<double> unused_mlp(Eigen::Index dim) {
    std::mt19937_64 rng(0);
    return nn::Mlp<double>(nn::mlp_config(config(dim)), rng);
  }
  Fn fn_;
};

FunctionModel exact_model(const FieldTask& task) {
  const physics::System& truth = task.truth();
  return FunctionModel(truth.dim(), [&truth](const Batch& x) {
    Batch dxdt;
    truth.vector_field(x, dxdt);
    return dxdt;
  });
}

FunctionModel zero_model(Eigen::Index dim) {
  return FunctionModel(dim, [](const Batch& x) { return Batch(Batch::Zero(x.rows(), x.cols())); });
}

std::unique_ptr<nn::DynamicsModel<double>> small_model(const std::string& kind, Eigen::Index dim,
                                                       std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  nn::DynamicsConfig config{.model = nn::parse_model_kind(kind), .dim = dim, .hidden = {16, 16}};
  return nn::make_model<double>(config, rng);
}

TEST(LossStats, MeanOverPointsAndComponentsWithTheReferencesStandardError) {
  const std::unique_ptr<FieldTask> task = make_field_task("spring");
  const Dataset d = task->build_dataset(0);
  const FunctionModel exact = exact_model(*task);
  const nn::MeanStderr s = loss_stats(exact, d.test_x, d.test_dxdt);
  // By hand, as the reference's train.py: dist = (dxdt - dxdt_hat)**2 (N x D),
  // dist.mean() +- dist.std() / sqrt(N), torch's std dividing by N * D - 1.
  Batch field;
  task->truth().vector_field(d.test_x, field);
  const Eigen::ArrayXXd dist = (field - d.test_dxdt).array().square();
  const double n = double(dist.rows()), mean = dist.mean();
  const double std = std::sqrt((dist - mean).square().sum() / (double(dist.size()) - 1));
  EXPECT_EQ(s.count, 750u);
  EXPECT_NEAR(s.mean, mean, 1e-15);
  EXPECT_NEAR(s.std_error, std / std::sqrt(n), 1e-15);
  // The exact field at inputs with N(0, 0.1^2) noise misses the targets by 2 * noise per
  // component: the loss floor of the spring is 4 * 0.01, and each squared error is 0.04 chi^2_1,
  // of std 0.04 sqrt(2): an error bar of 0.0566 / sqrt(750) = 2.1e-3 (the paper: 1.8e-3).
  EXPECT_NEAR(s.mean, 0.04, 0.006);
  EXPECT_NEAR(s.std_error, 0.04 * std::sqrt(2.0) / std::sqrt(750.0), 4e-4);
  // The trainer's field_mse is the same mean (without the standard error).
  EXPECT_NEAR(field_mse<double>(exact, d.test_x, d.test_dxdt), s.mean, 1e-15);
  EXPECT_THROW(loss_stats(exact, Batch(0, 2), Batch(0, 2)), std::exception);
}

TEST(LossStats, ChunkedEvaluationCoversEveryRow) {
  // More rows than one evaluation chunk (4096): a random model's loss equals the loss computed
  // in one go.
  const std::unique_ptr<FieldTask> task = make_field_task("two-body");
  const Dataset d = task->build_dataset(1);
  const auto model = small_model("baseline", 8, 3);
  const Batch pred = model->field(d.train_x);
  const double want = (pred - d.train_dxdt).squaredNorm() / double(d.train_dxdt.size());
  EXPECT_NEAR(loss_stats(*model, d.train_x, d.train_dxdt).mean, want, 1e-12 * want);
  EXPECT_NEAR(field_mse<double>(*model, d.train_x, d.train_dxdt), want, 1e-12 * want);
  EXPECT_EQ(loss_stats(*model, d.train_x, d.train_dxdt).count, 40000u);
}

TEST(MakeRollouts, ExactModelFollowsTheTruthAndHasNoEnergyError) {
  const std::unique_ptr<FieldTask> task = make_field_task("pendulum");
  const FunctionModel exact = exact_model(*task);
  Batch x0(3, 2);
  x0 << 0.5, -0.3, -1.0, 0.8, 0.2, 0.9;
  const RolloutConfig config{.trajectories = 3, .t_end = 5.0, .points = 26};
  const Rollouts r = make_rollouts(task->truth(), exact, x0, config);
  ASSERT_EQ(r.t.size(), 26u);
  EXPECT_DOUBLE_EQ(r.t.front(), 0.0);
  EXPECT_DOUBLE_EQ(r.t.back(), 5.0);
  EXPECT_NEAR(r.t[1], 0.2, 1e-15);
  ASSERT_EQ(r.truth.size(), 3u);
  ASSERT_EQ(r.pred.size(), 3u);
  EXPECT_EQ(r.true_energy.rows(), 3);
  EXPECT_EQ(r.true_energy.cols(), 26);
  EXPECT_EQ(r.learned_h.size(), 0);  // not an HNN
  EXPECT_TRUE(r.failures.empty());
  EXPECT_GT(r.nfev, 0);
  for (int i = 0; i < 3; ++i) {
    EXPECT_FALSE(r.failed[std::size_t(i)]);
    ASSERT_EQ(r.truth[std::size_t(i)].rows(), 26);
    EXPECT_EQ(r.truth[std::size_t(i)].row(0), x0.row(i));
    EXPECT_EQ(r.pred[std::size_t(i)].row(0), x0.row(i));
    EXPECT_LT((r.truth[std::size_t(i)] - r.pred[std::size_t(i)]).cwiseAbs().maxCoeff(), 1e-12);
    // The pendulum's energy along the true path is constant, and it is the pendulum's
    // (3(1 - cos q) + p^2), not the spring's (the reference's known defect).
    const double e0 = 3 * (1 - std::cos(x0(i, 0))) + x0(i, 1) * x0(i, 1);
    EXPECT_LT((r.true_energy.row(i).array() - e0).abs().maxCoeff(), 1e-7) << "trajectory " << i;
  }
  const nn::MeanStderr e = energy_mse(r);
  EXPECT_EQ(e.count, 3u);
  EXPECT_LT(e.mean, 1e-20);
  EXPECT_LT(coordinate_mse_over_time(r).maxCoeff(), 1e-20);
}

TEST(MakeRollouts, TrueRolloutsConserveEnergyOnEveryTask) {
  for (const std::string& name : testing::state_tasks()) {
    const std::unique_ptr<FieldTask> task = make_field_task(name);
    const Dataset d = task->build_dataset(0);
    std::mt19937_64 rng(1);
    const Batch x0 = task->rollout_states(d, kDefaultRollouts, rng);
    ASSERT_EQ(x0.rows(), kDefaultRollouts) << name;
    ASSERT_EQ(x0.cols(), task->truth().dim()) << name;
    // A zero field stays at x0: its energy is the true energy of x0 at every time.
    const FunctionModel still = zero_model(x0.cols());
    const RolloutConfig config{.trajectories = 15, .t_end = 5.0, .points = 11};
    const Rollouts r = make_rollouts(task->truth(), still, x0.topRows(4), config);
    for (int i = 0; i < 4; ++i) {
      const Eigen::RowVectorXd e = r.true_energy.row(i);
      const double scale = std::max(1.0, std::abs(e(0)));
      EXPECT_LT((e.array() - e(0)).abs().maxCoeff(), 1e-6 * scale) << name << " trajectory " << i;
      EXPECT_NEAR(r.pred_energy(i, 10), e(0), 1e-12 * scale) << name;
      EXPECT_EQ(r.pred[std::size_t(i)].row(10), x0.row(i)) << name;
    }
    EXPECT_LT(energy_mse(r).mean, 1e-10) << name;
  }
}

TEST(MakeRollouts, OscillatorRolloutStatesArePushedAwayFromZero) {
  // Tasks 1-2: uniform in [-0.8, 0.8]^2 pushed 0.2 away from zero in each component.
  for (const char* name : {"spring", "pendulum"}) {
    const std::unique_ptr<FieldTask> task = make_field_task(name);
    std::mt19937_64 rng(7);
    const Batch x0 = task->rollout_states(task->build_dataset(0), 15, rng);
    EXPECT_EQ(x0.rows(), 15);
    EXPECT_GE(x0.cwiseAbs().minCoeff(), 0.2) << name;
    EXPECT_LE(x0.cwiseAbs().maxCoeff(), 1.0) << name;
    std::mt19937_64 again(7);
    EXPECT_EQ(task->rollout_states(task->build_dataset(0), 15, again), x0) << name;
  }
}

TEST(MakeRollouts, RealPendulumStartsFromMeasuredTestStates) {
  const std::unique_ptr<FieldTask> task = make_field_task("real-pendulum");
  const Dataset d = task->build_dataset(0);
  std::mt19937_64 rng(0);
  const Batch x0 = task->rollout_states(d, kDefaultRollouts, rng);
  ASSERT_EQ(x0.rows(), kDefaultRollouts);
  for (Eigen::Index i = 0; i < x0.rows(); ++i) {
    bool found = false;
    for (Eigen::Index k = 0; k < d.test_x.rows() && !found; ++k)
      found = d.test_x.row(k) == x0.row(i);
    EXPECT_TRUE(found) << "rollout state " << i << " is not a test state";
  }
}

TEST(MakeRollouts, HnnConservesItsOwnLearnedHamiltonian) {
  const std::unique_ptr<FieldTask> task = make_field_task("spring");
  std::mt19937_64 rng(2);
  const Batch x0 = task->rollout_states(task->build_dataset(0), 3, rng);
  const RolloutConfig config{.trajectories = 3, .t_end = 10.0, .points = 21};
  const auto hnn = small_model("hnn", 2, 5);
  const Rollouts r = make_rollouts(task->truth(), *hnn, x0, config);
  ASSERT_EQ(r.learned_h.rows(), 3);
  ASSERT_EQ(r.learned_h.cols(), 21);
  const auto& h_model = dynamic_cast<const nn::Hnn<double>&>(*hnn);
  for (int i = 0; i < 3; ++i) {
    // Untrained, but an HNN nonetheless: its field is symplectic, so H stays put.
    const Eigen::RowVectorXd h = r.learned_h.row(i);
    EXPECT_NEAR(h(0), h_model.energy(Batch(x0.row(i)))(0, 0), 1e-14);
    EXPECT_LT((h.array() - h(0)).abs().maxCoeff(), 1e-7) << "trajectory " << i;
  }
  // A baseline has no H of its own.
  EXPECT_EQ(
      make_rollouts(task->truth(), *small_model("baseline", 2, 5), x0, config).learned_h.size(), 0);
}

TEST(MakeRollouts, BlowUpIsRecordedAsAFailureAndLeftOutOfTheMetrics) {
  const std::unique_ptr<FieldTask> task = make_field_task("spring");
  // dq/dt = q^2 reaches infinity at t = 1/q0 when q0 > 0, and decays when q0 < 0.
  const FunctionModel explosive(2, [](const Batch& x) {
    Batch dxdt = Batch::Zero(x.rows(), 2);
    dxdt.col(0) = x.col(0).array().square();
    return dxdt;
  });
  Batch x0(3, 2);
  x0 << 1.0, 0.3, -1.0, 0.3, -0.5, -0.4;
  const Rollouts r = make_rollouts(task->truth(), explosive, x0, {.t_end = 3.0, .points = 31});
  ASSERT_EQ(r.failed.size(), 3u);
  EXPECT_TRUE(r.failed[0]);
  EXPECT_FALSE(r.failed[1]);
  EXPECT_FALSE(r.failed[2]);
  ASSERT_EQ(r.failures.size(), 1u);
  EXPECT_NE(r.failures[0].find("trajectory 0"), std::string::npos) << r.failures[0];
  EXPECT_TRUE(r.pred[0].array().isNaN().all());  // never padded with made-up values
  EXPECT_TRUE(r.pred_energy.row(0).array().isNaN().all());
  EXPECT_TRUE(r.truth[0].allFinite());  // the true rollout is still there
  const nn::MeanStderr e = energy_mse(r);
  EXPECT_EQ(e.count, 2u);
  EXPECT_TRUE(std::isfinite(e.mean));
  EXPECT_TRUE(coordinate_mse_over_time(r).allFinite());
  // q(t) = q0 / (1 - q0 t) on the surviving rollouts.
  for (int i : {1, 2}) {
    for (std::size_t k = 0; k < r.t.size(); ++k) {
      const double q0 = x0(i, 0), want = q0 / (1 - q0 * r.t[k]);
      EXPECT_NEAR(r.pred[std::size_t(i)](Eigen::Index(k), 0), want, 1e-7);
    }
  }
}

// Rollouts with given per-trajectory energy errors: pred_energy - true_energy = sqrt(v_i) at
// every time, so trajectory i contributes v_i.
Rollouts synthetic_rollouts(const std::vector<double>& v, int times) {
  Rollouts r;
  const Eigen::Index n = Eigen::Index(v.size());
  r.t = physics::linspace(0.0, 1.0, times);
  r.true_energy = Eigen::MatrixXd::Constant(n, times, 1.0);
  r.pred_energy = r.true_energy;
  for (Eigen::Index i = 0; i < n; ++i) {
    r.pred_energy.row(i).array() += std::sqrt(v[std::size_t(i)]);
    r.truth.push_back(Eigen::MatrixXd::Zero(times, 2));
    r.pred.push_back(Eigen::MatrixXd::Constant(times, 2, double(i)));
    r.failed.push_back(false);
  }
  return r;
}

TEST(EnergyMse, MeanOverTrajectoriesAndTimesWithFiveSplitStandardError) {
  // v = 1..10; interleaved splits {1, 6}, {2, 7}, ..., {5, 10} have means 3.5 .. 7.5, whose
  // spread (numpy's std) is sqrt(2): standard error sqrt(2) / sqrt(5).
  std::vector<double> v;
  for (int i = 1; i <= 10; ++i) v.push_back(i);
  Rollouts r = synthetic_rollouts(v, 4);
  nn::MeanStderr e = energy_mse(r);
  EXPECT_EQ(e.count, 10u);
  EXPECT_NEAR(e.mean, 5.5, 1e-12);
  EXPECT_NEAR(e.std_error, std::sqrt(2.0 / 5.0), 1e-12);
  // A failed trajectory is left out, not counted as zero.
  r.failed[9] = true;
  e = energy_mse(r);
  EXPECT_EQ(e.count, 9u);
  EXPECT_NEAR(e.mean, 5.0, 1e-12);
  // The error is squared per time, then averaged: a sign flip changes nothing.
  Rollouts flipped = synthetic_rollouts(v, 4);
  flipped.pred_energy = 2.0 * flipped.true_energy - flipped.pred_energy;
  EXPECT_NEAR(energy_mse(flipped).mean, 5.5, 1e-12);
}

TEST(EnergyMse, NoSurvivingTrajectoryGivesNaNNotZero) {
  Rollouts r = synthetic_rollouts({1.0, 2.0}, 3);
  r.failed = {true, true};
  const nn::MeanStderr e = energy_mse(r);
  EXPECT_EQ(e.count, 0u);
  EXPECT_TRUE(std::isnan(e.mean));
  // One trajectory: a mean, but no spread to estimate an error from.
  const nn::MeanStderr one = energy_mse(synthetic_rollouts({4.0}, 3));
  EXPECT_NEAR(one.mean, 4.0, 1e-12);
  EXPECT_FALSE(std::isfinite(one.std_error) && one.std_error > 0);
}

TEST(RelativeEnergyMse, IsTheMseOverTheMeanSquaredTrueEnergyOfTheSameRollouts) {
  std::vector<double> v;
  for (int i = 1; i <= 10; ++i) v.push_back(i);
  Rollouts r = synthetic_rollouts(v, 4);
  r.true_energy *= 2.0;  // E = 2 on the rollouts: mean E^2 = 4; the errors stay sqrt(v_i)
  r.pred_energy.array() += 1.0;
  const nn::MeanStderr mse = energy_mse(r), relative = relative_energy_mse(r);
  EXPECT_NEAR(mse.mean, 5.5, 1e-12);
  EXPECT_NEAR(relative.mean, 5.5 / 4, 1e-12);
  EXPECT_NEAR(relative.std_error, mse.std_error / 4, 1e-12);
  EXPECT_EQ(relative.count, 10u);
  // Units cancel: H times 1000 gives the same relative figure.
  Rollouts scaled = r;
  scaled.true_energy *= 1000.0;
  scaled.pred_energy *= 1000.0;
  EXPECT_NEAR(relative_energy_mse(scaled).mean, relative.mean, 1e-12);
  // A failed rollout leaves both the MSE and the mean E^2; a true energy of 0 throughout gives
  // NaN, not infinity.
  r.failed[9] = true;
  r.true_energy.row(0).array() = 10.0;
  const double mean_square = (100.0 + 8 * 4.0) / 9;
  EXPECT_NEAR(relative_energy_mse(r).mean, energy_mse(r).mean / mean_square, 1e-12);
  r.true_energy.setZero();
  EXPECT_TRUE(std::isnan(relative_energy_mse(r).mean));
}

TEST(CoordinateMse, MeanOverSurvivingTrajectoriesAtEachTime) {
  Rollouts r = synthetic_rollouts({1.0, 1.0, 1.0}, 5);  // pred of trajectory i is i everywhere
  r.pred[1](2, 0) = 3.0;                                // one coordinate off at time 2
  Eigen::VectorXd mse = coordinate_mse_over_time(r);
  ASSERT_EQ(mse.size(), 5);
  // Per time: mean over trajectories of mean over coordinates: (0 + 1 + 4) / 3.
  EXPECT_NEAR(mse(0), 5.0 / 3.0, 1e-12);
  EXPECT_NEAR(mse(2), (0.0 + (9.0 + 1.0) / 2 + 4.0) / 3.0, 1e-12);
  r.failed[2] = true;
  mse = coordinate_mse_over_time(r);
  EXPECT_NEAR(mse(0), 0.5, 1e-12);
}

}  // namespace
}  // namespace hnn::tasks

namespace hnn::tasks {
namespace {

using nlohmann::json;

// R^2 = 1 - MSE / variance of the targets: 1 for the exact field, 1 - E[y^2] / Var(y) for zero,
// and the same whatever the units (the targets scaled by 100 scale MSE and variance alike).
TEST(FieldEvaluation, RSquaredIsOneMinusMseOverTheTargetsVariance) {
  const std::unique_ptr<FieldTask> task = make_field_task("spring");
  const Dataset d = task->build_dataset(0);
  const RolloutConfig few{.trajectories = 2, .t_end = 1.0, .points = 5};
  const Batch x0 = d.test_x.topRows(2);
  // The targets are the field at the clean states and the inputs are noisy: not exactly 1.
  const json exact = evaluate_field_model(task->truth(), exact_model(*task), d, x0, few).metrics;
  EXPECT_GT(exact["test_r2"].get<double>(), 0.9);
  EXPECT_LT(exact["test_r2"].get<double>(), 1.0);
  const json zero = evaluate_field_model(task->truth(), zero_model(2), d, x0, few).metrics;
  const Eigen::RowVectorXd mean = d.test_dxdt.colwise().mean();
  const double variance = (d.test_dxdt.rowwise() - mean).squaredNorm() / double(d.test_dxdt.size());
  EXPECT_NEAR(zero["test_r2"].get<double>(),
              1 - d.test_dxdt.squaredNorm() / double(d.test_dxdt.size()) / variance, 1e-12);
  Dataset scaled = d;
  scaled.test_dxdt *= 100;
  const FunctionModel scaled_exact(2, [&task](const Batch& x) {
    Batch dxdt;
    task->truth().vector_field(x, dxdt);
    return Batch(100 * dxdt);
  });
  EXPECT_NEAR(evaluate_field_model(task->truth(), scaled_exact, scaled, x0, few)
                  .metrics["test_r2"]
                  .get<double>(),
              exact["test_r2"].get<double>(), 1e-12);
}

// Finzi et al.'s relative state error: |x^ - x| / (|x^| + |x|) after the start; a prediction
// that drifts linearly away passes 0.1 where expected, an exact one never does.
TEST(RelativeError, GivesTheGeometricMeanAndTheValidPredictionTime) {
  Rollouts r;
  r.t = {0, 1, 2, 3, 4};
  Eigen::MatrixXd x = Eigen::MatrixXd::Ones(5, 2), drift = x;
  for (int k = 0; k < 5; ++k) drift.row(k) *= 1 + 0.15 * k;  // e = 0.15k / (2 + 0.15k)
  r.truth = {x, x};
  r.pred = {x * (1 + 1e-6), drift};
  r.failed = {false, false};
  const RelativeError e = relative_error(r);
  // Trajectory 0: e = 5e-7 throughout, censored at 4; trajectory 1 passes 0.1 at t = 2.
  EXPECT_DOUBLE_EQ(e.valid_time, (4.0 + 2.0) / 2);
  EXPECT_EQ(e.censored, 1);
  double log_sum = 4 * std::log(1e-6 / (2 + 1e-6));
  for (int k = 1; k < 5; ++k) log_sum += std::log(0.15 * k / (2 + 0.15 * k));
  EXPECT_NEAR(e.geomean, std::exp(log_sum / 8), 1e-9 * e.geomean);
  r.failed = {true, true};
  EXPECT_TRUE(std::isnan(relative_error(r).geomean));
}

}  // namespace
}  // namespace hnn::tasks
