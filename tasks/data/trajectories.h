#pragma once
// Sampling true trajectories for datasets: states at evenly spaced times from many initial
// states, with the exact derivatives at the clean states.

#include <random>

#include "physics/system.h"
#include "tasks/data/dataset.h"

namespace hnn::tasks {

/// Row blocks per trajectory: trajectory i occupies rows [i * points, (i + 1) * points).
struct TrajectorySamples {
  Batch x, dxdt;
};

/// Integrates every row of x0 over [0, t_end] (closed form when the system has one, else the
/// adaptive integrator at rtol) and samples `points` evenly spaced times including both ends.
TrajectorySamples sample_trajectories(const physics::System& system, const Batch& x0, double t_end,
                                      int points, double rtol);

/// Adds Gaussian noise of standard deviation `std` to every entry.
void add_noise(Batch& x, double std, std::mt19937_64& rng);

/// Rows [0, cut) and [cut, rows).
std::pair<Batch, Batch> split_rows(const Batch& x, Eigen::Index cut);

struct OscillatorSettings {
  int trajectories, points;
  double t_end;
  double noise = 0.1;
};

/// Tasks 1-2: trajectories from the system's sampler, noisy inputs, exact targets at the clean
/// states; the first half of the trajectories train, the rest test.
Dataset oscillator_dataset(const physics::System& system, std::uint64_t seed,
                           const OscillatorSettings& settings);

}  // namespace hnn::tasks
