#include "tasks/data/trajectories.h"

#include "physics/integrator.h"

namespace hnn::tasks {

namespace {
// Rows integrated together: an adaptive step serves a whole batch, so one hard trajectory
// (a close encounter) must not slow down all the others.
constexpr Eigen::Index kChunk = 50;
}  // namespace

TrajectorySamples sample_trajectories(const physics::System& system, const Batch& x0, double t_end,
                                      int points, double rtol) {
  const std::vector<double> times = physics::linspace(0.0, t_end, points);
  const auto integrator = physics::make_integrator("dopri5", {.rtol = rtol, .atol = rtol * 1e-3});
  TrajectorySamples out;
  out.x.resize(x0.rows() * points, x0.cols());
  for (Eigen::Index start = 0; start < x0.rows(); start += kChunk) {
    const Eigen::Index n = std::min(kChunk, x0.rows() - start);
    const Batch chunk = x0.middleRows(start, n);
    Batch states(n * points, x0.cols());
    bool exact = false;
    for (int k = 0; k < points; ++k) {
      const std::optional<Batch> flow = system.exact_flow(chunk, times[k]);
      if (!flow) break;
      exact = true;
      for (Eigen::Index i = 0; i < n; ++i) states.row(i * points + k) = flow->row(i);
    }
    if (!exact) states = integrator->integrate(system.field(), chunk, times).stacked();
    out.x.middleRows(start * points, n * points) = states;
  }
  system.vector_field(out.x, out.dxdt);
  return out;
}

void add_noise(Batch& x, double std, std::mt19937_64& rng) {
  std::normal_distribution<double> normal(0.0, std);
  for (Eigen::Index i = 0; i < x.size(); ++i) x.data()[i] += normal(rng);
}

std::pair<Batch, Batch> split_rows(const Batch& x, Eigen::Index cut) {
  return {x.topRows(cut), x.bottomRows(x.rows() - cut)};
}

Dataset oscillator_dataset(const physics::System& system, std::uint64_t seed,
                           const OscillatorSettings& settings) {
  std::mt19937_64 rng(seed);
  const Batch x0 = system.sample_initial_states(settings.trajectories, rng);
  TrajectorySamples s = sample_trajectories(system, x0, settings.t_end, settings.points, 1e-10);
  add_noise(s.x, settings.noise, rng);  // targets stay the derivatives at the clean states
  const Eigen::Index cut = Eigen::Index(settings.trajectories / 2) * settings.points;
  Dataset d;
  std::tie(d.train_x, d.test_x) = split_rows(s.x, cut);
  std::tie(d.train_dxdt, d.test_dxdt) = split_rows(s.dxdt, cut);
  return d;
}

std::uint64_t fingerprint(const Dataset& data) {
  std::uint64_t hash = 0xcbf29ce484222325ull;
  for (const Batch* b : {&data.train_x, &data.train_dxdt}) {
    const auto* bytes = reinterpret_cast<const unsigned char*>(b->data());
    for (std::size_t i = 0; i < std::size_t(b->size()) * sizeof(double); ++i) {
      hash = (hash ^ bytes[i]) * 0x100000001b3ull;
    }
  }
  return hash;
}

}  // namespace hnn::tasks
