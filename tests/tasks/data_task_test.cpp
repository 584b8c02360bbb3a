// The data task: units that keep an HNN Hamiltonian, a run on a user's CSV file from end to end,
// the same relative results at any scale of the data, and its bad settings.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>

#include "physics/expression_system.h"
#include "tasks/data/units.h"
#include "tasks/experiments/registry.h"
#include "tasks/task.h"
#include "test_configs.h"

namespace hnn::tasks {
namespace {

using testing::read_json;
using testing::read_lines;
using testing::TempDir;

// Two decoupled oscillators, H = (p1^2 + p2^2)/2 + (4 q1^2 + q2^2)/2, sampled exactly at 25
// times over 3 time units from 12 initial states; column c is multiplied by scale[c].
void write_oscillators(const std::filesystem::path& path, const std::array<double, 4>& scale) {
  std::ofstream out(path);
  out << "trajectory,t,q1,q2,p1,p2\n";
  out.precision(17);
  for (int k = 0; k < 12; ++k) {
    // Amplitudes shuffled: the last trajectories (the test set) lie within the others' range.
    const double a1 = 0.5 + 0.1 * (k * 5 % 12), a2 = 1.2 - 0.07 * (k * 7 % 12);
    const double f1 = 0.3 * k, f2 = 1.1 * k;
    for (int i = 0; i < 25; ++i) {
      const double t = 3.0 * i / 24;
      const double q1 = a1 * std::cos(2 * t + f1), p1 = -2 * a1 * std::sin(2 * t + f1);
      const double q2 = a2 * std::cos(t + f2), p2 = -a2 * std::sin(t + f2);
      out << k << ',' << t << ',' << q1 * scale[0] << ',' << q2 * scale[1] << ',' << p1 * scale[2]
          << ',' << p2 * scale[3] << '\n';
    }
  }
}

RunOptions data_run(const std::filesystem::path& file, const std::filesystem::path& out,
                    const std::string& model = "hnn") {
  RunOptions o = testing::small_run("data", model, out, 1000);
  o.hidden = std::vector<int>{32, 32};
  o.data_file = file.string();
  o.task_settings = {{"coords", {"q1", "q2"}}, {"momenta", {"p1", "p2"}}};
  return o;
}

// In the model's units the field of a Hamiltonian system is the symplectic gradient of
// H' = H * time / c: checked on H = p1^2/2 + 3 p2^2 + q1^4 + q1 q2 with finite differences.
TEST(Units, KeepAFieldHamiltonian) {
  const physics::ExpressionSystem h("p1^2/2 + 3*p2^2 + q1^4 + q1*q2", {"q1", "q2"}, {"p1", "p2"});
  Dataset d;
  std::mt19937_64 rng(3);
  d.train_x = h.sample_initial_states(200, rng);
  d.train_x.col(0) *= 50;  // very different column scales
  d.train_x.col(3) *= 0.02;
  h.vector_field(d.train_x, d.train_dxdt);
  const Units u = fit_units(d, 2, {"q1", "q2", "p1", "p2"});
  EXPECT_NEAR(u.scale(0) * u.scale(2), u.scale(1) * u.scale(3), 1e-12 * u.scale(0) * u.scale(2));
  EXPECT_LT((u.to_file(u.to_model(d.train_x)) - d.train_x).norm(), 1e-10 * d.train_x.norm());
  const double rms = u.rate_to_model(d.train_dxdt).array().square().mean();
  EXPECT_NEAR(rms, 1.0, 1e-12);

  const Batch z = u.to_model(d.train_x.topRows(5));
  Batch dxdt;
  h.vector_field(u.to_file(z), dxdt);
  const Batch dzdt = u.rate_to_model(dxdt);
  const auto h_model = [&](const Batch& zz) {
    return Eigen::VectorXd(h.hamiltonian_batch(u.to_file(zz)) / u.energy_to_file());
  };
  const double eps = 1e-6;
  for (int c = 0; c < 4; ++c) {
    Batch plus = z, minus = z;
    plus.col(c).array() += eps;
    minus.col(c).array() -= eps;
    const Eigen::VectorXd dh = (h_model(plus) - h_model(minus)) / (2 * eps);
    // dz/dt' = (dH'/dp', -dH'/dq')
    const Eigen::VectorXd expected =
        c < 2 ? Eigen::VectorXd(-dzdt.col(c + 2)) : Eigen::VectorXd(dzdt.col(c - 2));
    EXPECT_LT((dh - expected).norm(), 1e-5 * (1 + expected.norm())) << "column " << c;
  }
}

TEST(Units, RefuseAConstantColumnByName) {
  Dataset d;
  d.train_x = Batch::Random(10, 2);
  d.train_x.col(1).setConstant(4);
  d.train_dxdt = Batch::Random(10, 2);
  try {
    fit_units(d, 1, {"x", "v"});
    FAIL() << "a constant column was accepted";
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(),
                 "column 'v' is constant over the training split: nothing to learn from it");
  }
}

TEST(DataTask, TrainsOnACsvAndEvaluatesOnHeldOutTrajectories) {
  TempDir dir("data");
  write_oscillators(dir / "osc.csv", {1, 1, 1, 1});
  RunOptions o = data_run(dir / "osc.csv", dir / "hnn");
  o.task_settings["hamiltonian"] = "(p1^2 + p2^2)/2 + (4*q1^2 + q2^2)/2";
  const nlohmann::json m = run_training(o);
  EXPECT_EQ(m["n_held_out"], 2);  // 20% of 12 trajectories
  EXPECT_EQ(m["n_train"], 250);
  EXPECT_GT(m["test_r2"].get<double>(), 0.95);
  EXPECT_GT(m["valid_prediction_time"].get<double>(), 0.5);
  EXPECT_LT(m["coordinate_mse"].get<double>(), 0.05) << m.dump(1);
  EXPECT_LT(m["learned_h_drift_relative"].get<double>(), 1e-4);  // conserved along its own flow
  EXPECT_TRUE(m["energy_mse"].is_number());
  // The relative figure beside it: unit-free, and small for a good fit of H near 1.
  EXPECT_GT(m["energy_relative_mse"].get<double>(), 0);
  EXPECT_LT(m["energy_relative_mse"].get<double>(), 0.1);
  EXPECT_TRUE(m["energy_relative_mse_se"].is_number());
  EXPECT_EQ(m["state_names"], nlohmann::json({"q1", "q2", "p1", "p2"}));
  // The loss watched during training (loss_curve.csv, the progress line) is in metrics.json
  // under its own name, and "units" says which keys are in which units.
  const std::vector<std::string> curve = read_lines(dir / "hnn" / "loss_curve.csv");
  EXPECT_EQ(curve[0], "step,train_loss_standardised,test_loss_standardised");  // the file says so
  const double watched = std::stod(curve.back().substr(curve.back().rfind(',') + 1));
  EXPECT_NEAR(m["test_loss_standardised"].get<double>(), watched, 1e-6 * watched);
  EXPECT_NE(m["test_loss_standardised"], m["test_loss"]);
  for (const char* key : {"test_loss_standardised", "loss_curve.csv"}) {
    const nlohmann::json& listed = m["units"]["standardised"];
    EXPECT_NE(std::find(listed.begin(), listed.end(), key), listed.end()) << key;
  }
  EXPECT_NE(m["units"]["file"].get<std::string>().find("test_loss"), std::string::npos);
  const std::vector<std::string> csv = read_lines(dir / "hnn" / "rollout.csv");
  EXPECT_EQ(csv[0], "source,traj,t,q1,q2,p1,p2,energy,learned_h");
  EXPECT_EQ(csv.size(), 1u + 2 * 2 * 25);  // per held-out stretch the data's rows and the hnn's
  EXPECT_EQ(csv[1].substr(0, 9), "data,0,0,");
  EXPECT_EQ(csv[26].substr(0, 8), "hnn,0,0,");
  // A loaded run evaluates to the same numbers.
  const nlohmann::json again = evaluate_run(dir / "hnn", "", false);
  EXPECT_DOUBLE_EQ(again["test_loss"].get<double>(), m["test_loss"].get<double>());

  // What `hnn export` writes: the model with the units folded in, whose field in the file's
  // units is the trained model's field carried through the units.
  const LoadedRun loaded = load_run(dir / "hnn");
  Units u = identity_units(4);
  for (int c = 0; c < 4; ++c) {
    u.mean(c) = m["units"]["mean"][c];
    u.scale(c) = m["units"]["scale"][c];
  }
  u.time = m["units"]["time"];
  const Batch x = Batch::Random(7, 4);
  const Batch expected = u.rate_to_file(loaded.run->dynamics().field(u.to_model(x)));
  const Batch folded = loaded.run->model_in_data_units()->field(x);
  EXPECT_LT((folded - expected).norm(), 1e-12 * expected.norm());
}

// Without a known H there is no energy MSE, and the metrics say why.
TEST(DataTask, WithoutAHamiltonianHasNoEnergyMse) {
  TempDir dir("data");
  write_oscillators(dir / "osc.csv", {1, 1, 1, 1});
  RunOptions o = data_run(dir / "osc.csv", dir / "base", "baseline");
  o.steps = 20;
  const nlohmann::json m = run_training(o);
  EXPECT_TRUE(m["energy_mse"].is_null());
  EXPECT_FALSE(m.contains("learned_h_drift"));  // a baseline learns no H
  EXPECT_NE(m["energy_note"].get<std::string>().find("--hamiltonian"), std::string::npos);
}

// The same data in other units: the same R^2 and valid prediction time, losses scaled by the
// square of the factor (x100 and x0.01, with different factors per column).
TEST(DataTask, AnyScaleGivesTheSameRelativeResults) {
  TempDir dir("data");
  // x100, x0.01, and each degree of freedom in its own units (q1 x100 with p1 x0.01: a canonical
  // change of units, which keeps the products q_i p_i equal).
  const std::array<std::array<double, 4>, 4> scales = {
      {{1, 1, 1, 1}, {100, 100, 100, 100}, {0.01, 0.01, 0.01, 0.01}, {100, 1, 0.01, 1}}};
  std::vector<nlohmann::json> runs;
  for (std::size_t k = 0; k < scales.size(); ++k) {
    const std::string name = "s" + std::to_string(k);
    write_oscillators(dir / (name + ".csv"), scales[k]);
    RunOptions o = data_run(dir / (name + ".csv"), dir / name);
    o.steps = 60;
    runs.push_back(run_training(o));
  }
  for (std::size_t k = 1; k < runs.size(); ++k) {
    if (k < 3) {  // R^2 pools the columns: the same only when all have one factor
      EXPECT_NEAR(runs[k]["test_r2"].get<double>(), runs[0]["test_r2"].get<double>(), 1e-9) << k;
    }
    EXPECT_NEAR(runs[k]["valid_prediction_time"].get<double>(),
                runs[0]["valid_prediction_time"].get<double>(), 1e-9)
        << k;
    // The standardised loss (the progress line's) is the same whatever the file's units.
    EXPECT_NEAR(runs[k]["test_loss_standardised"].get<double>(),
                runs[0]["test_loss_standardised"].get<double>(),
                1e-6 * runs[0]["test_loss_standardised"].get<double>())
        << k;
  }
  EXPECT_NEAR(runs[1]["test_loss"].get<double>() / runs[0]["test_loss"].get<double>(), 1e4, 1e-5);
  EXPECT_NEAR(runs[2]["test_loss"].get<double>() / runs[0]["test_loss"].get<double>(), 1e-4, 1e-13);
}

TEST(DataTask, RefusesBadSettingsByName) {
  TempDir dir("data");
  write_oscillators(dir / "osc.csv", {1, 1, 1, 1});
  const auto message = [&](const nlohmann::json& settings, std::string file = "") {
    RunOptions o =
        data_run(file.empty() ? dir / "osc.csv" : std::filesystem::path(file), dir / "bad");
    o.data_file = file == "none" ? "" : o.data_file;
    o.task_settings.update(settings);
    try {
      run_training(o);
    } catch (const Error& e) {
      EXPECT_FALSE(std::filesystem::exists(dir / "bad")) << e.what();
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_TRUE(message({{"colour", 1}}).starts_with("the data task has no setting 'colour'"));
  EXPECT_TRUE(message({{"split", "random"}}).starts_with("data: split 'random' is not one of"));
  EXPECT_TRUE(message({{"hamiltonian", "p1^2 + r"}}).starts_with("--hamiltonian: hamiltonian"));
  EXPECT_NE(message({{"hamiltonian", "p1^2 + r"}}).find("unknown name 'r'"), std::string::npos);
  EXPECT_TRUE(message({{"threshold", 2}}).starts_with("data: threshold 2 is not between 0 and 1"));
  EXPECT_TRUE(message(nlohmann::json::object(), "none").starts_with("the data task needs a file"));
  EXPECT_NE(message({{"coords", {"q1", "x"}}}).find("'x'"), std::string::npos);
}

// Coarse samples (the oscillators at 25 points over 3 time units, every 4th kept: dt = 0.5):
// trained through RK4 from the states alone, the model rolls out better than one trained on
// finite-difference derivatives of the same states; a horizon past every stretch is refused.
TEST(DataTask, TheRolloutLossLearnsFromCoarseStates) {
  TempDir dir("data");
  write_oscillators(dir / "osc.csv", {1, 1, 1, 1});
  {
    const std::vector<std::string> lines = read_lines(dir / "osc.csv");
    std::ofstream coarse(dir / "coarse.csv");
    coarse << lines[0] << "\n";
    for (std::size_t i = 1; i < lines.size(); ++i)
      if ((i - 1) % 25 % 4 == 0) coarse << lines[i] << "\n";
  }
  std::map<std::string, nlohmann::json> m;
  for (const char* loss : {"derivative", "rollout"}) {
    RunOptions o = data_run(dir / "coarse.csv", dir / loss);
    o.steps = 400;
    o.task_settings["loss"] = loss;
    m[loss] = run_training(o);
  }
  EXPECT_LT(m["rollout"]["coordinate_mse"].get<double>() * 3,
            m["derivative"]["coordinate_mse"].get<double>())
      << m["rollout"].dump() << m["derivative"].dump();
  RunOptions o = data_run(dir / "coarse.csv", dir / "bad");
  o.task_settings["loss"] = "rollout";
  o.task_settings["horizon"] = 7;
  try {
    run_training(o);
    FAIL() << "a horizon past every stretch was accepted";
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(),
                 "a horizon of 7 steps is past the end of every training stretch (the longest "
                 "has 7 points, so 6 steps at most)");
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "bad"));
}

TEST(DataTask, IsNotOneOfThePapersTasks) {
  EXPECT_EQ(paper_task_names().size(), 6u);
  EXPECT_EQ(task_names().back(), "data");
}

}  // namespace
}  // namespace hnn::tasks
