// The constrained systems' tasks (tasks/experiments/constrained.cpp): Finzi et al.'s data (one
// 5-output chunk per trajectory), a run end to end with their metric, its floor and the failed
// rollouts; an angle or body-coordinate model's rollouts scored in Cartesian coordinates; the
// refusals; and the task's default loss (RK4 over the chunk, L1) with the keys that change it.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "nn/constrained/constrained_model.h"
#include "nn/constrained/masses.h"
#include "nn/mass_hnn.h"
#include "physics/constrained/body_coordinates.h"
#include "physics/constrained/chain_angles.h"
#include "physics/constrained/metric.h"
#include "physics/constrained/systems.h"
#include "tasks/evaluate/rollouts.h"
#include "tasks/experiments/registry.h"
#include "tasks/run.h"
#include "tasks/train/stop.h"
#include "test_configs.h"

namespace hnn::tasks {
namespace {

namespace pc = physics::constrained;
using testing::TempDir;

// A few short trajectories, a few rollouts: seconds, not the protocol's minutes.
RunOptions tiny(const std::string& model, const std::filesystem::path& out,
                const std::string& task = "chain-pendulum-2") {
  RunOptions o = testing::small_run(task, model, out, 3);
  o.batch_size = 4;
  o.task_settings = {{"trajectories", 6}, {"validation", 2}, {"rollouts", 2}};
  return o;
}

TEST(ConstrainedTask, HasThePeersProtocolAsItsDefaults) {
  const std::unique_ptr<Task> task = make_task("chain-pendulum-2");
  const TrainConfig c = task->train_config();
  EXPECT_EQ(c.steps, 8000);  // 2000 epochs of 800 trajectories in batches of 200
  EXPECT_EQ(c.batch_size, 200);
  EXPECT_EQ(c.hidden, (std::vector<int>{256, 256, 256}));
  EXPECT_EQ(c.learning_rate, 3e-3);
  EXPECT_EQ(c.weight_decay, 1e-4);
  EXPECT_EQ(c.lr_schedule, LrSchedule::kCosine);
  EXPECT_EQ(c.optimizer, OptimizerKind::kAdamW);  // their torch.optim.AdamW
  const RolloutLossConfig loss = task->default_loss();
  EXPECT_TRUE(loss.rollout);
  EXPECT_EQ(loss.horizon, 4);
  EXPECT_EQ(loss.norm, RolloutNorm::kL1);
  EXPECT_EQ(loss.minibatches, RowSampler::Draw::kEpochs);  // their DataLoader(shuffle=True)
  // Their float32, unless --dtype names another; the other tasks keep double.
  RunOptions o = tiny("chnn", "unused");
  EXPECT_EQ(resolve(*task, o).dtype, Dtype::kFloat);
  o.dtype = Dtype::kDouble;
  EXPECT_EQ(resolve(*task, o).dtype, Dtype::kDouble);
  EXPECT_EQ(make_task("spring")->default_dtype(), Dtype::kDouble);
  // Chunks of 5 states along the constrained truth: on the manifold, each chunk dt apart.
  const Dataset d = make_field_task("chain-pendulum-2")
                        ->build_dataset(RunSettings{.task = "chain-pendulum-2",
                                                    .model = nn::ModelKind::kBaseline,
                                                    .seed = 1,
                                                    .task_settings = {{"trajectories", 6}}});
  EXPECT_EQ(d.train_x.rows(), 30);
  EXPECT_EQ(d.test_x.rows(), 500);  // 100 validation trajectories
  const pc::ConstrainedSystem chain = pc::chain_pendulum(2);
  EXPECT_LT(chain.constraint_values(d.train_x).cwiseAbs().maxCoeff(), 1e-8);
  const Batch next = pc::simulate_constrained(chain, d.train_x.topRows(1), {0.0, 0.03}).states[1];
  EXPECT_LT((next - d.train_x.row(1)).cwiseAbs().maxCoeff(), 1e-8);
}

TEST(ConstrainedTask, RunsEndToEndWithTheMetricItsFloorAndTheFailedCount) {
  TempDir dir("runs");
  const nlohmann::json m = run_training(tiny("baseline", dir / "b"));
  ASSERT_TRUE(m.contains("cartesian_error")) << m.dump();
  EXPECT_EQ(m["cartesian_error_rollouts"], 2);
  EXPECT_GE(m["cartesian_error_failed"].get<int>(), 0);
  EXPECT_EQ(m["coordinates"], "cartesian");
  // The peer's floor on the 2-chain is 5.9e-5 over 100 starts; over 2 it is of that order.
  EXPECT_GT(m["cartesian_error_floor"].get<double>(), 1e-6);
  EXPECT_LT(m["cartesian_error_floor"].get<double>(), 1e-3);
  EXPECT_EQ(m["training"]["loss"], "rollout");
  EXPECT_EQ(m["training"]["norm"], "l1");
  EXPECT_EQ(m["training"]["horizon"], 4);
  // The truth through RK4 at the peer's step: about 2.4e-5 over the 2-chain's 800 windows.
  EXPECT_GT(m["truth_rollout_loss"].get<double>(), 1e-7);
  EXPECT_LT(m["truth_rollout_loss"].get<double>(), 1e-3);
}

// A run's rollouts from x0 in its own coordinates (those of `twin`, a System with to_cartesian),
// mapped to Cartesian (x, v) and scored against the Cartesian truth: the metric recomputed.
template <typename Twin>
pc::RolloutScore rescored(const Twin& twin, const LoadedRun& loaded, const Batch& x0) {
  const pc::ConstrainedSystem& cartesian = twin.cartesian();
  const std::vector<double> t = cartesian.output_times();
  const Rollouts r = make_rollouts(
      twin, loaded.run->dynamics(), x0,
      {.t_end = t.back(), .points = int(t.size()), .rtol = 1e-7, .atol = 1e-9, .perturbation = 0});
  std::vector<Batch> predicted(t.size(), Batch(x0.rows(), cartesian.dim()));
  for (std::size_t k = 0; k < t.size(); ++k)
    for (Eigen::Index i = 0; i < x0.rows(); ++i)
      predicted[k].row(i) =
          twin.to_cartesian(Batch(r.pred[std::size_t(i)].row(Eigen::Index(k)))).row(0);
  const std::vector<Batch> truth =
      pc::simulate_constrained(cartesian, twin.to_cartesian(x0), t).states;
  const double dt = cartesian.spec().dt;
  return pc::score_rollouts(predicted, truth, dt, dt * double(t.size()));
}

TEST(ConstrainedTask, AnAngleModelIsScoredInCartesianCoordinates) {
  TempDir dir("runs");
  const nlohmann::json m = run_training(tiny("hnn", dir / "h"));
  EXPECT_EQ(m["coordinates"], "angles (theta, p)");
  const LoadedRun loaded = load_run(dir / "h");
  const Batch x0 = loaded.run->rollout_states(2);
  ASSERT_EQ(x0.cols(), 4);  // (theta, p) of two links
  const pc::RolloutScore score = rescored(pc::ChainPendulumAngles(2), loaded, x0);
  EXPECT_NEAR(m["cartesian_error"].get<double>(), score.geometric_mean,
              1e-9 * score.geometric_mean);
  EXPECT_EQ(m["cartesian_error_failed"], score.failed);
}

// Finzi et al.'s HNN learns V and M^-1 from the chain's angles and angular velocities: its run
// records those coordinates, its loss falls, and the run loads back as a mass HNN (both MLPs in
// its parameters) whose dq/dt is the state's velocities.
TEST(ConstrainedTask, TheirHnnLearnsItsMassMatrixFromAnglesAndVelocities) {
  TempDir dir("runs");
  RunOptions o = tiny("hnn-mass", dir / "m");
  o.steps = 30;
  const nlohmann::json m = run_training(o);
  EXPECT_EQ(m["coordinates"], "angles (theta, omega)");
  EXPECT_EQ(m["model"], "hnn-mass");
  EXPECT_TRUE(m["hamiltonian_rel_l2"].is_number())
      << "its H against the truth's, up to H's constant";
  EXPECT_EQ(m["cartesian_error_failed"], 0);
  const std::string curve = testing::read_text(dir / "m" / "loss_curve.csv");
  const auto loss_at = [&](std::size_t line_start) {
    const std::size_t comma = curve.find(',', line_start);
    return std::stod(curve.substr(comma + 1));
  };
  const std::size_t first = curve.find('\n') + 1, last = curve.rfind('\n', curve.size() - 2) + 1;
  EXPECT_LT(loss_at(last), 0.8 * loss_at(first)) << curve;
  const LoadedRun loaded = load_run(dir / "m");
  const auto* model = dynamic_cast<const nn::MassHnn<double>*>(&loaded.run->dynamics());
  ASSERT_NE(model, nullptr);
  const Batch x0 = loaded.run->rollout_states(2);
  ASSERT_EQ(x0.cols(), 4);  // (theta, omega) of two links
  EXPECT_EQ(model->field(x0).leftCols(2), x0.rightCols(2));
}

// Where their HNN fails (their repository's issue 3: NaNs in HNNs on the chains): seed 2's mass
// HNN at full width on the 3-chain's data, after AdamW's first update, carries a state of the
// next batch out of float's range within its RK4 steps. The run stops at that step saying so,
// keeping the last good checkpoint and writing no results.
TEST(ConstrainedTask, AMassHnnThatDivergesStopsAtThatStep) {
  TempDir dir("runs");
  RunOptions o = testing::small_run("chain-pendulum-3", "hnn-mass", dir / "m", 3);
  o.hidden.reset();  // the task's 3 x 256
  o.batch_size = 10;
  o.seed = 2;
  o.task_settings = {{"trajectories", 110}, {"validation", 2}, {"rollouts", 2}};
  try {
    run_training(o);
    FAIL() << "the run finished";
  } catch (const TrainingDiverged& e) {
    EXPECT_EQ(e.step(), 2);
    EXPECT_NE(std::string(e.what()).find("training diverged at step 2: the loss is "),
              std::string::npos)
        << e.what();
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "m" / "metrics.json"));
  EXPECT_FALSE(std::filesystem::exists(dir / "m" / "params.bin"));
}

// The CHNN and CLNN get the task's own points, masses and constraints (links and anchors on the
// chain, pins on the gyroscope) and learn only V: their rollouts stay on the constraint manifold
// to the rollout tolerance, whatever V they have learned.
TEST(ConstrainedTask, TheConstrainedModelsTrainOnTheSystemsOwnConstraints) {
  TempDir dir("runs");
  const nn::ConstraintSpec chain = make_field_task("chain-pendulum-2")->constraints();
  EXPECT_EQ(chain.points, 2);
  EXPECT_EQ(chain.links.size() + chain.anchors.size(), 2u);
  EXPECT_FALSE(make_field_task("gyroscope")->constraints().pins.empty());
  for (const auto& [task, model] :
       {std::pair{"chain-pendulum-2", "chnn"}, std::pair{"chain-pendulum-2", "clnn"},
        std::pair{"gyroscope", "chnn"}}) {
    const std::filesystem::path out = dir / (std::string(task) + model);
    const nlohmann::json m = run_training(tiny(model, out, task));
    EXPECT_EQ(m["coordinates"], "cartesian") << task << " " << model;
    EXPECT_TRUE(std::isfinite(m["cartesian_error"].get<double>())) << task << " " << model;
    EXPECT_EQ(m["cartesian_error_failed"], 0) << task << " " << model;
    const LoadedRun loaded = load_run(out);
    const Batch x0 = loaded.run->rollout_states(2);
    const pc::ConstrainedSystem system = pc::make_constrained_system(
        std::string(task) == "gyroscope" ? "gyroscope" : "chain_pendulum_2");
    const std::vector<double> t = system.output_times();
    const Rollouts r = make_rollouts(system, loaded.run->dynamics(), x0,
                                     {.t_end = t.back(),
                                      .points = int(t.size()),
                                      .rtol = 1e-9,
                                      .atol = 1e-11,
                                      .perturbation = 0});
    for (const auto& path : r.pred) {
      EXPECT_LT(system.constraint_values(path).cwiseAbs().maxCoeff(), 1e-5) << task << model;
    }
  }
}

// --masses learned: the CHNN learns each body's mass (the chain's points) or mass and moments (the
// gyroscope's rigid body) with V, from 0.1 N(0, 1) log masses; the run loads back with them. Models
// without a mass matrix of their own refuse the option.
TEST(ConstrainedTask, TheConstrainedModelsLearnTheirMassesWhenAsked) {
  TempDir dir("runs");
  for (const auto& [task, count] : {std::pair{"chain-pendulum-2", 2}, std::pair{"gyroscope", 4}}) {
    RunOptions o = tiny("chnn", dir / task, task);
    o.task_settings["masses"] = "learned";
    const nlohmann::json m = run_training(o);
    EXPECT_EQ(m["cartesian_error_failed"], 0) << task;
    const LoadedRun loaded = load_run(dir / task);
    const auto* model = dynamic_cast<const nn::ConstrainedModel<double>*>(&loaded.run->dynamics());
    ASSERT_NE(model, nullptr) << task;
    EXPECT_TRUE(model->config().constraints.learned_masses) << task;
    const Batch c = model->inverse_mass_coefficients();
    ASSERT_EQ(c.cols(), count) << task;
    EXPECT_GT(c.minCoeff(), 0.5) << task;
    EXPECT_LT(c.maxCoeff(), 2.0) << task;
    EXPECT_NE(model->describe().find("learned masses"), std::string::npos) << task;
    // metrics.json gives them as masses and moments, beside the system's own.
    const auto learned = m.at("masses_learned").get<std::vector<double>>();
    const Eigen::VectorXd truth = nn::inverse_mass_coefficients(model->config().constraints);
    ASSERT_EQ(learned.size(), std::size_t(count)) << task;
    ASSERT_EQ(m.at("masses_true").size(), std::size_t(count)) << task;
    for (int k = 0; k < count; ++k) {
      EXPECT_NEAR(learned[std::size_t(k)] * c(0, k), 1.0, 1e-12) << task;
      EXPECT_NEAR(m["masses_true"][std::size_t(k)].get<double>() * truth[k], 1.0, 1e-12) << task;
    }
    // Drawn near 1, three steps from the start: they move the system otherwise than its own.
    EXPECT_GT(m.at("masses_tangent_error").get<double>(), 1e-3) << task;
  }
  const nlohmann::json known = run_training(tiny("chnn", dir / "known"));
  EXPECT_FALSE(known.contains("masses_learned"));
  RunOptions hnn = tiny("hnn", dir / "h");
  hnn.task_settings["masses"] = "learned";
  try {
    run_training(hnn);
    FAIL() << "an HNN took --masses learned";
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(),
                 "chain-pendulum-2: --masses learned applies to --model chnn and clnn only, not "
                 "hnn");
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "h"));
}

