#pragma once
// The pixel pendulum's evaluation rollouts: latent paths decoded to frames, against the true Gym
// continuation, and the energy of the states recovered from the frames.
#include <Eigen/Core>
#include <string>
#include <vector>

#include "nn/loss.h"
#include "tasks/pixel/model.h"

namespace hnn::tasks::pixel {

/// Latent rollouts from the first pair of each rollout trial (all trials integrated together
/// by dopri5, time unit = one frame), decoded, against the true Gym continuation.
struct PixelRollouts {
  std::vector<double> t;                            // 0, 1, ..., rollout_frames
  std::vector<Eigen::MatrixXd> z;                   // per trajectory: times x 2 latent states
  Eigen::MatrixXd frame_mse;                        // trajectories x times: MSE of the decoded pair
  Eigen::MatrixXd true_theta, true_p, true_energy;  // pair_state of the true angles
  /// pair_state of the angles of the first frames of decoded pairs k and k + 1: the rollout's
  /// own frames over time (Note [Velocity from the rollout's frames], tasks/pixel/rollouts.cpp).
  Eigen::MatrixXd pred_theta, pred_p, pred_energy;
  Eigen::MatrixXd pair_energy;    // from the two frames of one decoded pair (decoder-biased)
  Eigen::MatrixXd frames_energy;  // recovered from the true frames: the method's floor
  Eigen::MatrixXd learned_h;      // the HNN's H along its latent path (empty otherwise)
  std::vector<bool> failed;
  std::vector<std::string> failures;
  long nfev = 0;
  /// Second frames (times x 784) of the first `keep` trajectories, for GIFs and strips.
  std::vector<Eigen::MatrixXf> true_frames, pred_frames;
};
PixelRollouts pixel_rollouts(const PixelModel<double>& model, const PixelData& data,
                             const PixelConfig& config, int keep = 4);

/// Which recovered energy pixel_energy_mse compares with the true one.
enum class EnergySource {
  kRollout,     // pred_energy: the headline metric
  kWithinPair,  // pair_energy
  kTrueFrames,  // frames_energy: the floor of recovering states from frames
};
/// Energy MSE over trajectories and times with the 5-split standard error of tasks::energy_mse.
nn::MeanStderr pixel_energy_mse(const PixelRollouts& rollouts,
                                EnergySource source = EnergySource::kRollout);
/// tasks::relative_energy_mse of the rollout's recovered energy (the headline metric's).
nn::MeanStderr pixel_relative_energy_mse(const PixelRollouts& rollouts);

}  // namespace hnn::tasks::pixel
