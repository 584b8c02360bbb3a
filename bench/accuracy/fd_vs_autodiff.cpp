// Chart 1 of docs/speed_accuracy.md, autodiff against finite differences. Writes to --out DIR:
//   fd_error.csv        case,method,h,error: relative error of one-sided and central differences
//                       at each step h, and of reverse mode (float and double), against a
//                       long-double reference (analytic, or hand-derived for the MLP)
//   fd_time_dim.csv     dim,method,... seconds for dH/dx of a dim-200-200-1 HNN on 32 states
//   fd_time_params.csv  width,params,method,... seconds for the HNN loss's parameter gradient
// Run: fd_vs_autodiff --out DIR [--threads N (default 1)] [--only error|dim|params] [--quick]
#include <fmt/format.h>

#include <cmath>
#include <iostream>

#include "bench/accuracy/common.h"
#include "bench/accuracy/gradient_cases.h"

namespace hnn::accuracy {
namespace {

// h = 10^(-k / 4) from 1e-1 to 1e-12: 45 steps, 4 per decade.
std::vector<double> step_sizes(bool quick) {
  std::vector<double> h;
  for (int k = 4; k <= 48; k += quick ? 4 : 1) h.push_back(std::pow(10.0, -k / 4.0));
  return h;
}

void error_chart(const std::string& out, bool quick) {
  CsvWriter csv(out + "/fd_error.csv", "case,method,h,error");
  const std::vector<double> hs = step_sizes(quick);
  for (const GradientCase& c : gradient_cases(quick)) {
    fmt::print("{}: {} points x {} coordinates; autodiff error {:.2e} (double) {:.2e} (float)\n",
               c.name, c.points, c.coordinates, c.ad_double_error, c.ad_float_error);
    for (double h : hs) {
      csv.row(fmt::format("{},autodiff_double,{:.6e},{:.6e}", c.name, h, c.ad_double_error));
      csv.row(fmt::format("{},autodiff_float,{:.6e},{:.6e}", c.name, h, c.ad_float_error));
      const FdErrors fd = c.fd_errors(h);
      csv.row(fmt::format("{},forward,{:.6e},{:.6e}", c.name, h, fd.forward));
      csv.row(fmt::format("{},central,{:.6e},{:.6e}", c.name, h, fd.central));
    }
  }
}

// Methods timed together, in alternation (time_interleaved), and written as CSV rows.
struct TimedMethods {
  std::vector<std::string> names;
  std::vector<double> evaluations;
  std::vector<std::function<void()>> calls;
  void add(std::string name, double evals, std::function<void()> call) {
    names.push_back(std::move(name));
    evaluations.push_back(evals);
    calls.push_back(std::move(call));
  }
  // One row per method: prefix (the sweep's columns), method, evaluations, timing.
  void run(CsvWriter& csv, const std::string& prefix, bool quick) const {
    TimingOptions options;
    if (quick) options.samples = options.slow_samples = 1;
    const std::vector<Timing> timings = time_interleaved(calls, options);
    for (std::size_t i = 0; i < calls.size(); ++i) {
      const Timing& t = timings[i];
      csv.row(fmt::format("{},{},{},{:.6e},{:.6e},{:.6e},{},{}", prefix, names[i], evaluations[i],
                          t.median, t.min, t.max, t.samples, ad::num_threads()));
      fmt::print("{:12} {:10} {:10.3e} s ({:.3g} x evaluation)\n", prefix, names[i], t.median,
                 t.median / timings[0].median);
    }
  }
};

// dH/dx of a dim-200-200-1 HNN (random init) on 32 states: one evaluation of H, reverse mode,
// and one-sided / central differences over all dim inputs.
void dimension_chart(const std::string& out, bool quick) {
  CsvWriter csv(out + "/fd_time_dim.csv",
                "dim,method,evaluations,seconds,seconds_min,seconds_max,samples,threads");
  const Eigen::Index rows = 32;
  for (const nn::Index dim : {2, 8, 12, 1568}) {
    nn::DynamicsConfig config;
    config.dim = dim;
    std::mt19937_64 rng(100 + dim);
    const nn::Hnn<double> model(config, rng);
    const nn::Matrix<double> x = nn::random_normal<double>(rows, dim, rng);
    double sink = 0;
    const auto energy = [&](const nn::Matrix<double>& at) { return model.energy(at); };
    TimedMethods methods;
    methods.add("evaluation", 1, [&] { sink += energy(x)(0, 0); });
    methods.add("autodiff", 1, [&] {
      ad::TapeScope scope;
      const ad::Var<double> leaf = ad::Var<double>::leaf(x);
      sink += ad::grad<double>({ad::sum(model.energy(leaf))}, {leaf})[0].value()(0, 0);
    });
    methods.add("forward", static_cast<double>(dim + 1),
                [&] { sink += finite_difference_gradient(energy, x, 1e-7, false)(0, 0); });
    methods.add("central", static_cast<double>(2 * dim),
                [&] { sink += finite_difference_gradient(energy, x, 1e-5, true)(0, 0); });
    methods.run(csv, fmt::format("{}", dim), quick);
    if (sink == 42.0) std::cout << "";  // keeps the timed work observable
  }
}

// Gradient of the HNN loss (spring data, 750 states) with respect to all parameters of a
// 2-w-w-1 HNN: one loss evaluation, reverse mode, and finite differences over every parameter
// (skipped where one pass would exceed `fd_budget` seconds).
void parameter_chart(const std::string& out, bool quick) {
  CsvWriter csv(out + "/fd_time_params.csv",
                "width,params,method,evaluations,seconds,seconds_min,seconds_max,samples,threads");
  const SpringData data = spring_data(25, 30, 0.1, /*seed=*/0);
  const double fd_budget = quick ? 0.5 : 4.0;
  for (const nn::Index width : {4, 8, 16, 32, 64, 128, 200}) {
    nn::DynamicsConfig config;
    config.hidden = {width, width};
    std::mt19937_64 rng(200 + width);
    nn::Hnn<double> model(config, rng);
    const nn::Index params = model.parameter_count();
    double sink = 0;
    TimedMethods methods;
    methods.add("evaluation", 1, [&] { sink += hnn_loss(model, data); });
    methods.add("autodiff", 1, [&] { sink += hnn_loss_autodiff(model, data)[0](0, 0); });
    TimingOptions probe;
    probe.samples = 3;
    const double eval = time_call(methods.calls[0], probe).median;
    for (const bool central : {false, true}) {
      const double evaluations = central ? 2.0 * params : params + 1.0;
      if (evaluations * eval > fd_budget) {
        fmt::print("width {:4}: {} differences skipped (about {:.0f} s per gradient)\n", width,
                   central ? "central" : "forward", evaluations * eval);
        continue;
      }
      methods.add(central ? "central" : "forward", evaluations, [&, central] {
        sink += loss_fd_gradient(model, data, central ? 1e-5 : 1e-7, central)[0](0, 0);
      });
    }
    methods.run(csv, fmt::format("{},{}", width, params), quick);
    if (sink == 42.0) std::cout << "";
  }
}

}  // namespace
}  // namespace hnn::accuracy

int main(int argc, char** argv) {
  using namespace hnn::accuracy;
  return run_charts(
      argc, argv, "fd_vs_autodiff",
      {{"error", error_chart}, {"dim", dimension_chart}, {"params", parameter_chart}});
}
