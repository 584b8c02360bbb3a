// Timer, CSV writer, spring data and quick HNN training shared by the chart programs.
#include "bench/accuracy/common.h"

#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <iostream>
#include <stdexcept>

#include "physics/integrator.h"
#include "physics/oscillators.h"

namespace hnn::accuracy {

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

void summarise(std::vector<double> per_call, Timing& timing) {
  std::sort(per_call.begin(), per_call.end());
  const std::size_t n = per_call.size();
  timing.samples = static_cast<int>(n);
  timing.median = n % 2 == 1 ? per_call[n / 2] : 0.5 * (per_call[n / 2 - 1] + per_call[n / 2]);
  timing.min = per_call.front();
  timing.max = per_call.back();
}

}  // namespace

std::vector<Timing> time_interleaved(const std::vector<std::function<void()>>& fns,
                                     const TimingOptions& options) {
  std::vector<Timing> timings(fns.size());
  std::vector<std::vector<double>> per_call(fns.size());
  int samples = options.samples;
  for (std::size_t i = 0; i < fns.size(); ++i) {
    const Clock::time_point start = Clock::now();
    fns[i]();
    const double first = std::max(seconds_since(start), 1e-9);
    timings[i].calls_per_sample =
        std::max(1, static_cast<int>(std::ceil(options.min_sample_seconds / first)));
    // A call slower than slow_call_seconds is its own warm-up: it counts as the first sample.
    if (first > options.slow_call_seconds) {
      per_call[i].push_back(first);
      samples = std::min(samples, options.slow_samples);
    }
  }
  for (int s = 0; s < samples; ++s) {
    for (std::size_t i = 0; i < fns.size(); ++i) {
      if (static_cast<int>(per_call[i].size()) >= samples) continue;
      const Clock::time_point start = Clock::now();
      for (int c = 0; c < timings[i].calls_per_sample; ++c) fns[i]();
      per_call[i].push_back(seconds_since(start) / timings[i].calls_per_sample);
    }
  }
  for (std::size_t i = 0; i < fns.size(); ++i) summarise(per_call[i], timings[i]);
  return timings;
}

Timing time_call(const std::function<void()>& fn, const TimingOptions& options) {
  return time_interleaved({fn}, options).front();
}

CsvWriter::CsvWriter(const std::string& path, const std::string& header)
    : file_(std::fopen(path.c_str(), "w")) {
  if (file_ == nullptr) throw std::runtime_error(fmt::format("cannot write {}", path));
  fmt::print(file_, "{}\n", header);
}

CsvWriter::~CsvWriter() { std::fclose(file_); }

void CsvWriter::row(const std::string& line) {
  fmt::print(file_, "{}\n", line);
  std::fflush(file_);
}

SpringData spring_data(int trajectories, int points, double noise, std::uint64_t seed) {
  const physics::Spring spring;
  std::mt19937_64 rng(seed);
  const physics::Batch x0 = spring.sample_initial_states(trajectories, rng);
  SpringData data;
  data.x.resize(trajectories * points, 2);
  data.dxdt.resize(trajectories * points, 2);
  const std::vector<double> times = physics::linspace(0.0, 3.0, points);
  for (int k = 0; k < points; ++k) {
    const physics::Batch x = *spring.exact_flow(x0, times[k]);
    physics::Batch dxdt(x.rows(), 2);
    spring.vector_field(x, dxdt);
    for (int i = 0; i < trajectories; ++i) {
      data.x.row(i * points + k) = x.row(i);
      data.dxdt.row(i * points + k) = dxdt.row(i);
    }
  }
  data.x += nn::random_normal<double>(data.x.rows(), 2, rng, 0.0, noise);
  return data;
}

nn::Hnn<double> train_spring_hnn(const SpringData& data, const std::vector<nn::Index>& hidden,
                                 int steps, std::uint64_t seed, double* final_loss) {
  nn::DynamicsConfig config;
  config.hidden = hidden;
  std::mt19937_64 rng(seed);
  nn::Hnn<double> model(config, rng);
  nn::Adam<double> adam(model.parameters(), {.lr = 1e-3});
  const ad::Var<double> x = ad::Var<double>::leaf(data.x, /*requires_grad=*/false);
  const ad::Var<double> target = ad::Var<double>::leaf(data.dxdt, /*requires_grad=*/false);
  double loss = 0;
  for (int step = 0; step < steps; ++step) {
    ad::TapeScope scope;
    const ad::Var<double> l = nn::mse(model.time_derivative(x), target);
    adam.step(ad::grad<double>({l}, adam.parameters()));
    loss = l.item();
  }
  if (final_loss != nullptr) *final_loss = loss;
  return model;
}

int run_charts(int argc, char** argv, const std::string& program,
               const std::vector<Chart>& charts) {
  CLI::App app{program + ": writes its charts' CSV files (docs/speed_accuracy.md)", program};
  std::string out = ".";
  std::string only = "all";
  int threads = 1;
  bool quick = false;
  std::vector<std::string> names{"all"};
  for (const Chart& chart : charts) names.push_back(chart.name);
  app.add_option("--out", out, "Folder of the CSV files")->capture_default_str();
  app.add_option("--threads", threads, "Engine threads")
      ->check(CLI::Range(1, 1024))
      ->capture_default_str();
  app.add_option("--only", only, "One chart")->check(CLI::IsMember(names))->capture_default_str();
  app.add_flag("--quick", quick, "Small sizes, for a smoke run");
  CLI11_PARSE(app, argc, argv);
  try {
    ad::set_num_threads(threads);
    for (const Chart& chart : charts)
      if (only == "all" || only == chart.name) chart.write(out, quick);
  } catch (const std::exception& e) {
    std::cerr << program << ": " << e.what() << "\n";
    return 1;
  }
  return 0;
}

}  // namespace hnn::accuracy
