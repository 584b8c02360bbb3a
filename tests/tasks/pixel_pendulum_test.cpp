// Task 5, the pixel pendulum, on a small configuration (a few trials, narrow layers, a few
// steps): data offsets and shapes, the loss, training, the run folder with its GIF and PNG
// (decoded again with giflib and libpng), the energy bump, and reversibility.

#include "tasks/experiments/pixel_pendulum.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <random>

#include "autodiff/grad.h"
#include "autodiff/ops.h"
#include "autodiff/tape.h"
#include "tasks/evaluate/reversibility.h"
#include "tasks/experiments/registry.h"
#include "tasks/pixel/bump.h"
#include "tasks/pixel/objective.h"
#include "tasks/report/image_io.h"
#include "tasks/run.h"
#include "tasks/studies/published.h"

namespace hnn::tasks::pixel {
namespace {

namespace fs = std::filesystem;

PixelConfig small_config() {
  Eigen::setNbThreads(1);  // small products: OpenMP threads on busy cores would only wait
  PixelConfig c;
  c.trials = 6;
  c.frames_per_trial = 23;  // 20 pairs per trial, 120 pairs, 24 test rows
  c.ae_hidden = 32;
  c.hidden = {16, 16};
  c.steps = 80;
  c.batch_size = 32;
  c.learning_rate = 3e-3;
  c.rollout_frames = 20;
  c.rollout_trials = 1;
  c.curve_rows = 40;
  return c;
}

// A fresh folder under the build tree, emptied first.
fs::path scratch(const std::string& name) {
  const fs::path dir = fs::path(HNN_BINARY_DIR) / "test_scratch" / ("pixel_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::string head_bytes(const fs::path& path, std::size_t n) {
  std::ifstream in(path, std::ios::binary);
  std::string bytes(n, '\0');
  in.read(bytes.data(), std::streamsize(n));
  bytes.resize(std::size_t(in.gcount()));
  return bytes;
}

// The training loop on the pixel objective, quiet.
template <typename T>
TrainResult train_pixel(PixelModel<T>& model, const PixelData& data, const PixelConfig& c,
                        std::uint64_t seed) {
  PixelObjective<T> objective(model, data, c, seed);
  return train(objective, {.steps = c.steps, .record_every = c.record_every, .quiet = true});
}

// `hnn train pixel-pendulum` options for a config: the training settings as options, the rest
// as the task's own settings.
RunOptions run_options(const PixelConfig& c, const fs::path& out, std::uint64_t seed) {
  RunOptions o{.task = kPixelPendulum,
               .seed = seed,
               .steps = c.steps,
               .batch_size = c.batch_size,
               .hidden = c.hidden,
               .learning_rate = c.learning_rate,
               .out = out,
               .quiet = true};
  o.task_settings = c.to_json();
  for (const char* key : {"steps", "batch_size", "learning_rate", "weight_decay", "hidden"})
    o.task_settings.erase(key);
  return o;
}

// One trained HNN shared by the tests that need a model (training is the slow part).
struct Trained {
  PixelConfig config = small_config();
  PixelData data = build_pixel_data(config, 3);
  std::mt19937_64 rng{3};
  PixelModel<double> model{config, nn::ModelKind::kHnn, rng};
  TrainResult result;
  Trained() { result = train_pixel(model, data, config, 3); }
};

const Trained& trained() {
  static const Trained t;
  return t;
}

TEST(PixelData, HasTheReferenceOffsetsAndSplit) {
  const PixelConfig c = small_config();
  const PixelData d = build_pixel_data(c, 1);
  EXPECT_EQ(d.frames.rows(), 6 * 23);
  EXPECT_EQ(d.frames.cols(), 784);
  EXPECT_EQ(d.pairs_per_trial(), 20);
  EXPECT_EQ(d.pairs(), 120);
  EXPECT_EQ(d.test_rows, 24);  // int(120 * 0.2)
  EXPECT_EQ(d.first_frame(0), 1);
  EXPECT_EQ(d.first_frame(20), 23 + 1);  // trial 1 starts at its frame 1
  const ad::Matrix<double> x = d.pairs_of<double>({0, 19, 57}, false);
  const ad::Matrix<double> next = d.pairs_of<double>({0, 19, 57}, true);
  ASSERT_EQ(x.rows(), 3);
  ASSERT_EQ(x.cols(), kPairPixels);
  // A pair's second frame is its successor's first; the last successor ends on the trial's
  // last frame (frame 22 of trial 0 for pair 19).
  EXPECT_EQ(x.row(1).tail(784), next.row(1).head(784));
  EXPECT_EQ(next.row(1).tail(784), d.frames.row(22).cast<double>());
  // Frames are the scene's renders of the stored Gym states, which follow Gym's step.
  const physics::GymPendulum scene;
  EXPECT_TRUE(d.frames.row(5).cast<double>().isApprox(scene.render(d.states[5].th), 1e-6));
  EXPECT_DOUBLE_EQ(d.states[6].th, scene.step(d.states[5]).th);
  // Trials start inside (0, pi/6) from hanging down.
  for (int trial = 0; trial < c.trials; ++trial) {
    const double theta = scene.to_canonical(d.states[std::size_t(trial * 23)])(0);
    EXPECT_GT(std::abs(theta), 0.0);
    EXPECT_LT(std::abs(theta), M_PI / 6);
  }
  // The recovered state of a true pair is close to the true state of its second frame.
  const Eigen::RowVector2d recovered = state_from_pair(scene, x.row(2));
  const physics::Batch truth = d.coords_of({57});
  EXPECT_NEAR(recovered(0), truth(0, 0), 0.02);
  EXPECT_NEAR(recovered(1), truth(0, 1), 0.05);
}

// Gym's step is a leapfrog with velocities at half steps: the state halfway between two frames
// keeps its energy within about 1%, where a frame's own (th, thdot) swings by about 10%.
TEST(PixelState, PairStateKeepsTheTrueEnergyNearlyConstant) {
  const physics::GymPendulum scene;
  const std::vector<physics::GymState> s = scene.rollout(scene.from_canonical(0.45, 0.1), 120);
  Eigen::VectorXd paired(119), own(119);
  for (int k = 0; k < 119; ++k) {
    paired(k) = scene.energy(pair_state(s[std::size_t(k)].th, s[std::size_t(k) + 1].th));
    own(k) = scene.energy(scene.to_canonical(s[std::size_t(k) + 1]));
  }
  const auto swing = [](const Eigen::VectorXd& e) {
    return (e.maxCoeff() - e.minCoeff()) / e.mean();
  };
  EXPECT_LT(swing(paired), 0.02);
  EXPECT_GT(swing(own), 0.1);
}

// A state read from two frames one step apart: state_from_pair reads a pair's two halves the
// same way, and on rendered frames it recovers the true state (rollouts use it on the first
// frames of consecutive decoded pairs).
TEST(PixelState, FromFramesRecoversTheTrueStateOfRenderedFrames) {
  const physics::GymPendulum scene;
  const std::vector<physics::GymState> s = scene.rollout(scene.from_canonical(0.4, -0.2), 30);
  for (int k = 0; k < 29; k += 7) {
    const Eigen::RowVectorXd a = scene.render(s[std::size_t(k)].th);
    const Eigen::RowVectorXd b = scene.render(s[std::size_t(k) + 1].th);
    Eigen::RowVectorXd pair(kPairPixels);
    pair << a, b;
    const Eigen::RowVector2d from_frames = state_from_frames(scene, a, b);
    EXPECT_EQ(from_frames, state_from_pair(scene, pair));
    const Eigen::RowVector2d truth = pair_state(s[std::size_t(k)].th, s[std::size_t(k) + 1].th);
    EXPECT_NEAR(from_frames(0), truth(0), 0.02) << k;
    EXPECT_NEAR(from_frames(1), truth(1), 0.05) << k;
  }
  EXPECT_TRUE(std::isnan(
      state_from_frames(scene, Eigen::RowVectorXd::Zero(784), scene.render(s[0].th))(1)));
}

TEST(PixelData, IsDeterministicInTheSeed) {
  const PixelConfig c = small_config();
  const PixelData a = build_pixel_data(c, 7), b = build_pixel_data(c, 7),
                  other = build_pixel_data(c, 8);
  EXPECT_TRUE((a.frames.array() == b.frames.array()).all());
  EXPECT_FALSE((a.frames.array() == other.frames.array()).all());
}

TEST(PixelLoss, TermsHaveOneValuePerSampleAndAddUp) {
  const PixelConfig c = small_config();
  const PixelData d = build_pixel_data(c, 1);
  for (const nn::ModelKind kind : {nn::ModelKind::kHnn, nn::ModelKind::kBaseline}) {
    std::mt19937_64 rng(1);
    const PixelModel<double> model(c, kind, rng);
    ad::TapeScope scope;
    const PixelLoss<double> l =
        pixel_loss(model, ad::Var<double>::constant(d.pairs_of<double>({0, 1, 2, 3, 4}, false)),
                   ad::Var<double>::constant(d.pairs_of<double>({0, 1, 2, 3, 4}, true)), 0.1);
    for (const ad::Var<double>* term : {&l.total, &l.ae, &l.cc, &l.hnn}) {
      EXPECT_EQ(term->rows(), 5);
      EXPECT_EQ(term->cols(), 1);
    }
    EXPECT_TRUE(l.total.value().isApprox(l.ae.value() + l.cc.value() + 0.1 * l.hnn.value()));
    EXPECT_TRUE(l.total.requires_grad());
  }
}

// The HNN term differentiates H with respect to z = enc(x), so its gradient must reach the
// encoder along the second-order path: checked against central differences.
TEST(PixelLoss, HnnTermGradientReachesTheEncoder) {
  PixelConfig c = small_config();
  c.ae_hidden = 8;
  c.hidden = {6, 6};
  const PixelData d = build_pixel_data(c, 1);
  std::mt19937_64 rng(1);
  PixelModel<double> model(c, nn::ModelKind::kHnn, rng);
  const ad::Matrix<double> x = d.pairs_of<double>({0, 1, 5}, false);
  const ad::Matrix<double> next = d.pairs_of<double>({0, 1, 5}, true);
  const auto hnn_loss = [&] {
    ad::TapeScope scope;
    return ad::mean(
               pixel_loss(model, ad::Var<double>::constant(x), ad::Var<double>::constant(next), 0.1)
                   .hnn)
        .item();
  };
  std::vector<nn::NamedParameter<double>> params = model.named_parameters();
  std::vector<ad::Var<double>> leaves;
  for (const auto& p : params) leaves.push_back(p.var);
  std::vector<ad::Matrix<double>> grads;
  {
    ad::TapeScope scope;
    const ad::Var<double> loss = ad::mean(
        pixel_loss(model, ad::Var<double>::constant(x), ad::Var<double>::constant(next), 0.1).hnn);
    ad::GradOptions options;
    options.allow_unused = true;  // the decoder does not enter the HNN term
    for (const ad::Var<double>& g : ad::grad<double>({loss}, leaves, options))
      grads.push_back(g.value());
  }
  int checked = 0;
  for (std::size_t i = 0; i < params.size(); ++i) {
    if (params[i].name.rfind("autoencoder.decoder", 0) == 0) continue;
    ad::Matrix<double>& value = params[i].var.mutable_value();
    for (Eigen::Index k = value.size() - 3; k < value.size(); ++k) {
      const double saved = value.data()[k], h = 1e-6;
      value.data()[k] = saved + h;
      const double up = hnn_loss();
      value.data()[k] = saved - h;
      const double down = hnn_loss();
      value.data()[k] = saved;
      const double fd = (up - down) / (2 * h);
      EXPECT_NEAR(grads[i].data()[k], fd, 1e-7 + 1e-5 * std::abs(fd)) << params[i].name << " " << k;
      ++checked;
    }
  }
  EXPECT_GE(checked, 3 * 11);  // 8 encoder tensors and the MLP's 5
}

TEST(PixelTraining, LossDecreases) {
  const TrainResult& r = trained().result;
  ASSERT_GE(r.curve.size(), 2u);
  EXPECT_LT(r.curve.back().train_loss, 0.5 * r.curve.front().train_loss);
  EXPECT_LT(r.curve.back().test_loss, 0.5 * r.curve.front().test_loss);
  EXPECT_EQ(r.steps, 80);
}

TEST(PixelTraining, BaselineLossDecreasesToo) {
  PixelConfig c = small_config();
  c.steps = 40;
  const PixelData d = build_pixel_data(c, 2);
  std::mt19937_64 rng(2);
  PixelModel<float> model(c, nn::ModelKind::kBaseline, rng);
  const TrainResult r = train_pixel(model, d, c, 2);
  EXPECT_LT(r.curve.back().train_loss, 0.5 * r.curve.front().train_loss);
}

TEST(PixelRun, WritesTheRunFolderWithReadableGifAndPng) {
  const fs::path dir = scratch("run");
  PixelConfig c = small_config();
  c.steps = 20;
  const nlohmann::json m = run_training(run_options(c, dir, 5));
  for (const char* key : {"train_loss", "train_loss_se", "test_loss", "test_loss_se", "energy_mse",
                          "energy_mse_se", "energy_mse_within_pair", "energy_mse_frames_floor",
                          "amplitude_ratio", "n_rollouts", "train_seconds", "eval_seconds"}) {
    EXPECT_TRUE(m.contains(key)) << key;
  }
  EXPECT_EQ(m["n_test"], 24);
  EXPECT_EQ(m["pixel"]["weight_decay"], 1e-5);  // the autoencoder's
  EXPECT_EQ(m["pixel"]["dynamics_weight_decay"], 0.0);
  EXPECT_EQ(m["n_rollouts"], 1);
  for (const char* file : {"metrics.json", "loss_curve.csv", "params.bin", "pixel_rollout.csv",
                           "latent_grid.csv", "latent_paths.csv", "checkpoint/state.json"}) {
    EXPECT_TRUE(fs::exists(dir / file)) << file;
  }
  EXPECT_EQ(head_bytes(dir / "rollout.gif", 6), "GIF89a");
  EXPECT_EQ(head_bytes(dir / "rollout_strip.png", 8), "\x89PNG\r\n\x1a\n");
  const std::vector<GrayImage> gif = read_gif(dir / "rollout.gif");
  ASSERT_EQ(gif.size(), 21u);                     // frames 0..20
  EXPECT_EQ(gif[0].width, 2 * (28 * 3 + 2) + 2);  // truth | model
  const GrayImage png = read_png(dir / "rollout_strip.png");
  EXPECT_EQ(png.height, 2 * (28 * 2 + 2) + 2);  // rows truth, model
  EXPECT_EQ(png.width, 3 * (28 * 2 + 2) + 2);   // frames 0, 10, 20
  // The rod is drawn: the true frame's brightest pixel is full white.
  EXPECT_EQ(*std::max_element(gif[0].pixels.begin(), gif[0].pixels.end()), 255);

  // Loaded back, the same parameters give the same losses.
  const nlohmann::json again = evaluate_run(dir, "", false);
  EXPECT_DOUBLE_EQ(again["test_loss"].get<double>(), m["test_loss"].get<double>());
  EXPECT_EQ(pixel_parts(*load_run(dir).run).config.trials, c.trials);
}

TEST(PixelBump, RiemannGradientRaisesTheLearnedH) {
  const Trained& t = trained();
  const fs::path dir = scratch("bump");
  BumpOptions o;
  o.before = 10;
  o.riemann = 0.5;
  o.after = 10;
  o.dt = 1;
  o.out = dir;
  const BumpResult up = energy_bump(t.model, t.data, t.config, o);
  EXPECT_GT(up.h_after, up.h_before);
  EXPECT_EQ(head_bytes(dir / "bump.gif", 6), "GIF89a");
  EXPECT_EQ(read_gif(dir / "bump.gif").size(), 11u + 10u + 10u);
  EXPECT_GT(read_png(dir / "bump_strip.png").width, 0);
  o.riemann = -0.5;
  o.out.clear();
  const BumpResult down = energy_bump(t.model, t.data, t.config, o);
  EXPECT_LT(down.h_after, down.h_before);
}

// The default mode: follow R_H until H has risen by `raise` x its spread over the test trials'
// first pairs (12 trials: 2 whole test trials), then S_H keeps the new level.
TEST(PixelBump, RaiseLiftsTheLearnedHByTheAskedFractionOfItsSpread) {
  const Trained& t = trained();
  PixelConfig c = t.config;
  c.trials = 12;
  const PixelData d = build_pixel_data(c, 4);
  ASSERT_EQ(d.test_trials(), 2);
  const Eigen::VectorXd h =
      t.model.energy(t.model.encode(d.pairs_of<double>({0, 20}, false))).col(0);
  const double spread = h.maxCoeff() - h.minCoeff();
  ASSERT_GT(spread, 0);
  BumpOptions o;
  o.before = 5;
  o.after = 5;
  o.raise = 0.5;
  const BumpResult up = energy_bump(t.model, d, c, o);
  EXPECT_GT(up.riemann_time, 0);
  // H is conserved along S_H, so the phase means differ by the rise (dopri5 at rtol 1e-9).
  EXPECT_NEAR(up.h_after - up.h_before, 0.5 * spread, 0.01 * spread);
  o.raise = -0.25;
  const BumpResult down = energy_bump(t.model, d, c, o);
  EXPECT_NEAR(down.h_after - down.h_before, -0.25 * spread, 0.01 * spread);
  // One test trial has no spread: the raise cannot be scaled.
  EXPECT_THROW(energy_bump(t.model, t.data, t.config, BumpOptions{}), std::runtime_error);
}

TEST(PixelBump, RefusesABaseline) {
  const PixelConfig c = small_config();
  const PixelData d = build_pixel_data(c, 1);
  std::mt19937_64 rng(1);
  const PixelModel<double> model(c, nn::ModelKind::kBaseline, rng);
  EXPECT_THROW(energy_bump(model, d, c, {}), std::exception);
}

TEST(Reversibility, MidpointReturnsToTheStart) {
  const Trained& t = trained();
  const physics::Batch z0 = t.model.encode(t.data.pairs_of<double>({0, 20}, false));
  ReversibilityOptions o;
  o.integrators = {"midpoint", "rk4"};
  o.t_end = 20;
  o.dt = 0.1;
  const nlohmann::json r = measure_reversibility(t.model.dynamics(), z0, o);
  ASSERT_EQ(r["integrators"].size(), 2u);
  EXPECT_LT(r["integrators"][0]["return_distance_max"].get<double>(), 1e-9);
  EXPECT_LT(r["integrators"][1]["return_distance_max"].get<double>(), 1e-3);
  // The HNN's latent flow keeps area.
  EXPECT_NEAR(r["volume"]["det_mean"].get<double>(), 1.0, 1e-4);
}

TEST(ImageIo, PngAndGifRoundTrip) {
  const fs::path dir = scratch("io");
  GrayImage a(5, 3), b(5, 3, 200);
  for (int i = 0; i < 15; ++i) a.pixels[std::size_t(i)] = std::uint8_t(i * 17);
  write_png(dir / "a.png", a);
  EXPECT_EQ(read_png(dir / "a.png").pixels, a.pixels);
  write_gif(dir / "ab.gif", {a, b}, 5);
  const std::vector<GrayImage> back = read_gif(dir / "ab.gif");
  ASSERT_EQ(back.size(), 2u);
  EXPECT_EQ(back[0].pixels, a.pixels);
  EXPECT_EQ(back[1].pixels, b.pixels);
  EXPECT_THROW(read_png(dir / "ab.gif"), std::runtime_error);
  EXPECT_THROW(write_gif(dir / "bad.gif", {a, GrayImage(2, 2)}, 5), std::runtime_error);
}

TEST(PixelTask, IsRegisteredWithThePapersRow) {
  const std::unique_ptr<Task> task = make_task(kPixelPendulum);
  EXPECT_EQ(task->name(), kPixelPendulum);
  EXPECT_EQ(task->train_config().steps, 10000);
  EXPECT_EQ(task->train_config().batch_size, 200);
  EXPECT_DOUBLE_EQ(task->train_config().weight_decay, 1e-5);
  const nlohmann::json published = read_published(published_path());
  EXPECT_DOUBLE_EQ(paper_row(published, kPixelPendulum, nn::ModelKind::kHnn).test_loss.mean,
                   1.8451e-4);
  EXPECT_DOUBLE_EQ(paper_row(published, kPixelPendulum, nn::ModelKind::kBaseline).energy_mse.mean,
                   9.2748e-3);
}

}  // namespace
}  // namespace hnn::tasks::pixel
