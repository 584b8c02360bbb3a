// The pixel-pendulum scene of task 5: Gym's Pendulum-v0 dynamics at zero
// torque, its canonical coordinates, and a 28 x 28 anti-aliased renderer.
#pragma once

#include <vector>

#include "physics/oscillators.h"

namespace hnn::physics {

/// Gym's own state: th measured from upright (counter-clockwise positive, not
/// wrapped) and thdot = dth/dt.
struct GymState {
  double th = 0.0;
  double thdot = 0.0;
};

/// The scene. As a System it is the continuous-time pendulum in the canonical
/// coordinates of docs/tasks.md: theta from hanging down, p = 0.25 dtheta/dt, so
/// H = 0.25 (3g/2l) (1 - cos theta) + p^2 / (2 * 0.25) = 3.75 (1 - cos theta) + 2 p^2.
/// (The rod's mechanical energy is 4/3 of this H.)
class GymPendulum : public Pendulum {
 public:
  static constexpr double kGravity = 10.0;
  static constexpr double kLength = 1.0;  // also the rendered rod length
  static constexpr double kDt = 0.05;
  static constexpr double kMaxSpeed = 8.0;
  static constexpr double kMomentumScale = 0.25;  // p = kMomentumScale * dtheta/dt
  static constexpr int kSide = 28;                // frames are kSide x kSide
  static constexpr double kRodWidth = 0.2;
  static constexpr double kIntensity = 0.5;
  static constexpr double kViewHalfWidth = 1.2;  // world units from pivot to frame edge

  GymPendulum();

  std::string name() const override { return "gym_pendulum"; }
  /// Canonical (theta, p) of sample_gym_state().
  Batch sample_initial_states(int n, std::mt19937_64& rng) const override;

  /// One zero-torque Gym step, v0 order: thdot += 3g/(2l) sin(th) dt,
  /// th += thdot dt, then thdot is clipped to [-8, 8].
  GymState step(GymState s) const;
  /// `frames` states: s0 and its frames - 1 successors.
  std::vector<GymState> rollout(GymState s0, int frames) const;
  /// A trial start of docs/tasks.md: |theta| in (0, pi/6), thdot ~ U[-1, 1].
  GymState sample_gym_state(std::mt19937_64& rng) const;

  /// (theta, p): theta = th - pi wrapped to (-pi, pi], p = 0.25 thdot.
  Eigen::RowVector2d to_canonical(GymState s) const;
  GymState from_canonical(double theta, double p) const;

  /// The rod at angle th (from upright) as a row-major kSide^2 row: a capsule of
  /// length 1 and width 0.2 from the pivot at the frame centre, intensity 0.5 on
  /// black, edges anti-aliased by a one-pixel ramp on the distance to its axis.
  Eigen::RowVectorXd render(double th) const;
  /// One frame per angle: rows x kSide^2.
  Batch render_batch(const Eigen::Ref<const Eigen::VectorXd>& th) const;
  /// th (from upright, in (-pi, pi]) of the frame's intensity-weighted centroid
  /// about the pivot. Throws std::invalid_argument on a blank or mis-sized frame.
  double angle_from_frame(const Eigen::Ref<const Eigen::RowVectorXd>& frame) const;
};

/// a wrapped to (-pi, pi].
double wrap_angle(double a);

}  // namespace hnn::physics
