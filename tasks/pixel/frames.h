#pragma once
// The pixel pendulum's data: rendered frames of Gym trials, pairs of consecutive frames as the
// model's input, and the pendulum's canonical state recovered from a pair of frames.
#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "autodiff/var.h"
#include "physics/gym_pendulum.h"
#include "physics/types.h"
#include "tasks/pixel/config.h"

namespace hnn::tasks::pixel {

/// The frames of every trial (stored once, as float: pairs are assembled when needed) and the
/// Gym state behind each frame. Pair r of trial j is (frame f, frame f + 1) with
/// f = j * frames_per_trial + (r mod pairs) + 1, and its successor starts one frame later: the
/// reference's offsets, 100 usable pairs per trial of 103 frames. Pairs are numbered trial-major
/// and the first test_rows() of them are the test split.
struct PixelData {
  using Frames = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  int trials = 0, frames_per_trial = 0;
  Frames frames;                          // trials * frames_per_trial x 784
  std::vector<physics::GymState> states;  // one per frame
  Eigen::Index test_rows = 0;

  int pairs_per_trial() const { return frames_per_trial - 3; }
  Eigen::Index pairs() const { return Eigen::Index(trials) * pairs_per_trial(); }
  Eigen::Index train_rows() const { return pairs() - test_rows; }
  /// Frame index of the first frame of pair `row`.
  Eigen::Index first_frame(Eigen::Index row) const;
  /// The pairs (next = false) or their successors (next = true) of the given rows: n x 1568.
  template <typename T>
  ad::Matrix<T> pairs_of(const std::vector<Eigen::Index>& rows, bool next) const;
  /// Canonical (theta, p) of each given pair: pair_state of its two frames' true angles.
  physics::Batch coords_of(const std::vector<Eigen::Index>& rows) const;
  /// Whole test trials: the trials all of whose pairs are in the test split (at least one).
  int test_trials() const;
};

/// Deterministic: the same seed gives the same frames, bit for bit.
PixelData build_pixel_data(const PixelConfig& config, std::uint64_t seed);

/// The canonical state (theta, p) of a pair of frames whose Gym angles (from upright) are th_a
/// then th_b: taken halfway between them, theta = th_a + d/2 - pi and p = 0.25 d / dt with
/// d = wrap(th_b - th_a). Gym's semi-implicit Euler step is a leapfrog whose velocities live at
/// half steps, so this state's energy stays within about 0.5% along a true trajectory, where
/// the energy of either frame's own (th, thdot) swings by about 10% each period.
Eigen::RowVector2d pair_state(double th_a, double th_b);
/// pair_state of the angles recovered from a decoded or rendered pair (1568 values), each by
/// GymPendulum::angle_from_frame (the intensity centroid); NaNs for a blank frame.
Eigen::RowVector2d state_from_pair(const physics::GymPendulum& scene,
                                   const Eigen::Ref<const Eigen::RowVectorXd>& pair);
/// pair_state of the angles recovered from two frames (784 values each) one time step apart.
Eigen::RowVector2d state_from_frames(const physics::GymPendulum& scene,
                                     const Eigen::Ref<const Eigen::RowVectorXd>& first,
                                     const Eigen::Ref<const Eigen::RowVectorXd>& second);

}  // namespace hnn::tasks::pixel
