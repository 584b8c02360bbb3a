// The pixel pendulum's evaluation: losses by term, latent rollouts decoded and compared with the
// true Gym continuation, their files and figures; and the rollouts of `hnn rollout`.

#include "tasks/pixel/evaluation.h"

#include <fmt/format.h>

#include <cmath>

#include "physics/integrator.h"
#include "tasks/pixel/figures.h"
#include "tasks/pixel/rollouts.h"
#include "tasks/report/csv_cell.h"
#include "tasks/report/json_values.h"
#include "tasks/report/rollout_csv.h"

namespace hnn::tasks::pixel {

using nlohmann::json;

namespace {

json stats_json(const nn::MeanStderr& s) {
  return {{"mean", number(s.mean)}, {"se", number(s.std_error)}};
}

std::string rollout_csv(const PixelRollouts& r) {
  std::string csv =
      "traj,frame,frame_mse,true_theta,true_p,true_energy,pred_theta,pred_p,pred_energy,"
      "frames_energy,z_q,z_p,learned_h,pair_energy\n";
  for (Eigen::Index i = 0; i < r.true_energy.rows(); ++i) {
    for (Eigen::Index k = 0; k < Eigen::Index(r.t.size()); ++k) {
      csv += fmt::format("{},{},{},{},{},{},{},{},{},{},{},{},{},{}\n", i, r.t[std::size_t(k)],
                         csv_cell(r.frame_mse(i, k), 9), csv_cell(r.true_theta(i, k), 9),
                         csv_cell(r.true_p(i, k), 9), csv_cell(r.true_energy(i, k), 9),
                         csv_cell(r.pred_theta(i, k), 9), csv_cell(r.pred_p(i, k), 9),
                         csv_cell(r.pred_energy(i, k), 9), csv_cell(r.frames_energy(i, k), 9),
                         csv_cell(r.z[std::size_t(i)](k, 0), 9),
                         csv_cell(r.z[std::size_t(i)](k, 1), 9),
                         r.learned_h.size() ? csv_cell(r.learned_h(i, k), 9) : "",
                         csv_cell(r.pair_energy(i, k), 9));
    }
  }
  return csv;
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

}  // namespace

namespace {

// The decoded pairs' MSE at each time, over the rollouts that did not fail.
Eigen::VectorXd mean_frame_mse(const PixelRollouts& r) {
  Eigen::VectorXd mse = Eigen::VectorXd::Zero(Eigen::Index(r.t.size()));
  int used = 0;
  for (Eigen::Index i = 0; i < r.frame_mse.rows(); ++i) {
    if (r.failed[std::size_t(i)]) continue;
    mse += r.frame_mse.row(i).transpose();
    ++used;
  }
  return mse / std::max(used, 1);
}

json loss_metrics(const PixelLossStats& train, const PixelLossStats& test) {
  const auto terms = [](const PixelLossStats& s) {
    return json{{"ae", stats_json(s.ae)}, {"cc", stats_json(s.cc)}, {"hnn", stats_json(s.hnn)}};
  };
  return {{"train_loss", number(train.total.mean)},
          {"train_loss_se", number(train.total.std_error)},
          {"test_loss", number(test.total.mean)},
          {"test_loss_se", number(test.total.std_error)},
          {"loss_terms", {{"train", terms(train)}, {"test", terms(test)}}}};
}

json rollout_metrics(const PixelRollouts& r, const PixelConfig& config) {
  const nn::MeanStderr energy = pixel_energy_mse(r);
  const nn::MeanStderr within_pair = pixel_energy_mse(r, EnergySource::kWithinPair);
  const nn::MeanStderr relative = pixel_relative_energy_mse(r);
  const Eigen::VectorXd frame_mse = mean_frame_mse(r);
  return {{"energy_mse", number(energy.mean)},
          {"energy_mse_se", number(energy.std_error)},
          {"energy_relative_mse", number(relative.mean)},
          {"energy_relative_mse_se", number(relative.std_error)},
          {"n_rollouts", energy.count},
          {"rollout_failures", r.failures},
          {"energy_mse_frames_floor", number(pixel_energy_mse(r, EnergySource::kTrueFrames).mean)},
          {"energy_mse_within_pair", number(within_pair.mean)},
          {"energy_mse_within_pair_se", number(within_pair.std_error)},
          {"frame_mse_mean", number(frame_mse.mean())},
          {"frame_mse_first", number(frame_mse(0))},
          {"frame_mse_last", number(frame_mse(frame_mse.size() - 1))},
          {"amplitude_ratio", number(amplitude_ratio(r.pred_theta))},
          {"amplitude_ratio_true", number(amplitude_ratio(r.true_theta))},
          {"rollout_frames", config.rollout_frames},
          {"rollout_nfev", r.nfev}};
}

// pixel_rollout.csv, the latent files, and the first rollouts as GIF and strip.
void write_pixel_files(const PixelModel<double>& model, const PixelData& data,
                       const PixelRollouts& r, const RunFolder& folder) {
  folder.write_text("pixel_rollout.csv", rollout_csv(r));
  write_latent_files(model, data, folder);
  if (r.true_frames.empty()) return;
  std::vector<std::vector<const Eigen::MatrixXf*>> grid;
  for (std::size_t i = 0; i < r.true_frames.size(); ++i)
    grid.push_back({&r.true_frames[i], &r.pred_frames[i]});
  write_animation(folder.file("rollout.gif"), grid);
  write_strip(folder.file("rollout_strip.png"), {&r.true_frames[0], &r.pred_frames[0]}, 10);
}

}  // namespace

json evaluate_pixel_model(const PixelModel<double>& model, const PixelData& data,
                          const PixelConfig& config, const RunFolder* folder) {
  json m = loss_metrics(pixel_loss_stats(model, data, false, config.hnn_weight),
                        pixel_loss_stats(model, data, true, config.hnn_weight));
  const PixelRollouts r = pixel_rollouts(model, data, config, 2);
  m.update(rollout_metrics(r, config));
  m["n_train"] = data.train_rows();
  m["n_test"] = data.test_rows;
  if (folder) write_pixel_files(model, data, r, *folder);
  return m;
}

std::string pixel_rollout_csv(const PixelModel<double>& model, const PixelData& data,
                              std::string_view model_name, const PixelRolloutOptions& o) {
  const physics::GymPendulum scene;
  const int n = std::min(o.trajectories, data.test_trials());
  std::vector<Eigen::Index> rows;
  for (int i = 0; i < n; ++i) rows.push_back(Eigen::Index(i) * data.pairs_per_trial());
  const physics::Batch z0 = model.encode(data.pairs_of<double>(rows, false));
  const auto integrator =
      physics::make_integrator(o.integrator, {.dt = o.dt, .rtol = o.rtol, .atol = o.rtol * 1e-3});
  // One frame past the last reported: its angle gives the last state's velocity.
  const std::vector<double> t = physics::linspace(0.0, o.frames + 1, o.frames + 2);
  const Eigen::VectorXd frames = as_vector(t);
  const nn::DynamicsModel<double>& dynamics = model.dynamics();
  const physics::Trajectory path = integrator->integrate(
      [&dynamics](double, const physics::Batch& z, physics::Batch& dz) { dz = dynamics.field(z); },
      z0, t);
  RolloutCsv csv({"z_q", "z_p", "theta", "p"}, {.values = 9, .times = 9});
  for (int i = 0; i < n; ++i) {
    const std::vector<physics::GymState> states = scene.rollout(
        data.states[std::size_t(data.first_frame(rows[std::size_t(i)]))], o.frames + 2);
    // The true rows: the angle and momentum, no latent state.
    Eigen::MatrixXd truth = Eigen::MatrixXd::Constant(o.frames + 1, 4, NAN);
    Eigen::VectorXd energy(o.frames + 1);
    for (int k = 0; k <= o.frames; ++k) {
      const Eigen::RowVector2d x =
          pair_state(states[std::size_t(k)].th, states[std::size_t(k) + 1].th);
      truth.row(k).tail(2) = x;
      energy(k) = scene.energy(x);
    }
    csv.add(kTrueSource, std::size_t(i), frames.head(o.frames + 1), truth, energy);
    const physics::Batch z = path.path(i);
    const physics::Batch pairs = model.decode(z);
    Eigen::VectorXd h;
    if (model.is_hnn()) h = model.energy(z).col(0);
    // As pixel_rollouts (Note [Velocity from the rollout's frames]): the first frames of
    // consecutive decoded pairs.
    Eigen::MatrixXd pred(z.rows() - 1, 4);
    Eigen::VectorXd pred_energy(z.rows() - 1);
    for (Eigen::Index k = 0; k + 1 < z.rows(); ++k) {
      const Eigen::RowVector2d x = state_from_frames(scene, pairs.row(k).head(kFramePixels),
                                                     pairs.row(k + 1).head(kFramePixels));
      pred.row(k) << z(k, 0), z(k, 1), x(0), x(1);
      pred_energy(k) = scene.energy(x);
    }
    csv.add(model_name, std::size_t(i), frames.head(z.rows() - 1), pred, pred_energy,
            h.size() ? Eigen::VectorXd(h.head(z.rows() - 1)) : Eigen::VectorXd());
  }
  return csv.str();
}

}  // namespace hnn::tasks::pixel
