// `hnn simulate`: trajectories of any Hamiltonian given as an expression, or states scattered
// over the sampling box (--scattered N, no time column: the sampled-HNN paper's kind of data),
// with the exact time derivatives at the clean states, as CSV (noise, if any, on the states
// only).

#include "physics/simulate.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <optional>
#include <set>

#include "apps/hnn/commands/commands.h"
#include "apps/hnn/commands/validators.h"
#include "nn/atomic_file.h"
#include "physics/expression_system.h"
#include "physics/integrator.h"

namespace hnn::app {

namespace {

// Rows integrated together: an adaptive step serves a whole batch, so one hard trajectory
// must not slow down all the others (as tasks/data does).
constexpr Eigen::Index kChunk = 50;
constexpr double kMaxRows = 1e8;  // trajectories x points held in memory at once

struct SimulateOptions {
  std::string hamiltonian, sample, energy, out, integrator = "dopri5";
  std::vector<std::string> coords, momenta;
  int trajectories = 0, points = 0, scattered = 0;
  double t_end = 0.0, noise = 0.0, dt = 1e-2, rtol = 1e-10;
  std::uint64_t seed = 0;
};

// "LO:HI" as a range; `what` names the option in the message.
physics::ValueRange parse_range(const std::string& text, const std::string& what) {
  const std::size_t colon = text.find(':');
  physics::ValueRange r;
  if (colon == std::string::npos || !detail::parse_whole(text.substr(0, colon), r.lo) ||
      !detail::parse_whole(text.substr(colon + 1), r.hi)) {
    throw std::invalid_argument(
        fmt::format("{}: '{}' is not LO:HI with two numbers (e.g. -1:1)", what, text));
  }
  return r;
}

// "q=-1:1,p=-0.5:0.5" as (name, range) pairs.
std::vector<std::pair<std::string, physics::ValueRange>> parse_box(const std::string& text) {
  std::vector<std::pair<std::string, physics::ValueRange>> ranges;
  std::set<std::string> seen;
  std::size_t start = 0;
  while (start <= text.size()) {
    const std::size_t end = std::min(text.find(',', start), text.size());
    const std::string item = text.substr(start, end - start);
    const std::size_t eq = item.find('=');
    if (eq == std::string::npos || eq == 0) {
      throw std::invalid_argument(
          fmt::format("--sample: '{}' is not NAME=LO:HI (e.g. q=-1:1,p=-1:1)", item));
    }
    const std::string name = item.substr(0, eq);
    if (!seen.insert(name).second) {
      throw std::invalid_argument(fmt::format("--sample: '{}' has two ranges", name));
    }
    ranges.emplace_back(name, parse_range(item.substr(eq + 1), "--sample " + name));
    start = end + 1;
  }
  return ranges;
}

physics::ExpressionSystem make_system(const SimulateOptions& o) {
  physics::StateSampling sampling;
  if (!o.sample.empty()) sampling.ranges = parse_box(o.sample);
  if (!o.energy.empty()) sampling.energy = parse_range(o.energy, "--energy");
  return physics::ExpressionSystem(o.hamiltonian, o.coords, o.momenta, sampling);
}

// The states of every trajectory at every time, trajectory-major (row i * points + k).
physics::Batch integrate(const physics::ExpressionSystem& system, const physics::Batch& x0,
                         const SimulateOptions& o) {
  const auto integrator =
      physics::make_integrator(o.integrator, {.dt = o.dt, .rtol = o.rtol, .atol = o.rtol * 1e-3});
  const std::vector<double> times = physics::linspace(0.0, o.t_end, o.points);
  physics::Batch states(x0.rows() * o.points, x0.cols());
  for (Eigen::Index start = 0; start < x0.rows(); start += kChunk) {
    const Eigen::Index n = std::min(kChunk, x0.rows() - start);
    states.middleRows(start * o.points, n * o.points) =
        physics::integrate_system(*integrator, system, x0.middleRows(start, n), times).stacked();
  }
  return states;
}

// Trajectories with their id and time first; scattered states (o.scattered) without either.
std::string csv(const physics::ExpressionSystem& system, const physics::Batch& x,
                const physics::Batch& dxdt, const SimulateOptions& o) {
  const std::vector<std::string> names = system.variables();
  const bool timed = o.scattered == 0;
  fmt::memory_buffer out;
  if (timed) fmt::format_to(std::back_inserter(out), "trajectory,t,");
  fmt::format_to(std::back_inserter(out), "{}", fmt::join(names, ","));
  for (const std::string& name : names) fmt::format_to(std::back_inserter(out), ",d{}/dt", name);
  const std::vector<double> times = physics::linspace(0.0, o.t_end, std::max(o.points, 2));
  for (Eigen::Index row = 0; row < x.rows(); ++row) {
    out.push_back('\n');
    if (timed)
      fmt::format_to(std::back_inserter(out), "{},{},", row / o.points, times[row % o.points]);
    for (Eigen::Index j = 0; j < x.cols(); ++j)
      fmt::format_to(std::back_inserter(out), "{}{}", j ? "," : "", x(row, j));
    for (Eigen::Index j = 0; j < x.cols(); ++j) {
      fmt::format_to(std::back_inserter(out), ",{}", dxdt(row, j));
    }
  }
  out.push_back('\n');
  return fmt::to_string(out);
}

// Either trajectories (--trajectories, --t-end and --points) or scattered states.
void check_kind(const SimulateOptions& o) {
  if (o.scattered > 0) return;  // the options of trajectories exclude it (add_simulate_command)
  if (o.trajectories == 0 || o.t_end == 0 || o.points == 0) {
    throw std::invalid_argument(
        "give --trajectories, --t-end and --points for trajectories, or --scattered N for N "
        "states without time (uniform in --sample's box, with exact dx/dt)");
  }
}

void simulate(const SimulateOptions& o) {
  check_kind(o);
  if (double(o.trajectories) * o.points > kMaxRows) {
    throw std::invalid_argument(
        fmt::format("--trajectories {} x --points {} is more than {:g} rows", o.trajectories,
                    o.points, kMaxRows));
  }
  const physics::ExpressionSystem system = make_system(o);
  std::mt19937_64 rng(o.seed);
  physics::Batch x =
      system.sample_initial_states(o.scattered > 0 ? o.scattered : o.trajectories, rng);
  if (o.scattered == 0) x = integrate(system, x, o);
  physics::Batch dxdt;
  system.vector_field(x, dxdt);  // the exact derivatives at the clean states
  if (o.noise > 0.0) {
    std::normal_distribution<double> normal(0.0, o.noise);
    for (Eigen::Index i = 0; i < x.size(); ++i) x.data()[i] += normal(rng);
  }
  nn::write_file_atomic(o.out, csv(system, x, dxdt, o));
  if (o.scattered > 0) {
    fmt::print("hnn simulate: {} scattered states of {} with exact dx/dt, no time column -> {}\n",
               o.scattered, system.name(), o.out);
    return;
  }
  fmt::print("hnn simulate: {} trajectories x {} points of {} ({}{}) -> {}\n", o.trajectories,
             o.points, system.name(), o.integrator,
             system.separable() ? ", separable" : ", not separable", o.out);
}

// A finite number >= 0.
CLI::Validator non_negative_real() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        double value = 0;
        if (detail::parse_whole(text, value) && std::isfinite(value) && value >= 0) return "";
        return "expected a finite number >= 0, got '" + text + "'";
      },
      "NONNEGATIVE");
}

}  // namespace

