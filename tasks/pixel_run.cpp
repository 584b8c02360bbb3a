// Task 5's run folders: train and evaluate end to end, load a run back, its CSVs, and the
// animations (GIF) and strips (PNG) of decoded rollouts.

#include <chrono>
#include <cmath>
#include <fstream>

#include "autodiff/parallel.h"
#include "nn/checkpoint.h"
#include "physics/integrator.h"
#include "tasks/files.h"
#include "tasks/image_io.h"
#include "tasks/pixel_pendulum.h"
#include "tasks/task_library.h"

namespace hnn::tasks::pixel {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr int kSide = physics::GymPendulum::kSide;
constexpr int kGap = 2;       // pixels between tiles
constexpr int kGifScale = 3;  // each frame pixel as a 3 x 3 block in the GIF
constexpr int kStripScale = 2;
constexpr int kGifDelay = 5;  // hundredths of a second: Gym's dt, so the GIF runs in real time

json number(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

json stats_json(const nn::MeanStderr& s) {
  return {{"mean", number(s.mean)}, {"se", number(s.std_error)}};
}

std::string cell(double v) { return std::isfinite(v) ? fmt::format("{:.9g}", v) : ""; }

// grid[r][c]: frames (times x 784) shown in tile row r, column c; one GIF image per time.
void write_animation(const fs::path& path,
                     const std::vector<std::vector<const Eigen::MatrixXf*>>& grid) {
  const int rows = int(grid.size()), cols = int(grid.front().size());
  const int tile = kSide * kGifScale + kGap;
  const Eigen::Index times = grid.front().front()->rows();
  std::vector<GrayImage> images;
  for (Eigen::Index k = 0; k < times; ++k) {
    GrayImage image(cols * tile + kGap, rows * tile + kGap, 64);
    for (int r = 0; r < rows; ++r) {
      for (int c = 0; c < cols; ++c) {
        draw_frame(image, kGap + c * tile, kGap + r * tile, grid[r][c]->row(k), kSide, kGifScale,
                   physics::GymPendulum::kIntensity);
      }
    }
    images.push_back(std::move(image));
  }
  write_gif(path, images, kGifDelay);
}

// One row per source, every `stride` frames from 0: Figure 4's strip.
void write_strip(const fs::path& path, const std::vector<const Eigen::MatrixXf*>& rows,
                 int stride) {
  const int tile = kSide * kStripScale + kGap;
  const int cols = int((rows.front()->rows() - 1) / stride) + 1;
  GrayImage image(cols * tile + kGap, int(rows.size()) * tile + kGap, 64);
  for (std::size_t r = 0; r < rows.size(); ++r) {
    for (int c = 0; c < cols; ++c) {
      draw_frame(image, kGap + c * tile, kGap + int(r) * tile, rows[r]->row(c * stride), kSide,
                 kStripScale, physics::GymPendulum::kIntensity);
    }
  }
  write_png(path, image);
}

std::string rollout_csv(const PixelRollouts& r) {
  std::string csv =
      "traj,frame,frame_mse,true_theta,true_p,true_energy,pred_theta,pred_p,pred_energy,"
      "frames_energy,z_q,z_p,learned_h,pair_energy\n";
  for (Eigen::Index i = 0; i < r.true_energy.rows(); ++i) {
    for (Eigen::Index k = 0; k < Eigen::Index(r.t.size()); ++k) {
      csv +=
          fmt::format("{},{},{},{},{},{},{},{},{},{},{},{},{},{}\n", i, r.t[std::size_t(k)],
                      cell(r.frame_mse(i, k)), cell(r.true_theta(i, k)), cell(r.true_p(i, k)),
                      cell(r.true_energy(i, k)), cell(r.pred_theta(i, k)), cell(r.pred_p(i, k)),
                      cell(r.pred_energy(i, k)), cell(r.frames_energy(i, k)),
                      cell(r.z[std::size_t(i)](k, 0)), cell(r.z[std::size_t(i)](k, 1)),
                      r.learned_h.size() ? cell(r.learned_h(i, k)) : "", cell(r.pair_energy(i, k)));
    }
  }
  return csv;
}

// The encoded pairs of the test trials (Figure C.1's trajectories) and, over their bounding box
// with a margin, the learned field and H on a grid.
void write_latent_files(const PixelModel<double>& model, const PixelData& data,
                        const fs::path& out) {
  const int trials = std::min(data.test_trials(), 10);
  std::vector<Eigen::Index> rows;
  for (Eigen::Index i = 0; i < Eigen::Index(trials) * data.pairs_per_trial(); ++i)
    rows.push_back(i);
  const physics::Batch z = model.encode(data.pairs_of<double>(rows, false));
  const physics::Batch x = data.coords_of(rows);
  std::string paths = "traj,k,z_q,z_p,theta,p\n";
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const auto row = Eigen::Index(i);
    paths += fmt::format("{},{},{:.9g},{:.9g},{:.9g},{:.9g}\n", row / data.pairs_per_trial(),
                         row % data.pairs_per_trial(), z(row, 0), z(row, 1), x(row, 0), x(row, 1));
  }
  write_file_atomic(out / "latent_paths.csv", paths);

  constexpr int kGrid = 60;
  const Eigen::RowVector2d lo = z.colwise().minCoeff(), hi = z.colwise().maxCoeff();
  const Eigen::RowVector2d margin = 0.3 * (hi - lo).cwiseMax(1e-3);
  physics::Batch grid(kGrid * kGrid, 2);
  for (int a = 0; a < kGrid; ++a) {
    for (int b = 0; b < kGrid; ++b) {
      grid(a * kGrid + b, 0) =
          lo(0) - margin(0) + (hi(0) - lo(0) + 2 * margin(0)) * a / (kGrid - 1);
      grid(a * kGrid + b, 1) =
          lo(1) - margin(1) + (hi(1) - lo(1) + 2 * margin(1)) * b / (kGrid - 1);
    }
  }
  const physics::Batch f = model.dynamics().field(grid);
  Eigen::VectorXd h;
  if (model.is_hnn()) h = model.energy(grid).col(0);
  std::string csv = "z_q,z_p,learned_h,dz_q,dz_p\n";
  for (Eigen::Index k = 0; k < grid.rows(); ++k) {
    csv += fmt::format("{:.9g},{:.9g},{},{:.9g},{:.9g}\n", grid(k, 0), grid(k, 1),
                       h.size() ? cell(h(k)) : "", f(k, 0), f(k, 1));
  }
  write_file_atomic(out / "latent_grid.csv", csv);
}

// Mean over trajectories of (max |theta| over the last 40 frames) / (max |theta| over the
// first 40): about 1 when the swing keeps its amplitude.
double amplitude_ratio(const Eigen::MatrixXd& theta) {
  const Eigen::Index m = theta.cols(), w = std::min<Eigen::Index>(40, m);
  double sum = 0;
  int used = 0;
  for (Eigen::Index i = 0; i < theta.rows(); ++i) {
    const double first = theta.row(i).head(w).cwiseAbs().maxCoeff();
    const double last = theta.row(i).tail(w).cwiseAbs().maxCoeff();
    if (std::isfinite(first) && std::isfinite(last) && first > 0) {
      sum += last / first;
      ++used;
    }
  }
  return used ? sum / used : NAN;
}

json evaluate_model(const PixelModel<double>& model, const PixelData& data,
                    const PixelConfig& config, const fs::path& out, bool write_files) {
  const auto start = std::chrono::steady_clock::now();
  const PixelLossStats train = pixel_loss_stats(model, data, false, config.hnn_weight);
  const PixelLossStats test = pixel_loss_stats(model, data, true, config.hnn_weight);
  const PixelRollouts r = pixel_rollouts(model, data, config, 2);
  const nn::MeanStderr energy = pixel_energy_mse(r);
  const nn::MeanStderr floor = pixel_energy_mse(r, EnergySource::kTrueFrames);
  const nn::MeanStderr within_pair = pixel_energy_mse(r, EnergySource::kWithinPair);
  Eigen::VectorXd frame_mse = Eigen::VectorXd::Zero(Eigen::Index(r.t.size()));
  int used = 0;
  for (Eigen::Index i = 0; i < r.frame_mse.rows(); ++i) {
    if (r.failed[std::size_t(i)]) continue;
    frame_mse += r.frame_mse.row(i).transpose();
    ++used;
  }
  frame_mse /= std::max(used, 1);
  const auto terms = [](const PixelLossStats& s) {
    return json{{"ae", stats_json(s.ae)}, {"cc", stats_json(s.cc)}, {"hnn", stats_json(s.hnn)}};
  };
  json m = {{"train_loss", number(train.total.mean)},
            {"train_loss_se", number(train.total.std_error)},
            {"test_loss", number(test.total.mean)},
            {"test_loss_se", number(test.total.std_error)},
            {"energy_mse", number(energy.mean)},
            {"energy_mse_se", number(energy.std_error)},
            {"n_rollouts", energy.count},
            {"rollout_failures", r.failures},
            {"n_train", data.train_rows()},
            {"n_test", data.test_rows},
            {"loss_terms", {{"train", terms(train)}, {"test", terms(test)}}},
            {"energy_mse_frames_floor", number(floor.mean)},
            {"energy_mse_within_pair", number(within_pair.mean)},
            {"energy_mse_within_pair_se", number(within_pair.std_error)},
            {"frame_mse_mean", number(frame_mse.mean())},
            {"frame_mse_first", number(frame_mse(0))},
            {"frame_mse_last", number(frame_mse(frame_mse.size() - 1))},
            {"amplitude_ratio", number(amplitude_ratio(r.pred_theta))},
            {"amplitude_ratio_true", number(amplitude_ratio(r.true_theta))},
            {"rollout_frames", config.rollout_frames},
            {"rollout_nfev", r.nfev}};
  if (write_files) {
    write_file_atomic(out / "pixel_rollout.csv", rollout_csv(r));
    write_latent_files(model, data, out);
    if (!r.true_frames.empty()) {
      std::vector<std::vector<const Eigen::MatrixXf*>> grid;
      for (std::size_t i = 0; i < r.true_frames.size(); ++i)
        grid.push_back({&r.true_frames[i], &r.pred_frames[i]});
      write_animation(out / "rollout.gif", grid);
      write_strip(out / "rollout_strip.png", {&r.true_frames[0], &r.pred_frames[0]}, 10);
    }
  }
  m["eval_seconds"] = seconds_since(start);
  return m;
}

std::string loss_curve_csv(const TrainResult& result) {
  std::string csv = "step,train_loss,test_loss\n";
  for (const CurvePoint& p : result.curve)
    csv += fmt::format("{},{:.9g},{:.9g}\n", p.step, p.train_loss, p.test_loss);
  return csv;
}

template <typename T>
json train_and_evaluate(const PixelData& data, const RunOptions& o, const PixelConfig& config) {
  std::mt19937_64 init_rng(o.seed);
  PixelModel<T> model(config, nn::parse_model_kind(o.model), init_rng);
  TrainHooks hooks;
  hooks.quiet = o.quiet;
  hooks.label = std::string(kTaskName) + " " + o.model;
  const TrainResult trained = train_pixel_model(model, data, config, o.seed, hooks);
  nn::save_parameters(o.out / "params.bin", model);
  write_file_atomic(o.out / "loss_curve.csv", loss_curve_csv(trained));
  const PixelModel<double> model_d = model.template cast<double>();
  json metrics = evaluate_model(model_d, data, config, o.out, true);
  metrics["train_seconds"] = trained.seconds;
  metrics["final_batch_loss"] =
      number(trained.curve.empty() ? NAN : trained.curve.back().train_loss);
  return metrics;
}

std::string join(const std::vector<int>& v) {
  std::string s;
  for (int x : v) s += (s.empty() ? "" : "-") + std::to_string(x);
  return s;
}

json read_metrics(const fs::path& run_dir) {
  const fs::path path = run_dir / "metrics.json";
  std::ifstream in(path);
  HNN_TASKS_CHECK(in.good(), "cannot read '{}': is '{}' a run folder of `hnn train`?",
                  path.string(), run_dir.string());
  try {
    return json::parse(in);
  } catch (const json::exception& e) {
    throw Error(fmt::format("'{}' is not valid JSON: {}", path.string(), e.what()));
  }
}

}  // namespace

