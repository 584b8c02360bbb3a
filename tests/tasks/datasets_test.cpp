// The datasets of tasks 1-4b against docs/tasks.md: sizes and splits, targets equal to the true
// field at the clean states, the noise level, the samplers' distributions, and determinism.

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <numbers>
#include <sstream>

#include "physics/integrator.h"
#include "tasks/experiments/registry.h"
#include "tasks/field/field_task.h"
#include "tasks/run.h"
#include "tests/tasks/test_configs.h"

namespace hnn::tasks {
namespace {

using Rows = Eigen::MatrixXd;

// Rows [i * points, (i + 1) * points): trajectory i of a split.
Rows trajectory(const Batch& x, int i, int points) {
  return x.middleRows(Eigen::Index(i) * points, points);
}

bool bit_identical(const Batch& a, const Batch& b) {
  return a.rows() == b.rows() && a.cols() == b.cols() && (a.array() == b.array()).all();
}

bool bit_identical(const Dataset& a, const Dataset& b) {
  return bit_identical(a.train_x, b.train_x) && bit_identical(a.train_dxdt, b.train_dxdt) &&
         bit_identical(a.test_x, b.test_x) && bit_identical(a.test_dxdt, b.test_dxdt);
}

Batch stack(const Batch& a, const Batch& b) {
  Batch out(a.rows() + b.rows(), a.cols());
  out << a, b;
  return out;
}

double mean(const Eigen::VectorXd& v) { return v.mean(); }
double stddev(const Eigen::VectorXd& v) {
  return std::sqrt((v.array() - v.mean()).square().sum() / double(v.size() - 1));
}

// Sample noise of N values with std sigma: the sample std lies within 5 standard errors,
// sigma / sqrt(2N) each; the mean within 5 * sigma / sqrt(N).
void expect_gaussian_noise(const Eigen::VectorXd& noise, double sigma, const std::string& what) {
  const double n = double(noise.size());
  EXPECT_NEAR(mean(noise), 0.0, 5 * sigma / std::sqrt(n)) << what;
  EXPECT_NEAR(stddev(noise), sigma, 5 * sigma / std::sqrt(2 * n)) << what;
  // Gaussian, not uniform: about 4.55% of draws lie beyond 2 sigma (uniform of that std: 0%).
  const double beyond = double((noise.array().abs() > 2 * sigma).count()) / n;
  EXPECT_NEAR(beyond, 0.0455, 0.02) << what;
}

TEST(TaskRegistry, NamesTheStateTasksInOrderAndRejectsOthers) {
  const std::vector<std::string>& expected = testing::state_tasks();
  const std::vector<std::string> names = task_names();
  ASSERT_GE(names.size(), expected.size());
  EXPECT_EQ(std::vector<std::string>(names.begin(), names.begin() + long(expected.size())),
            expected);
  for (const std::string& name : names) {
    const std::unique_ptr<Task> task = make_task(name);
    EXPECT_EQ(task->name(), name);
    EXPECT_FALSE(task->summary().empty());
  }
  EXPECT_THROW(make_field_task("pixel-pendulum"), Error);  // it learns from frames
  try {
    make_task("spring2");
    FAIL() << "an unknown task was accepted";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("spring2"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("two-body"), std::string::npos) << e.what();
  }
}

TEST(TaskRegistry, TrainingSettingsAreThePapers) {
  struct Expected {
    std::string task;
    int steps, batch;
    double weight_decay;
    int rollout_points;
  };
  for (const Expected& e :
       {Expected{"spring", 2000, 0, 1e-4, 100}, Expected{"pendulum", 2000, 0, 1e-4, 100},
        Expected{"real-pendulum", 2000, 0, 1e-5, 100}, Expected{"two-body", 10000, 200, 0.0, 1000},
        Expected{"three-body", 10000, 600, 1e-4, 100}}) {
    const std::unique_ptr<FieldTask> task = make_field_task(e.task);
    const TrainConfig c = task->train_config();
    EXPECT_EQ(c.steps, e.steps) << e.task;
    EXPECT_EQ(c.batch_size, e.batch) << e.task;
    EXPECT_DOUBLE_EQ(c.weight_decay, e.weight_decay) << e.task;
    EXPECT_DOUBLE_EQ(c.learning_rate, 1e-3) << e.task;
    EXPECT_EQ(c.hidden, (std::vector<int>{200, 200})) << e.task;
    const RolloutConfig r = task->rollout_config();
    EXPECT_EQ(r.points, e.rollout_points) << e.task;
    EXPECT_EQ(r.trajectories, kDefaultRollouts) << e.task;
    EXPECT_DOUBLE_EQ(r.t_end, 20.0) << e.task;
    EXPECT_LE(r.rtol, 1e-9) << e.task;
  }
}

TEST(TaskRegistry, OnlyMeasuredDataTasksTakeADataFile) {
  for (const char* name : {"spring", "two-body", "pixel-pendulum"}) {
    EXPECT_FALSE(make_task(name)->reads_data_file()) << name;
    EXPECT_THROW(resolve(*make_task(name), {.task = name, .data_file = "x.txt"}), Error) << name;
  }
  EXPECT_TRUE(make_task("real-pendulum")->reads_data_file());
  EXPECT_NO_THROW(
      resolve(*make_task("real-pendulum"), {.task = "real-pendulum", .data_file = "x.txt"}));
}

// Task 1: H = q^2 + p^2, 50 trajectories of 30 points over [0, 3], noise std 0.1.
TEST(SpringDataset, SplitsTrajectoriesInHalves) {
  const Dataset d = make_field_task("spring")->build_dataset(0);
  EXPECT_EQ(d.train_x.rows(), 750);
  EXPECT_EQ(d.test_x.rows(), 750);
  for (const Batch* b : {&d.train_x, &d.train_dxdt, &d.test_x, &d.test_dxdt})
    EXPECT_EQ(b->cols(), 2);
  EXPECT_EQ(d.train_dxdt.rows(), 750);
  EXPECT_EQ(d.test_dxdt.rows(), 750);
}

TEST(SpringDataset, TargetsAreTheExactFieldOnCleanOrbitsAndInputsCarryNoise) {
  const Dataset d = make_field_task("spring")->build_dataset(3);
  const Batch x = stack(d.train_x, d.test_x), dxdt = stack(d.train_dxdt, d.test_dxdt);
  // dq/dt = 2p, dp/dt = -2q at the clean state, so the targets give the clean state back.
  Batch clean(x.rows(), 2);
  clean.col(0) = -dxdt.col(1) / 2;
  clean.col(1) = dxdt.col(0) / 2;
  // Each trajectory is the exact flow (rotation by angle 2t) of its first clean state, sampled at
  // 30 evenly spaced times over [0, 3], from radius U[0.1, 1].
  Eigen::VectorXd radii(50);
  for (int i = 0; i < 50; ++i) {
    const Rows path = trajectory(clean, i, 30);
    radii(i) = path.row(0).norm();
    EXPECT_GE(radii(i), 0.1) << "trajectory " << i;
    EXPECT_LE(radii(i), 1.0) << "trajectory " << i;
    for (int k = 0; k < 30; ++k) {
      const double t = 3.0 * k / 29.0, c = std::cos(2 * t), s = std::sin(2 * t);
      EXPECT_NEAR(path(k, 0), c * path(0, 0) + s * path(0, 1), 1e-9) << i << " " << k;
      EXPECT_NEAR(path(k, 1), c * path(0, 1) - s * path(0, 0), 1e-9) << i << " " << k;
    }
  }
  EXPECT_NEAR(radii.mean(), 0.55, 0.15);  // U[0.1, 1]: mean 0.55, std of the mean 0.037
  // Inputs = clean + N(0, 0.1^2), independently on q and p.
  const Batch noise = x - clean;
  expect_gaussian_noise(noise.col(0), 0.1, "noise on q");
  expect_gaussian_noise(noise.col(1), 0.1, "noise on p");
  const double corr = (noise.col(0).array() * noise.col(1).array()).mean() / 0.01;
  EXPECT_NEAR(corr, 0.0, 0.15);
}

TEST(SpringDataset, SameSeedSameBitsOtherSeedOtherData) {
  const std::unique_ptr<FieldTask> task = make_field_task("spring");
  const Dataset a = task->build_dataset(11), b = make_field_task("spring")->build_dataset(11);
  EXPECT_TRUE(bit_identical(a, b));
  const Dataset c = task->build_dataset(12);
  EXPECT_FALSE(bit_identical(a.train_x, c.train_x));
  EXPECT_FALSE(bit_identical(a.test_dxdt, c.test_dxdt));
}

// Task 2: H = 3(1 - cos q) + p^2, radius U[1.3, 2.3], 45 points over [0, 3].
TEST(PendulumDataset, SplitsTrajectoriesInHalves) {
  const Dataset d = make_field_task("pendulum")->build_dataset(0);
  EXPECT_EQ(d.train_x.rows(), 1125);
  EXPECT_EQ(d.test_x.rows(), 1125);
  EXPECT_EQ(d.train_dxdt.rows(), 1125);
  EXPECT_EQ(d.test_dxdt.rows(), 1125);
  EXPECT_EQ(d.train_x.cols(), 2);
  EXPECT_EQ(d.test_dxdt.cols(), 2);
}

TEST(PendulumDataset, TargetsAreTheExactFieldOnCleanOrbitsAndInputsCarryNoise) {
  const std::unique_ptr<FieldTask> task = make_field_task("pendulum");
  const Dataset d = task->build_dataset(5);
  const Batch x = stack(d.train_x, d.test_x), dxdt = stack(d.train_dxdt, d.test_dxdt);
  // dq/dt = 2p and dp/dt = -3 sin q give p and sin q; the branch of q (cos q > 0 or < 0) is the
  // one whose energy 3(1 - cos q) + p^2 matches its trajectory's. That energy comes from the
  // points with |sin q| < 0.9, where the noisy input alone tells the branches apart.
  const auto energy = [](const Rows& s) {
    return (3.0 * (1.0 - s.col(0).array().cos()) + s.col(1).array().square()).matrix().eval();
  };
  Batch clean(x.rows(), 2);
  for (int i = 0; i < 50; ++i) {
    std::vector<double> candidates[2];  // per point: the branch with cos q >= 0, then < 0
    double level = 0;
    int unambiguous = 0;
    for (int k = 0; k < 45; ++k) {
      const Eigen::Index row = Eigen::Index(i) * 45 + k;
      const double s = std::clamp(-dxdt(row, 1) / 3.0, -1.0, 1.0), a = std::asin(s);
      const double far = a >= 0 ? std::numbers::pi - a : -std::numbers::pi - a;
      candidates[0].push_back(a);
      candidates[1].push_back(far);
      clean(row, 1) = dxdt(row, 0) / 2;
      if (std::abs(s) < 0.9) {
        const double q = std::abs(a - x(row, 0)) < std::abs(far - x(row, 0)) ? a : far;
        level += 3.0 * (1.0 - std::cos(q)) + clean(row, 1) * clean(row, 1);
        ++unambiguous;
      }
    }
    ASSERT_GT(unambiguous, 5) << "trajectory " << i;
    level /= unambiguous;
    for (int k = 0; k < 45; ++k) {
      const Eigen::Index row = Eigen::Index(i) * 45 + k;
      const double kinetic = clean(row, 1) * clean(row, 1);
      const auto mismatch = [&](double q) {
        return std::abs(3 * (1 - std::cos(q)) + kinetic - level);
      };
      clean(row, 0) = mismatch(candidates[0][k]) <= mismatch(candidates[1][k]) ? candidates[0][k]
                                                                               : candidates[1][k];
    }
  }
  const auto dopri = physics::make_integrator("dopri5", {.rtol = 1e-12, .atol = 1e-14});
  const std::vector<double> times = physics::linspace(0.0, 3.0, 45);
  for (int i = 0; i < 50; ++i) {
    const Rows path = trajectory(clean, i, 45);
    const double r = path.row(0).norm();
    EXPECT_GE(r, 1.3 - 1e-6) << "trajectory " << i;
    EXPECT_LE(r, 2.3 + 1e-6) << "trajectory " << i;
    const Eigen::VectorXd e = energy(path);
    EXPECT_LT((e.array() - e(0)).abs().maxCoeff(), 1e-7) << "trajectory " << i;
    if (i % 10 == 0) {  // the sample times: an independent tight integration from the start
      const physics::Trajectory ref =
          dopri->integrate(task->truth().field(), Batch(path.row(0)), times);
      EXPECT_LT((ref.path(0) - path).cwiseAbs().maxCoeff(), 1e-6) << "trajectory " << i;
    }
  }
  const Batch noise = x - clean;
  expect_gaussian_noise(noise.col(0), 0.1, "noise on q");
  expect_gaussian_noise(noise.col(1), 0.1, "noise on p");
}

TEST(PendulumDataset, SameSeedSameBitsOtherSeedOtherData) {
  const Dataset a = make_field_task("pendulum")->build_dataset(2);
  const Dataset b = make_field_task("pendulum")->build_dataset(2);
  EXPECT_TRUE(bit_identical(a, b));
  EXPECT_FALSE(bit_identical(a.train_x, make_field_task("pendulum")->build_dataset(3).train_x));
}

// Task 3: the shipped Schmidt & Lipson file, read here independently of physics/lipson.
struct MeasuredRows {
  std::vector<double> trial, t, angle, velocity;
};

MeasuredRows read_measured(const std::filesystem::path& path) {
  std::ifstream in(path);
  EXPECT_TRUE(in.good()) << path;
  MeasuredRows rows;
  for (std::string line; std::getline(in, line);) {
    if (line.empty() || line[0] == '%' || line == "\r") continue;
    std::istringstream fields(line);
    double a, b, c, d;
    if (!(fields >> a >> b >> c >> d)) continue;
    rows.trial.push_back(a);
    rows.t.push_back(b);
    rows.angle.push_back(c);
    rows.velocity.push_back(d);
  }
  return rows;
}

TEST(RealPendulumDataset, ForwardDifferencesOfTheShippedFileSplit80To20InOrder) {
  const MeasuredRows file =
      read_measured(std::filesystem::path(HNN_SOURCE_DIR) / "data/lipson/real_pend_h_1.txt");
  ASSERT_EQ(file.t.size(), 556u);  // one trial
  const Dataset d = make_field_task("real-pendulum")->build_dataset(0);
  const Eigen::Index n = 555, cut = n * 8 / 10;  // the last point has no forward difference
  ASSERT_EQ(d.train_x.rows(), cut);
  ASSERT_EQ(d.test_x.rows(), n - cut);
  ASSERT_EQ(d.train_dxdt.rows(), cut);
  ASSERT_EQ(d.test_dxdt.rows(), n - cut);
  const Batch x = stack(d.train_x, d.test_x), dxdt = stack(d.train_dxdt, d.test_dxdt);
  for (Eigen::Index i = 0; i < n; ++i) {
    const std::size_t k = std::size_t(i);
    const double dt = file.t[k + 1] - file.t[k];
    EXPECT_EQ(x(i, 0), file.angle[k]) << "row " << i;
    EXPECT_EQ(x(i, 1), file.velocity[k]) << "row " << i;
    EXPECT_NEAR(dxdt(i, 0), (file.angle[k + 1] - file.angle[k]) / dt, 1e-12) << "row " << i;
    EXPECT_NEAR(dxdt(i, 1), (file.velocity[k + 1] - file.velocity[k]) / dt, 1e-12) << "row " << i;
  }
}

TEST(RealPendulumDataset, IgnoresTheSeed) {
  const std::unique_ptr<FieldTask> task = make_field_task("real-pendulum");
  EXPECT_TRUE(bit_identical(task->build_dataset(0), task->build_dataset(9)));
}

TEST(RealPendulumDataset, ReadsAnotherFileAndDifferencesWithinEachTrial) {
  testing::TempDir dir("data");
  const std::filesystem::path path = dir / "two_trials.txt";
  {
    std::ofstream out(path, std::ios::binary);
    out << "%o v\r\n";
    // Trial 0: 8 rows, trial 1: 6 rows; angle = t^2, velocity = trial + row.
    for (int trial = 0; trial < 2; ++trial)
      for (int k = 0; k < (trial == 0 ? 8 : 6); ++k) {
        const double t = 0.5 * k;
        out << trial << " " << t << " " << t * t << " " << trial + k << "\r\n";
      }
  }
  const std::unique_ptr<FieldTask> task = make_field_task("real-pendulum");
  const Dataset d = task->build_dataset({.task = "real-pendulum", .data_file = path.string()});
  // 7 + 5 differences (none across the trial boundary): 9 train, 3 test.
  ASSERT_EQ(d.train_x.rows(), 9);
  ASSERT_EQ(d.test_x.rows(), 3);
  const Batch x = stack(d.train_x, d.test_x), dxdt = stack(d.train_dxdt, d.test_dxdt);
  for (Eigen::Index i = 0; i < 12; ++i) {
    const int k = i < 7 ? int(i) : int(i) - 7;  // row within its trial
    const double t = 0.5 * k;
    EXPECT_DOUBLE_EQ(x(i, 0), t * t);
    EXPECT_DOUBLE_EQ(dxdt(i, 0), ((t + 0.5) * (t + 0.5) - t * t) / 0.5) << "row " << i;
    EXPECT_DOUBLE_EQ(dxdt(i, 1), 2.0) << "row " << i;  // velocity rises by 1 per 0.5 s
  }
}

TEST(RealPendulumDataset, MissingOrMalformedFileThrows) {
  testing::TempDir dir("data");
  const std::unique_ptr<FieldTask> task = make_field_task("real-pendulum");
  EXPECT_THROW(task->build_dataset({.data_file = (dir / "absent.txt").string()}), std::exception);
  const std::filesystem::path backwards = dir / "backwards.txt";
  std::ofstream(backwards) << "%o v\n0 1.0 0.1 0.2\n0 0.5 0.2 0.3\n0 1.5 0.3 0.4\n";
  EXPECT_THROW(task->build_dataset({.data_file = backwards.string()}), std::exception);
}

// Tasks 4 and 4b: gravity, masses 1, G = 1, coordinates (qx.., qy.., px.., py..).
Batch nbody_field(const Batch& x, int bodies) {
  Batch f = Batch::Zero(x.rows(), x.cols());
  const int n = bodies;
  f.leftCols(2 * n) = x.rightCols(2 * n);
  for (Eigen::Index r = 0; r < x.rows(); ++r)
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) {
        if (i == j) continue;
        const double dx = x(r, i) - x(r, j), dy = x(r, n + i) - x(r, n + j);
        const double d3 = std::pow(dx * dx + dy * dy, 1.5);
        f(r, 2 * n + i) -= dx / d3;
        f(r, 3 * n + i) -= dy / d3;
      }
  return f;
}

Eigen::VectorXd nbody_energy(const Rows& x, int n) {
  Eigen::VectorXd e = 0.5 * x.rightCols(2 * n).rowwise().squaredNorm();
  for (Eigen::Index r = 0; r < x.rows(); ++r)
    for (int i = 0; i < n; ++i)
      for (int j = i + 1; j < n; ++j)
        e(r) -= 1.0 / std::hypot(x(r, i) - x(r, j), x(r, n + i) - x(r, n + j));
  return e;
}

// Centre of mass and total momentum (equal masses): both zero on every row.
void expect_zero_com_and_momentum(const Batch& x, int n, const std::string& what) {
  double worst = 0;
  for (int block = 0; block < 4; ++block)
    worst = std::max(worst, x.middleCols(block * n, n).rowwise().sum().cwiseAbs().maxCoeff());
  EXPECT_LT(worst, 1e-9) << what;
}

// Checks trajectories of an N-body split: exact targets, conserved energy, and (for a few) the
// sample times against an independent tight integration.
void expect_exact_trajectories(const FieldTask& task, const Batch& x, const Batch& dxdt, int n,
                               int points, double t_end, const std::string& what) {
  const int trajectories = int(x.rows()) / points;
  const Batch field = nbody_field(x, n);
  EXPECT_LT(((field - dxdt).array().abs() / (1.0 + field.array().abs())).maxCoeff(), 1e-12) << what;
  if (n == 2) expect_zero_com_and_momentum(x, n, what);  // three bodies: perturbed momenta
  double worst_drift = 0;
  for (int i = 0; i < trajectories; ++i) {
    const Eigen::VectorXd e = nbody_energy(trajectory(x, i, points), n);
    worst_drift = std::max(worst_drift, (e.array() - e(0)).abs().maxCoeff() / std::abs(e(0)));
  }
  EXPECT_LT(worst_drift, 1e-6) << what << ": relative energy drift along a trajectory";
  const auto dopri = physics::make_integrator("dopri5", {.rtol = 1e-12, .atol = 1e-15});
  const std::vector<double> times = physics::linspace(0.0, t_end, points);
  for (int i : {0, trajectories / 2, trajectories - 1}) {
    const Rows path = trajectory(x, i, points);
    const physics::Trajectory ref =
        dopri->integrate(task.truth().field(), Batch(path.row(0)), times);
    EXPECT_LT((ref.path(0) - path).cwiseAbs().maxCoeff(), 1e-5) << what << " trajectory " << i;
  }
}

TEST(TwoBodyDataset, TwentyPercentTestFirstExactDerivativesNearCircularOrbits) {
  const std::unique_ptr<FieldTask> task = make_field_task("two-body");
  const Dataset d = task->build_dataset(0);
  ASSERT_EQ(d.train_x.rows(), 40000);
  ASSERT_EQ(d.test_x.rows(), 10000);
  ASSERT_EQ(d.train_dxdt.rows(), 40000);
  ASSERT_EQ(d.test_dxdt.rows(), 10000);
  ASSERT_EQ(d.train_x.cols(), 8);
  ASSERT_EQ(d.test_dxdt.cols(), 8);
  expect_exact_trajectories(*task, d.train_x, d.train_dxdt, 2, 50, 20.0, "train");
  expect_exact_trajectories(*task, d.test_x, d.test_dxdt, 2, 50, 20.0, "test");
  // Initial states: body 1 at pos ~ U[0.5, 1.5]^2, body 2 at -pos, velocity perpendicular to pos
  // with speed 1 / (2 sqrt r) scaled by 1 + 0.05 N(0, 1).
  const Batch x = stack(d.test_x, d.train_x);
  Eigen::VectorXd scale(1000);
  for (int i = 0; i < 1000; ++i) {
    const Eigen::RowVectorXd s = x.row(Eigen::Index(i) * 50);
    const Eigen::Vector2d pos(s(0), s(2)), vel(s(4), s(6));
    EXPECT_TRUE(pos.x() >= 0.5 && pos.x() <= 1.5 && pos.y() >= 0.5 && pos.y() <= 1.5)
        << "trajectory " << i << ": " << pos.transpose();
    EXPECT_NEAR(pos.dot(vel), 0.0, 1e-12) << "trajectory " << i;
    EXPECT_GT(pos.x() * vel.y() - pos.y() * vel.x(), 0.0) << "counter-clockwise orbit";
    scale(i) = vel.norm() * 2.0 * std::sqrt(pos.norm()) - 1.0;
  }
  EXPECT_NEAR(mean(scale), 0.0, 5 * 0.05 / std::sqrt(1000.0));
  EXPECT_NEAR(stddev(scale), 0.05, 5 * 0.05 / std::sqrt(2000.0));
}

TEST(TwoBodyDataset, SameSeedSameBitsOtherSeedOtherData) {
  const Dataset a = make_field_task("two-body")->build_dataset(4);
  EXPECT_TRUE(bit_identical(a, make_field_task("two-body")->build_dataset(4)));
  EXPECT_FALSE(bit_identical(a.test_x, make_field_task("two-body")->build_dataset(5).test_x));
}

// The three-body set (100,000 points) is built once for all its tests.
class ThreeBodyDataset : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    data_ = new Dataset(make_field_task("three-body")->build_dataset(0));
  }
  static void TearDownTestSuite() {
    delete data_;
    data_ = nullptr;
  }
  static const Dataset* data_;
};
const Dataset* ThreeBodyDataset::data_ = nullptr;