void add_simulate_command(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "simulate", "Trajectories and exact dx/dt of a Hamiltonian given as an expression (CSV)");
  auto o = std::make_shared<SimulateOptions>();
  cmd->add_option("--hamiltonian", o->hamiltonian,
                  "H as an expression, e.g. \"p^2/2 + 9.81*(1 - cos(q))\"")
      ->option_text("EXPR")
      ->required();
  cmd->add_option("--coords", o->coords, "Coordinate names, in order (repeat or comma-separate)")
      ->option_text("NAME ...")
      ->required()
      ->delimiter(',');
  cmd->add_option("--momenta", o->momenta, "Momentum names, one per coordinate")
      ->option_text("NAME ...")
      ->required()
      ->delimiter(',');
  // Trajectories, or --scattered states: the options of trajectories exclude it.
  std::vector<CLI::Option*> timed = {
      cmd->add_option("--trajectories", o->trajectories, "Trajectories")
          ->check(integer_in(1, 10000000)),
      cmd->add_option("--t-end", o->t_end, "Time span of each trajectory")->check(positive_real()),
      cmd->add_option("--points", o->points, "Evenly spaced times from 0 to --t-end")
          ->check(integer_in(2, 10000000))};
  cmd->add_option("--noise", o->noise, "Gaussian noise std added to the states (not to dx/dt)")
      ->check(non_negative_real())
      ->capture_default_str();
  timed.push_back(
      cmd->add_option("--integrator", o->integrator,
                      fmt::format("One of {} (the splitting methods leapfrog, yoshida4 and "
                                  "symplectic_euler need a separable H)",
                                  fmt::join(physics::integrator_names(), ", ")))
          ->option_text("NAME")
          ->capture_default_str());
  timed.push_back(cmd->add_option("--dt", o->dt, "Step of fixed-step integrators")
                      ->check(positive_real())
                      ->capture_default_str());
  timed.push_back(cmd->add_option("--rtol", o->rtol, "Tolerance of dopri5")
                      ->check(positive_real())
                      ->capture_default_str());
  CLI::Option* scattered =
      cmd->add_option("--scattered", o->scattered,
                      "Instead of trajectories: N states uniform in --sample's box with their "
                      "exact dx/dt, without time or trajectory columns")
          ->option_text("N")
          ->check(integer_in(1, 10000000));
  for (CLI::Option* option : timed) scattered->excludes(option);
  cmd->add_option("--seed", o->seed, "Seed of the initial states and the noise")
      ->check(seed_value())
      ->capture_default_str();
  cmd->add_option("--sample", o->sample,
                  "Initial-state box, e.g. \"q=-1:1,p=-1:1\" (unnamed variables: -1:1)")
      ->option_text("NAME=LO:HI,...");
  cmd->add_option("--energy", o->energy,
                  "Keep only initial states with LO <= H <= HI, given as LO:HI (e.g. 0.5:2)")
      ->option_text("LO:HI");
  cmd->add_option("--out", o->out, "CSV file to write")->option_text("FILE")->required();
  cmd->callback([o] { simulate(*o); });
}

}  // namespace hnn::app