json run_pixel_training(const RunOptions& o, PixelConfig config) {
  if (o.steps) config.steps = *o.steps;
  if (o.batch_size) config.batch_size = *o.batch_size;
  // The model-size sweep (issue 7) left this task out (10 min a run), so its `lean` preset is
  // the paper's widths; the preset is checked and recorded all the same.
  HNN_TASKS_CHECK(o.preset == "paper" || o.preset == "lean",
                  "--preset must be paper or lean, got '{}'", o.preset);
  if (o.hidden) config.hidden = *o.hidden;
  if (o.learning_rate) config.learning_rate = *o.learning_rate;
  validate(config);
  nn::parse_model_kind(o.model);
  HNN_TASKS_CHECK(o.dtype == "float" || o.dtype == "double",
                  "--dtype must be float or double, got '{}'", o.dtype);
  HNN_TASKS_CHECK(o.data_file.empty(), "pixel-pendulum renders its own frames: no --data");
  HNN_TASKS_CHECK(!o.out.empty(), "an output folder is required");
  ad::set_num_threads(o.threads);  // the fused kernels' row blocks
  const auto start = std::chrono::steady_clock::now();
  const PixelData data = build_pixel_data(config, o.seed);
  const double data_seconds = seconds_since(start);
  fs::create_directories(o.out);
  json metrics = o.dtype == "float" ? train_and_evaluate<float>(data, o, config)
                                    : train_and_evaluate<double>(data, o, config);
  metrics.update({{"task", kTaskName},
                  {"model", o.model},
                  {"seed", o.seed},
                  {"steps", config.steps},
                  {"batch_size", config.batch_size},
                  {"hidden", join(config.hidden)},
                  {"preset", o.preset},
                  {"learning_rate", config.learning_rate},
                  {"weight_decay", config.weight_decay},
                  {"dtype", o.dtype},
                  {"threads", o.threads},
                  {"data_file", ""},
                  {"data_seconds", data_seconds},
                  {"pixel", config.to_json()}});
  write_file_atomic(o.out / "metrics.json", metrics.dump(2) + "\n");
  return metrics;
}

