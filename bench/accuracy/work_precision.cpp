// Chart 2 of docs/speed_accuracy.md, the integrators' work against their precision. Writes to
// --out DIR:
//   work_precision.csv  system,method,knob,value,error,seconds,...: 16 states to t = 10 on the
//                       spring, the pendulum and the two-body problem, each method over a
//                       step-size (or rtol) sweep; error = max |x(10) - x_ref(10)| over states
//   energy_drift.csv    system,method,quantity,t,periods,error: max relative energy error in
//                       log-spaced time bins over long horizons, true systems and a trained HNN
// Run: work_precision --out DIR [--threads N (default 1)] [--only work|energy] [--quick]
#include <fmt/format.h>

#include <cmath>
#include <iostream>
#include <memory>
#include <numbers>

#include "bench/accuracy/common.h"
#include "physics/dopri5.h"
#include "physics/nbody.h"
#include "physics/oscillators.h"
#include "physics/simulate.h"

namespace hnn::accuracy {
namespace {

using physics::Batch;

constexpr double kEnd = 10.0;

struct Problem {
  std::string name;
  std::shared_ptr<physics::System> system;
  Batch x0, reference;  // reference: the states at kEnd
};

// No closed form (pendulum, two-body): DOPRI5 at rtol 1e-13, below every error charted but the
// tightest DOPRI5 runs themselves.
Batch tight_reference(const physics::System& system, const Batch& x0) {
  physics::IntegratorOptions tight;
  tight.rtol = 1e-13;
  tight.atol = 1e-16;
  return physics::Dopri5(tight).integrate(system.field(), x0, {0.0, kEnd}).states.back();
}

std::vector<Problem> problems() {
  std::vector<Problem> out;
  const auto add = [&](std::string name, std::shared_ptr<physics::System> system, unsigned seed) {
    std::mt19937_64 rng(seed);
    Batch x0 = system->sample_initial_states(16, rng);
    const std::optional<Batch> exact = system->exact_flow(x0, kEnd);
    Batch reference = exact ? *exact : tight_reference(*system, x0);
    out.push_back({std::move(name), std::move(system), std::move(x0), std::move(reference)});
  };
  add("spring", std::make_shared<physics::Spring>(), 21);
  add("pendulum", std::make_shared<physics::Pendulum>(), 22);
  add("two_body", std::make_shared<physics::NBody>(physics::NBody::equal_masses(2)), 23);
  return out;
}

void work_precision_chart(const std::string& out, bool quick) {
  CsvWriter csv(out + "/work_precision.csv",
                "system,method,knob,value,error,seconds,seconds_min,seconds_max,nfev,steps,"
                "rejected,samples");
  for (const Problem& problem : problems()) {
    for (const std::string method :
         {"euler", "rk4", "leapfrog", "yoshida4", "midpoint", "dopri5"}) {
      const bool adaptive = method == "dopri5";
      // dt = 10^(-k/3) from 0.1 to 1e-4; rtol = 10^-k from 1e-3 to 1e-12.
      for (int k = 3; k <= 12; k += quick ? 3 : 1) {
        physics::IntegratorOptions options;
        const double value = adaptive ? std::pow(10.0, -k) : std::pow(10.0, -k / 3.0);
        options.dt = value;
        options.rtol = value;
        options.atol = value * 1e-3;
        const auto integrator = physics::make_integrator(method, options);
        physics::Trajectory traj;
        Timing t;
        try {
          TimingOptions timing;
          timing.samples = quick ? 1 : 5;
          t = time_call(
              [&] {
                traj = physics::integrate_system(*integrator, *problem.system, problem.x0,
                                                 {0.0, kEnd});
              },
              timing);
        } catch (const physics::IntegrationError& e) {
          fmt::print("{} {} {}: {}\n", problem.name, method, value, e.what());
          continue;
        }
        const double error = (traj.states.back() - problem.reference).cwiseAbs().maxCoeff();
        csv.row(fmt::format("{},{},{},{:.6e},{:.6e},{:.6e},{:.6e},{:.6e},{},{},{},{}", problem.name,
                            method, adaptive ? "rtol" : "dt", value, error, t.median, t.min, t.max,
                            traj.stats.nfev, traj.stats.steps, traj.stats.rejected, t.samples));
        fmt::print("{:9} {:9} {}={:.1e}  error {:.2e}  {:.2e} s  nfev {}\n", problem.name, method,
                   adaptive ? "rtol" : "dt", value, error, t.median, traj.stats.nfev);
      }
    }
  }
}

// Complete elliptic integral of the first kind K(k), by the arithmetic-geometric mean.
double elliptic_k(double k) {
  double a = 1.0, b = std::sqrt(1.0 - k * k);
  for (int i = 0; i < 40 && std::abs(a - b) > 1e-16 * a; ++i) {
    const double next = 0.5 * (a + b);
    b = std::sqrt(a * b);
    a = next;
  }
  return std::numbers::pi / (2.0 * a);
}

// A long run: the state and energy are sampled at every step (or, for DOPRI5, on the same grid by
// dense output), in chunks, and the worst relative energy error is kept per log-spaced time bin
// (20 per decade of periods).
struct DriftRun {
  std::string system, method, quantity;
  double period = 0;              // time unit of the horizon
  std::vector<double> bin_error;  // per bin; -1 where no sample fell
};

using EnergyFn = std::function<Eigen::VectorXd(const Batch&)>;

constexpr int kBinsPerDecade = 20;
constexpr double kFirstBinPeriods = 0.1;

// Bin b holds (0.1 * 10^(b/20), 0.1 * 10^((b+1)/20)] periods; bin 0 also holds all earlier times.
int bin_of(double periods) {
  const double position = kBinsPerDecade * std::log10(periods / kFirstBinPeriods);
  return std::max(0, static_cast<int>(std::ceil(position - 1e-9)) - 1);
}

// Integrates x0 for `periods` periods with `steps_per_period` fixed steps (the output grid),
// recording each energy in `energies` (name -> function) relative to its start. Stops early
// (keeping what it has) when the integration fails or an error exceeds 10.
using Integrate =
    std::function<physics::Trajectory(const Batch& x0, const std::vector<double>& t_eval)>;

std::vector<DriftRun> drift_runs(const std::string& system, const std::string& method,
                                 const Integrate& integrate, const Batch& x0, double period,
                                 double periods, int steps_per_period,
                                 const std::vector<std::pair<std::string, EnergyFn>>& energies,
                                 double* seconds) {
  std::vector<DriftRun> runs;
  std::vector<double> e0;
  for (const auto& [quantity, energy] : energies) {
    runs.push_back(
        {system, method, quantity, period, std::vector<double>(bin_of(periods) + 1, -1)});
    e0.push_back(energy(x0)(0));
  }
  const double dt = period / steps_per_period;
  const long total_steps = std::lround(periods * steps_per_period);
  const long chunk = 100L * steps_per_period;
  Batch x = x0;
  const auto start = std::chrono::steady_clock::now();
  try {
    for (long done = 0; done < total_steps; done += chunk) {
      const long n = std::min(chunk, total_steps - done);
      std::vector<double> times(n + 1);
      for (long k = 0; k <= n; ++k) times[k] = (done + k) * dt;
      const physics::Trajectory traj = integrate(x, times);
      const Batch states = traj.stacked();
      bool blown = false;
      for (std::size_t q = 0; q < energies.size(); ++q) {
        const Eigen::VectorXd e = energies[q].second(states);
        bool over = false;  // the last sample kept is the first above 10
        for (long k = 1; k <= n && !over; ++k) {
          const double error = std::abs(e(k) - e0[q]) / std::abs(e0[q]);
          double& slot = runs[q].bin_error[bin_of(times[k] / period)];
          slot = std::max(slot, error);
          over = !(error < 10.0);
        }
        blown = blown || over;
      }
      x = traj.states.back();
      if (blown) break;
    }
  } catch (const physics::IntegrationError& e) {
    fmt::print("{} {}: stopped: {}\n", system, method, e.what());
  }
  *seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return runs;
}

void write_runs(CsvWriter& csv, const std::vector<DriftRun>& runs, double seconds) {
  for (const DriftRun& run : runs) {
    double worst = 0;
    for (std::size_t b = 0; b < run.bin_error.size(); ++b) {
      if (run.bin_error[b] < 0) continue;
      const double periods = kFirstBinPeriods * std::pow(10.0, (b + 1.0) / kBinsPerDecade);
      csv.row(fmt::format("{},{},{},{:.6e},{:.6e},{:.6e},{:.3f}", run.system, run.method,
                          run.quantity, periods * run.period, periods, run.bin_error[b], seconds));
      worst = std::max(worst, run.bin_error[b]);
    }
    fmt::print("{:9} {:9} {:9} worst relative energy error {:.2e} ({:.1f} s)\n", run.system,
               run.method, run.quantity, worst, seconds);
  }
}

// The fixed-step driver takes the fewest steps <= dt per output interval. Far from t = 0 the
// rounding of the output times makes some intervals exceed the spacing by more than the driver's
// 1e-12 relative slack, and it would take two half steps there (which breaks a symplectic
// method's bounded energy error). A dt a hair above the spacing keeps one step per interval.
double grid_step(double spacing) { return spacing * (1.0 + 1e-9); }

physics::IntegratorOptions drift_options() {
  physics::IntegratorOptions o;
  o.rtol = 1e-8;  // DOPRI5
  o.atol = 1e-11;
  return o;
}

void energy_chart(const std::string& out, bool quick) {
  CsvWriter csv(out + "/energy_drift.csv", "system,method,quantity,t,periods,error,seconds");
  // The true systems, one state each, 32 steps per period (64 for the two-body problem).
  struct Case {
    std::shared_ptr<physics::System> system;
    Batch x0;
    double period, periods;
    int steps_per_period;
  };
  std::vector<Case> cases;
  cases.push_back({std::make_shared<physics::Spring>(), Batch{{1.0, 0.0}}, std::numbers::pi,
                   quick ? 100.0 : 1e4, 32});
  // H = 3 (1 - cos q) + p^2 from rest at q = 1.5: q'' = -6 sin q, period 4 K(sin 0.75) / sqrt 6.
  cases.push_back({std::make_shared<physics::Pendulum>(), Batch{{1.5, 0.0}},
                   4.0 * elliptic_k(std::sin(0.75)) / std::sqrt(6.0), quick ? 100.0 : 1e4, 32});
  {
    auto two = std::make_shared<physics::NBody>(physics::NBody::equal_masses(2));
    std::mt19937_64 rng(24);
    const Batch x0 = two->sample_initial_states(1, rng);
    // Kepler: E = -G m1 m2 / 2a, period 2 pi sqrt(a^3 / G (m1 + m2)).
    const double a = 1.0 / (2.0 * std::abs(two->hamiltonian(x0.row(0))));
    cases.push_back(
        {two, x0, 2 * std::numbers::pi * std::sqrt(a * a * a / 2.0), quick ? 30.0 : 1e3, 64});
  }
  for (const Case& c : cases) {
    const auto energy = c.system;
    for (const std::string method :
         {"euler", "rk4", "dopri5", "leapfrog", "yoshida4", "midpoint"}) {
      physics::IntegratorOptions o = drift_options();
      o.dt = grid_step(c.period / c.steps_per_period);
      const auto integrator = physics::make_integrator(method, o);
      double seconds = 0;
      // integrate_system gives splitting methods the system's exact separable halves.
      const Integrate run = [&](const Batch& x, const std::vector<double>& t) {
        return physics::integrate_system(*integrator, *c.system, x, t);
      };
      const std::vector<DriftRun> runs = drift_runs(
          c.system->name(), method, run, c.x0, c.period, c.periods, c.steps_per_period,
          {{"true_H", [energy](const Batch& s) { return energy->energy_batch(s); }}}, &seconds);
      write_runs(csv, runs, seconds);
    }
  }
  // A trained HNN (2-64-64-1 on noisy spring data): its learned field is not separable, so only
  // the general methods apply. Both its own H and the true spring energy along its path.
  double loss = 0;
  const int steps = quick ? 200 : 3000;
  const auto model = std::make_shared<nn::Hnn<double>>(
      train_spring_hnn(spring_data(25, 30, 0.1, /*seed=*/0), {64, 64}, steps, /*seed=*/3, &loss));
  fmt::print("learned: 2-64-64-1 HNN, {} Adam steps, final training loss {:.3e}\n", steps, loss);
  const physics::VectorField learned = [model](double, const Batch& x, Batch& dxdt) {
    dxdt = model->field(x);
  };
  const physics::Spring spring;
  const std::vector<std::pair<std::string, EnergyFn>> energies = {
      {"learned_H", [model](const Batch& s) { return Eigen::VectorXd(model->energy(s).col(0)); }},
      {"true_H", [&spring](const Batch& s) { return spring.energy_batch(s); }}};
  for (const std::string method : {"rk4", "dopri5", "midpoint"}) {
    physics::IntegratorOptions o = drift_options();
    o.dt = grid_step(std::numbers::pi / 32);
    const auto integrator = physics::make_integrator(method, o);
    double seconds = 0;
    const Integrate run = [&](const Batch& x, const std::vector<double>& t) {
      return integrator->integrate(learned, x, t);
    };
    const std::vector<DriftRun> runs =
        drift_runs("hnn_spring", method, run, Batch{{0.8, 0.0}}, std::numbers::pi,
                   quick ? 20.0 : 1e3, 32, energies, &seconds);
    write_runs(csv, runs, seconds);
  }
}

}  // namespace
}  // namespace hnn::accuracy

int main(int argc, char** argv) {
  using namespace hnn::accuracy;
  return run_charts(argc, argv, "work_precision",
                    {{"work", work_precision_chart}, {"energy", energy_chart}});
}