// Off the chains, their HNN and the LNN learn the body coordinates with their rates (the
// gyroscope's Euler angles): the run says so, its rollouts are scored in Cartesian coordinates
// through the body's map, and the free HNN, which needs canonical momenta in angles, is refused
// saying where hnn has them.
TEST(ConstrainedTask, OffTheChainsTheirHnnLearnsBodyCoordinates) {
  TempDir dir("runs");
  for (const char* model : {"hnn-mass", "lnn"}) {
    SCOPED_TRACE(model);
    const nlohmann::json m = run_training(tiny(model, dir / model, "gyroscope"));
    EXPECT_EQ(m["coordinates"], "body coordinates (q, dq/dt)");
    const LoadedRun loaded = load_run(dir / model);
    const Batch x0 = loaded.run->rollout_states(2);
    ASSERT_EQ(x0.cols(), 6);  // three Euler angles and their rates
    const pc::RolloutScore score =
        rescored(pc::BodyCoordinates(pc::make_constrained_system("gyroscope")), loaded, x0);
    EXPECT_NEAR(m["cartesian_error"].get<double>(), score.geometric_mean,
                1e-9 * score.geometric_mean);
  }
  try {
    run_training(tiny("hnn", dir / "hnn", "gyroscope"));
    FAIL() << "hnn accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("canonical momenta in angle coordinates"),
              std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("--model hnn-mass"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "hnn"));
}