bool is_pixel_run(const fs::path& run_dir) {
  std::ifstream in(run_dir / "metrics.json");
  if (!in) return false;
  const json m = json::parse(in, nullptr, /*allow_exceptions=*/false);
  return m.is_object() && m.value("task", "") == kTaskName;
}

LoadedPixelRun load_pixel_run(const fs::path& run_dir) {
  const json saved = read_metrics(run_dir);
  LoadedPixelRun run;
  try {
    HNN_TASKS_CHECK(saved.at("task") == kTaskName, "'{}' is a '{}' run, not {}", run_dir.string(),
                    saved.at("task").get<std::string>(), kTaskName);
    run.options.task = kTaskName;
    run.options.model = saved.at("model");
    run.options.seed = saved.at("seed");
    run.options.dtype = saved.at("dtype");
    run.config = PixelConfig::from_json(saved.at("pixel"));
  } catch (const json::exception& e) {
    throw Error(fmt::format("'{}' lacks a pixel run's settings: {}",
                            (run_dir / "metrics.json").string(), e.what()));
  }
  run.options.hidden = run.config.hidden;
  run.options.out = run_dir;
  run.data = build_pixel_data(run.config, run.options.seed);
  std::mt19937_64 rng(run.options.seed);
  const nn::ModelKind kind = nn::parse_model_kind(run.options.model);
  if (run.options.dtype == "float") {
    PixelModel<float> f(run.config, kind, rng);
    nn::load_parameters(run_dir / "params.bin", f);
    run.model = std::make_unique<PixelModel<double>>(f.cast<double>());
  } else {
    run.model = std::make_unique<PixelModel<double>>(run.config, kind, rng);
    nn::load_parameters(run_dir / "params.bin", *run.model);
  }
  return run;
}

