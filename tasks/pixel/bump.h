#pragma once
// Figure 5: the energy bump of a pixel-pendulum HNN along the Riemann gradient of its learned H.
#include <filesystem>
#include <vector>

#include "tasks/pixel/model.h"

namespace hnn::tasks::pixel {

/// Figure 5: from an encoded test pair, integrate the symplectic gradient S_H for `before`
/// frames, then the Riemann gradient R_H = (dH/dq, dH/dp) (or -R_H to lower H), then S_H for
/// `after` frames. The learned H grows along R_H at the rate |grad H|^2, which varies a lot over
/// the latent plane, so the bump is given as a rise in H: `raise` times the spread of H over the
/// test trials' first pairs (keeping the bumped swing among the energies the model was trained
/// on), unless a fixed `riemann` time is given.
struct BumpOptions {
  int trajectory =
      -1;  // test trial that starts it; -1: at the 25th percentile of H (75th to lower)
  double before = 60, after = 100;
  double raise = 0.5;         // rise of H as a fraction of its spread (negative: lower H)
  double riemann = 0;         // when non-zero: time along R_H (negative: along -R_H), not `raise`
  double dt = 1;              // output spacing (frames): the GIF runs in real time
  std::filesystem::path out;  // folder; default the run folder
};
struct BumpResult {
  int trajectory = 0;
  double riemann_time = 0;                           // time spent along R_H
  double h_before = 0, h_after = 0;                  // learned H in each S_H phase (mean)
  double energy_before = 0, energy_after = 0;        // true energy recovered from decoded frames
  double amplitude_before = 0, amplitude_after = 0;  // max |theta| of the decoded frames
  std::vector<std::filesystem::path> files{};
};
/// Writes bump.csv (phase,t,z_q,z_p,learned_h,theta,p,energy), bump.gif and bump_strip.png.
/// theta, p and energy: state_from_frames of the decoded state and of the state one frame later
/// along S_H.
BumpResult energy_bump(const PixelModel<double>& model, const PixelData& data,
                       const PixelConfig& config, const BumpOptions& options);

}  // namespace hnn::tasks::pixel