TEST(ConstrainedTask, RefusesAZeroTrajectoryCount) {
  TempDir dir("runs");
  RunOptions o = tiny("baseline", dir / "bad");
  o.task_settings["trajectories"] = 0;
  EXPECT_THROW(run_training(o), Error);
}

TEST(RolloutLoss, ATasksDefaultLossAndTheNormKey) {
  const RolloutLossConfig chunks{.rollout = true, .horizon = 4, .norm = RolloutNorm::kL1};
  RolloutLossConfig c = rollout_loss_config(nlohmann::json::object(), "t", chunks);
  EXPECT_TRUE(c.rollout);
  EXPECT_EQ(c.horizon, 4);
  EXPECT_EQ(c.norm, RolloutNorm::kL1);
  c = rollout_loss_config({{"loss", "rollout"}, {"norm", "l2"}}, "t", chunks);
  EXPECT_EQ(c.horizon, 4);
  EXPECT_EQ(c.norm, RolloutNorm::kL2);
  c = rollout_loss_config({{"loss", "derivative"}}, "t", chunks);
  EXPECT_FALSE(c.rollout);
  EXPECT_EQ(c.norm, RolloutNorm::kL2);
  EXPECT_EQ(rollout_loss_config({{"loss", "rollout"}, {"norm", "l1"}}, "t").norm, RolloutNorm::kL1);
  EXPECT_THROW(rollout_loss_config({{"norm", "l1"}}, "t"), Error);  // dx/dt targets
  EXPECT_THROW(rollout_loss_config({{"loss", "rollout"}, {"norm", "l3"}}, "t"), Error);
  EXPECT_EQ(rollout_loss_config({{"loss", "rollout"}}, "t").to_json().count("norm"), 0u);
}

}  // namespace
}  // namespace hnn::tasks