json evaluate_pixel_run(const fs::path& run_dir, bool write_files) {
  const LoadedPixelRun run = load_pixel_run(run_dir);
  json m = evaluate_model(*run.model, run.data, run.config, run_dir, write_files);
  m.update({{"task", kTaskName},
            {"model", run.options.model},
            {"seed", run.options.seed},
            {"dtype", run.options.dtype}});
  return m;
}

fs::path write_pixel_rollout(const fs::path& run_dir, const PixelRolloutOptions& o) {
  const LoadedPixelRun run = load_pixel_run(run_dir);
  const physics::GymPendulum scene;
  const int n = std::min(o.trajectories, run.data.test_trials());
  std::vector<Eigen::Index> rows;
  for (int i = 0; i < n; ++i) rows.push_back(Eigen::Index(i) * run.data.pairs_per_trial());
  const physics::Batch z0 = run.model->encode(run.data.pairs_of<double>(rows, false));
  const auto integrator =
      physics::make_integrator(o.integrator, {.dt = o.dt, .rtol = o.rtol, .atol = o.rtol * 1e-3});
  // One frame past the last reported: its angle gives the last state's velocity.
  const std::vector<double> t = physics::linspace(0.0, o.frames + 1, o.frames + 2);
  const nn::DynamicsModel<double>& dynamics = run.model->dynamics();
  const physics::Trajectory path = integrator->integrate(
      [&dynamics](double, const physics::Batch& z, physics::Batch& dz) { dz = dynamics.field(z); },
      z0, t);
  std::string csv = "source,traj,t,z_q,z_p,theta,p,energy,learned_h\n";
  for (int i = 0; i < n; ++i) {
    const std::vector<physics::GymState> states = scene.rollout(
        run.data.states[std::size_t(run.data.first_frame(rows[std::size_t(i)]))], o.frames + 2);
    for (int k = 0; k <= o.frames; ++k) {
      const Eigen::RowVector2d x =
          pair_state(states[std::size_t(k)].th, states[std::size_t(k) + 1].th);
      csv += fmt::format("true,{},{},,,{:.9g},{:.9g},{:.9g},\n", i, t[std::size_t(k)], x(0), x(1),
                         scene.energy(x));
    }
    const physics::Batch z = path.path(i);
    const physics::Batch pairs = run.model->decode(z);
    Eigen::VectorXd h;
    if (run.model->is_hnn()) h = run.model->energy(z).col(0);
    // As pixel_rollouts (Note [Velocity from the rollout's frames]): the first frames of
    // consecutive decoded pairs.
    for (Eigen::Index k = 0; k + 1 < z.rows(); ++k) {
      const Eigen::RowVector2d x = state_from_frames(scene, pairs.row(k).head(kFramePixels),
                                                     pairs.row(k + 1).head(kFramePixels));
      csv += fmt::format("{},{},{},{:.9g},{:.9g},{},{},{},{}\n", run.options.model, i,
                         t[std::size_t(k)], z(k, 0), z(k, 1), cell(x(0)), cell(x(1)),
                         cell(scene.energy(x)), h.size() ? cell(h(k)) : "");
    }
  }
  const fs::path out =
      o.out.empty() ? run_dir / fmt::format("pixel_rollout_{}.csv", o.integrator) : o.out;
  write_file_atomic(out, csv);
  return out;
}

