#pragma once
// The pixel pendulum's evaluation (metrics.json's values and the run's pixel files) and the
// latent rollouts of `hnn rollout`.

#include <nlohmann/json.hpp>
#include <string>
#include <string_view>

#include "tasks/pixel/model.h"
#include "tasks/report/run_folder.h"

namespace hnn::tasks::pixel {

/// Losses by term over both splits, energy MSE of decoded latent rollouts (and its floor from the
/// true frames), frame MSE and amplitude ratios. With a folder, also pixel_rollout.csv,
/// latent_paths.csv, latent_grid.csv, rollout.gif and rollout_strip.png.
nlohmann::json evaluate_pixel_model(const PixelModel<double>& model, const PixelData& data,
                                    const PixelConfig& config, const RunFolder* folder);

/// `hnn rollout` of a pixel run: latent paths with any integrator, decoded states as CSV
/// (source,traj,t,z_q,z_p,theta,p,energy,learned_h), time unit one frame.
struct PixelRolloutOptions {
  std::string integrator = "dopri5";
  double dt = 0.25, rtol = 1e-9;
  int frames = 200, trajectories = 5;
};
std::string pixel_rollout_csv(const PixelModel<double>& model, const PixelData& data,
                              std::string_view model_name, const PixelRolloutOptions& options);

}  // namespace hnn::tasks::pixel