TEST_F(ThreeBodyDataset, TwentyPercentTestFirstExactDerivatives) {
  const Dataset& d = *data_;
  ASSERT_EQ(d.train_x.rows(), 80000);
  ASSERT_EQ(d.test_x.rows(), 20000);
  ASSERT_EQ(d.train_dxdt.rows(), 80000);
  ASSERT_EQ(d.test_dxdt.rows(), 20000);
  ASSERT_EQ(d.train_x.cols(), 12);
  const std::unique_ptr<FieldTask> task = make_field_task("three-body");
  expect_exact_trajectories(*task, d.train_x, d.train_dxdt, 3, 20, 5.0, "train");
  expect_exact_trajectories(*task, d.test_x, d.test_dxdt, 3, 20, 5.0, "test");
}

TEST_F(ThreeBodyDataset, InitialStatesArePerturbedRotatingTriangles) {
  const Batch x = stack(data_->test_x, data_->train_x);
  const double speed =
      std::sqrt(std::sin(std::numbers::pi / 3) / (2 * std::pow(std::cos(std::numbers::pi / 6), 2)));
  Eigen::VectorXd factors(5000 * 6);
  for (int i = 0; i < 5000; ++i) {
    const Eigen::RowVectorXd s = x.row(Eigen::Index(i) * 20);
    const Eigen::Vector2d p1(s(0), s(3));
    const double r = p1.norm();
    EXPECT_TRUE(r >= 0.9 - 1e-12 && r <= 1.2 + 1e-12) << "trajectory " << i << ": r = " << r;
    for (int b = 0; b < 3; ++b) {
      const double angle = 2 * std::numbers::pi * b / 3;
      const Eigen::Vector2d pos(s(b), s(3 + b));
      const Eigen::Vector2d want(std::cos(angle) * p1.x() - std::sin(angle) * p1.y(),
                                 std::sin(angle) * p1.x() + std::cos(angle) * p1.y());
      EXPECT_LT((pos - want).norm(), 1e-12) << "trajectory " << i << " body " << b;
      // The unperturbed velocity is rot90(pos) / r^1.5 * speed; each component is scaled.
      const Eigen::Vector2d v0 = Eigen::Vector2d(-pos.y(), pos.x()) / std::pow(r, 1.5) * speed;
      const Eigen::Vector2d vel(s(6 + b), s(9 + b));
      for (int axis = 0; axis < 2; ++axis) {
        if (std::abs(v0(axis)) > 0.05)
          factors(6 * i + 2 * b + axis) = vel(axis) / v0(axis) - 1;
        else
          factors(6 * i + 2 * b + axis) = NAN;
      }
    }
  }
  // Factors 1 + 0.2 U[-1, 1]: within [-0.2, 0.2], mean 0, std 0.2 / sqrt(3).
  std::vector<double> kept;
  for (Eigen::Index k = 0; k < factors.size(); ++k)
    if (std::isfinite(factors(k))) kept.push_back(factors(k));
  ASSERT_GT(kept.size(), 20000u);
  const Eigen::Map<const Eigen::VectorXd> f(kept.data(), Eigen::Index(kept.size()));
  EXPECT_LE(f.cwiseAbs().maxCoeff(), 0.2 + 1e-9);
  EXPECT_NEAR(mean(f), 0.0, 0.005);
  EXPECT_NEAR(stddev(f), 0.2 / std::sqrt(3.0), 0.005);
}

TEST_F(ThreeBodyDataset, SameSeedSameBits) {
  EXPECT_TRUE(bit_identical(*data_, make_field_task("three-body")->build_dataset(0)));
}

}  // namespace
}  // namespace hnn::tasks