void write_comparison(const fs::path& baseline_run, const fs::path& hnn_run, const fs::path& out,
                      int trajectories, int stride) {
  const LoadedPixelRun base = load_pixel_run(baseline_run);
  const LoadedPixelRun hnn = load_pixel_run(hnn_run);
  HNN_TASKS_CHECK(base.options.seed == hnn.options.seed &&
                      base.config.to_json()["trials"] == hnn.config.to_json()["trials"] &&
                      base.config.frames_per_trial == hnn.config.frames_per_trial,
                  "'{}' and '{}' were trained on different data (seed or trials differ)",
                  baseline_run.string(), hnn_run.string());
  HNN_TASKS_CHECK(!base.model->is_hnn() && hnn.model->is_hnn(),
                  "write_comparison wants a baseline run and then an HNN run");
  PixelConfig config = hnn.config;
  config.rollout_trials = std::max(1, trajectories);
  const PixelRollouts rb = pixel_rollouts(*base.model, base.data, config, trajectories);
  const PixelRollouts rh = pixel_rollouts(*hnn.model, hnn.data, config, trajectories);
  HNN_TASKS_CHECK(!rb.true_frames.empty() && rb.pred_frames.size() == rh.pred_frames.size(),
                  "no rollout frames to compare (a rollout failed)");
  fs::create_directories(out);
  std::vector<std::vector<const Eigen::MatrixXf*>> grid;
  for (std::size_t i = 0; i < rh.pred_frames.size(); ++i)
    grid.push_back({&rh.true_frames[i], &rb.pred_frames[i], &rh.pred_frames[i]});
  write_animation(out / "rollout.gif", grid);
  write_strip(out / "rollout_strip.png",
              {&rh.true_frames[0], &rb.pred_frames[0], &rh.pred_frames[0]}, stride);
}

}  // namespace hnn::tasks::pixel
