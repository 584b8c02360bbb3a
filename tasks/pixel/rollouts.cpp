// The pixel pendulum's evaluation rollouts: latent paths by the adaptive integrator, decoded to
// frames and compared with the true Gym continuation.

#include "tasks/pixel/rollouts.h"

#include <cmath>
#include <numbers>

#include "physics/integrator.h"
#include "tasks/error.h"
#include "tasks/evaluate/energy_errors.h"
#include "tasks/evaluate/rollouts.h"

namespace hnn::tasks::pixel {

PixelRollouts pixel_rollouts(const PixelModel<double>& model, const PixelData& data,
                             const PixelConfig& config, int keep) {
  const physics::GymPendulum scene;
  const int n = config.rollout_trials > 0 ? std::min(config.rollout_trials, data.test_trials())
                                          : data.test_trials();
  const int frames = config.rollout_frames;
  const Eigen::Index m = frames + 1;
  PixelRollouts r;
  r.t = physics::linspace(0.0, double(frames), frames + 1);
  // One frame more than reported: the state at time k needs the angle of frame k + 1.
  const std::vector<double> t_ext = physics::linspace(0.0, double(frames + 1), frames + 2);
  for (Eigen::MatrixXd* mat :
       {&r.frame_mse, &r.true_theta, &r.true_p, &r.true_energy, &r.pred_theta, &r.pred_p,
        &r.pred_energy, &r.pair_energy, &r.frames_energy}) {
    mat->setConstant(n, m, NAN);
  }
  if (model.is_hnn()) r.learned_h.setConstant(n, m, NAN);
  const auto dopri = physics::make_integrator("dopri5", {.rtol = config.rtol, .atol = config.atol});
  const nn::DynamicsModel<double>& dynamics = model.dynamics();
  const physics::VectorField field = [&dynamics](double, const physics::Batch& z,
                                                 physics::Batch& dzdt) {
    dzdt = dynamics.field(z);
  };

  for (int i = 0; i < n; ++i) {
    // The first pair of test trial i: frames 1 and 2 of the trial. At rollout time k the true
    // pair is trial frames k + 1 and k + 2, and its state is halfway between them.
    const Eigen::Index row = Eigen::Index(i) * data.pairs_per_trial();
    const Eigen::Index f0 = data.first_frame(row);
    const std::vector<physics::GymState> states =
        scene.rollout(data.states[std::size_t(f0)], frames + 2);
    physics::Batch truth(m, kPairPixels);
    for (Eigen::Index k = 0; k < m; ++k) {
      truth.row(k).head(kFramePixels) = scene.render(states[std::size_t(k)].th);
      truth.row(k).tail(kFramePixels) = scene.render(states[std::size_t(k) + 1].th);
      const Eigen::RowVector2d x =
          pair_state(states[std::size_t(k)].th, states[std::size_t(k) + 1].th);
      r.true_theta(i, k) = x(0);
      r.true_p(i, k) = x(1);
      r.frames_energy(i, k) = scene.energy(state_from_pair(scene, truth.row(k)));
    }
    r.true_energy.row(i) = scene.energy_batch(physics::Batch(
        (Eigen::MatrixX2d(m, 2) << r.true_theta.row(i).transpose(), r.true_p.row(i).transpose())
            .finished()));
    const physics::Batch z0 = model.encode(data.pairs_of<double>({row}, false));
    Eigen::MatrixXd z;
    try {
      const physics::Trajectory path = dopri->integrate(field, z0, t_ext);
      r.nfev += path.stats.nfev;
      z = path.path(0);
      r.failed.push_back(false);
    } catch (const physics::IntegrationError& e) {
      r.failed.push_back(true);
      r.failures.push_back(fmt::format("trajectory {}: {}", i, e.what()));
      r.z.push_back(Eigen::MatrixXd::Constant(m, 2, NAN));
      if (i < keep) {  // blank frames keep the figures' rows aligned
        r.true_frames.push_back(truth.rightCols(kFramePixels).cast<float>());
        r.pred_frames.push_back(Eigen::MatrixXf::Zero(m, kFramePixels));
      }
      continue;
    }
    r.z.push_back(z.topRows(m));
    const physics::Batch pred = model.decode(physics::Batch(z));  // m + 1 pairs
    r.frame_mse.row(i) = (pred.topRows(m) - truth).array().square().rowwise().mean().transpose();
    // Note [Velocity from the rollout's frames]: the state at time k is pair_state of the angles
    // of the first frames of decoded pairs k and k + 1, as the true state is that of frames k
    // and k + 1. The angle difference inside one decoded pair is not used for it: the decoder
    // renders that difference about 20% too small even for encoded true pairs (measured, seed
    // 0: p recovered = 0.78 p at t = 0 for both models), a bias of the autoencoder that would
    // swamp the dynamics' energy error. It stays in pair_energy for comparison.
    physics::Batch recovered(m, 2), within_pair(m, 2);
    for (Eigen::Index k = 0; k < m; ++k) {
      recovered.row(k).head<2>() = state_from_frames(scene, pred.row(k).head(kFramePixels),
                                                     pred.row(k + 1).head(kFramePixels));
      within_pair.row(k).head<2>() = state_from_pair(scene, pred.row(k));
    }
    r.pred_theta.row(i) = recovered.col(0).transpose();
    r.pred_p.row(i) = recovered.col(1).transpose();
    r.pred_energy.row(i) = scene.energy_batch(recovered).transpose();
    r.pair_energy.row(i) = scene.energy_batch(within_pair).transpose();
    if (model.is_hnn())
      r.learned_h.row(i) = model.energy(physics::Batch(z.topRows(m))).col(0).transpose();
    if (i < keep) {
      r.true_frames.push_back(truth.rightCols(kFramePixels).cast<float>());
      r.pred_frames.push_back(pred.topRows(m).rightCols(kFramePixels).cast<float>());
    }
  }
  return r;
}

namespace {

// The rollouts' energies as tasks::energy_mse reads them, from `source`.
Rollouts energy_view(const PixelRollouts& r, EnergySource source) {
  Rollouts view;
  view.t = r.t;
  view.failed = r.failed;
  view.true_energy = r.true_energy;
  view.pred_energy = source == EnergySource::kTrueFrames   ? r.frames_energy
                     : source == EnergySource::kWithinPair ? r.pair_energy
                                                           : r.pred_energy;
  // A frame whose angle cannot be recovered (blank) makes its trajectory fail the metric.
  for (Eigen::Index i = 0; i < view.pred_energy.rows(); ++i) {
    if (!view.pred_energy.row(i).allFinite()) view.failed[std::size_t(i)] = true;
  }
  return view;
}

}  // namespace

nn::MeanStderr pixel_energy_mse(const PixelRollouts& r, EnergySource source) {
  return energy_mse(energy_view(r, source));
}

nn::MeanStderr pixel_relative_energy_mse(const PixelRollouts& r) {
  return relative_energy_mse(energy_view(r, EnergySource::kRollout));
}

}  // namespace hnn::tasks::pixel
