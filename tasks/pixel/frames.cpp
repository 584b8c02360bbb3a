// The pixel pendulum's frames: rendered Gym trials, the pairs of the model's input, and the
// pendulum's state recovered from frames.

#include "tasks/pixel/frames.h"

#include <cmath>
#include <numbers>
#include <random>

#include "tasks/error.h"

namespace hnn::tasks::pixel {

namespace {

// The frame's angle by physics' intensity centroid, which ignores negative (decoded) values.
// Tried: zeroing a faint background (< 0.05) first more than doubled the error on true frames
// (energy floor 3.0e-4 instead of 1.3e-4) and changed decoded rollouts' energies by < 1%.
double frame_angle(const physics::GymPendulum& scene, const Eigen::RowVectorXd& frame) {
  try {
    return scene.angle_from_frame(frame);
  } catch (const std::invalid_argument&) {
    return NAN;  // a blank frame: no angle
  }
}

}  // namespace

Eigen::Index PixelData::first_frame(Eigen::Index row) const {
  const Eigen::Index per = pairs_per_trial();
  return (row / per) * frames_per_trial + row % per + 1;
}

template <typename T>
ad::Matrix<T> PixelData::pairs_of(const std::vector<Eigen::Index>& rows, bool next) const {
  ad::Matrix<T> x(Eigen::Index(rows.size()), kPairPixels);
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const Eigen::Index f = first_frame(rows[i]) + (next ? 1 : 0);
    x.row(Eigen::Index(i)).head(kFramePixels) = frames.row(f).template cast<T>();
    x.row(Eigen::Index(i)).tail(kFramePixels) = frames.row(f + 1).template cast<T>();
  }
  return x;
}

physics::Batch PixelData::coords_of(const std::vector<Eigen::Index>& rows) const {
  physics::Batch x(Eigen::Index(rows.size()), 2);
  for (std::size_t i = 0; i < rows.size(); ++i) {
    x.row(Eigen::Index(i)).head<2>() = pair_state(states[std::size_t(first_frame(rows[i]))].th,
                                                  states[std::size_t(first_frame(rows[i]) + 1)].th);
  }
  return x;
}

int PixelData::test_trials() const { return std::max(1, int(test_rows / pairs_per_trial())); }

PixelData build_pixel_data(const PixelConfig& config, std::uint64_t seed) {
  validate(config);
  const physics::GymPendulum scene;
  std::mt19937_64 rng(seed);
  PixelData d;
  d.trials = config.trials;
  d.frames_per_trial = config.frames_per_trial;
  d.frames.resize(Eigen::Index(config.trials) * config.frames_per_trial, kFramePixels);
  d.states.reserve(std::size_t(d.frames.rows()));
  for (int trial = 0; trial < config.trials; ++trial) {
    for (const physics::GymState& s :
         scene.rollout(scene.sample_gym_state(rng), config.frames_per_trial)) {
      d.frames.row(Eigen::Index(d.states.size())) = scene.render(s.th).cast<float>();
      d.states.push_back(s);
    }
  }
  d.test_rows = Eigen::Index(double(d.pairs()) * config.test_fraction);  // floor, as int() does
  HNN_TASKS_CHECK(d.test_rows >= 1 && d.train_rows() >= 1,
                  "pixel-pendulum: {} pairs cannot be split with test fraction {}", d.pairs(),
                  config.test_fraction);
  return d;
}

Eigen::RowVector2d pair_state(double th_a, double th_b) {
  const double d = physics::wrap_angle(th_b - th_a);
  return {physics::wrap_angle(th_a + d / 2 - std::numbers::pi),
          physics::GymPendulum::kMomentumScale * d / physics::GymPendulum::kDt};
}

Eigen::RowVector2d state_from_pair(const physics::GymPendulum& scene,
                                   const Eigen::Ref<const Eigen::RowVectorXd>& pair) {
  return state_from_frames(scene, pair.head(kFramePixels), pair.tail(kFramePixels));
}

Eigen::RowVector2d state_from_frames(const physics::GymPendulum& scene,
                                     const Eigen::Ref<const Eigen::RowVectorXd>& first,
                                     const Eigen::Ref<const Eigen::RowVectorXd>& second) {
  return pair_state(frame_angle(scene, first), frame_angle(scene, second));
}

template ad::Matrix<float> PixelData::pairs_of(const std::vector<Eigen::Index>&, bool) const;
template ad::Matrix<double> PixelData::pairs_of(const std::vector<Eigen::Index>&, bool) const;

}  // namespace hnn::tasks::pixel
