// The sampled fit on the peer's protocols (Rahma, Datar & Dietrich 2024; docs/sampled.md):
// states uniform in a box with exact derivatives, an HNN of one tanh layer (or more), the
// relative L2 error of H on held-out points. One fit per run, printed as one JSON line:
//   sampled_fit_bench --system hh --width 5000 --train 20000 --test 20000 --solver lsqr
// Systems: hh (Henon-Heiles, alpha 1, [-5, 5]^4), pendulum ([-2pi, 2pi] x [-1, 1]),
// double-pendulum (m = l = g = 1, canonical; q in [-pi, pi]^2, p in [-1, 1]^2).

#include <fmt/format.h>
#include <sys/resource.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "autodiff/parallel.h"
#include "nn/hnn.h"
#include "nn/sampled/sampled_fit.h"

namespace nn = hnn::nn;
using Index = Eigen::Index;
using Mat = hnn::nn::Matrix<double>;

namespace {

struct System {
  Index dim;
  std::vector<double> low, high;
  // H and its gradient (dH/dq, dH/dp) at one state.
  double (*energy)(const double* x, double* grad);
};

double henon_heiles(const double* x, double* g) {
  const double q1 = x[0], q2 = x[1], p1 = x[2], p2 = x[3];
  g[0] = q1 + 2 * q1 * q2;
  g[1] = q2 + q1 * q1 - q2 * q2;
  g[2] = p1;
  g[3] = p2;
  return (p1 * p1 + p2 * p2) / 2 + (q1 * q1 + q2 * q2) / 2 + q1 * q1 * q2 - q2 * q2 * q2 / 3;
}

double pendulum(const double* x, double* g) {
  g[0] = std::sin(x[0]);
  g[1] = x[1];
  return x[1] * x[1] / 2 + 1 - std::cos(x[0]);
}

// H = (p1^2 + 2 p2^2 - 2 p1 p2 cos d) / (2 (1 + sin^2 d)) - 2 cos q1 - cos q2, d = q1 - q2.
double double_pendulum(const double* x, double* g) {
  const double q1 = x[0], q2 = x[1], p1 = x[2], p2 = x[3];
  const double c = std::cos(q1 - q2), s = std::sin(q1 - q2), den = 1 + s * s;
  const double num = p1 * p1 + 2 * p2 * p2 - 2 * p1 * p2 * c;
  const double dkin = p1 * p2 * s / den - num * s * c / (den * den);
  g[0] = dkin + 2 * std::sin(q1);
  g[1] = -dkin + std::sin(q2);
  g[2] = (p1 - p2 * c) / den;
  g[3] = (2 * p2 - p1 * c) / den;
  return num / (2 * den) - 2 * std::cos(q1) - std::cos(q2);
}

System system_named(const std::string& name) {
  constexpr double pi = std::numbers::pi;
  if (name == "hh") return {4, {-5, -5, -5, -5}, {5, 5, 5, 5}, henon_heiles};
  if (name == "pendulum") return {2, {-2 * pi, -1}, {2 * pi, 1}, pendulum};
  if (name == "double-pendulum") return {4, {-pi, -pi, -1, -1}, {pi, pi, 1, 1}, double_pendulum};
  throw std::invalid_argument("--system: hh, pendulum or double-pendulum, got '" + name + "'");
}

struct Data {
  Mat x, dxdt;
  Eigen::VectorXd h;
};

Data draw(const System& sys, Index n, std::mt19937_64& rng) {
  Data d{Mat(n, sys.dim), Mat(n, sys.dim), Eigen::VectorXd(n)};
  std::vector<double> g(std::size_t(sys.dim));
  const Index dof = sys.dim / 2;
  for (Index r = 0; r < n; ++r) {
    for (Index i = 0; i < sys.dim; ++i) {
      std::uniform_real_distribution<double> u(sys.low[std::size_t(i)], sys.high[std::size_t(i)]);
      d.x(r, i) = u(rng);
    }
    d.h(r) = sys.energy(&d.x(r, 0), g.data());
    for (Index k = 0; k < dof; ++k) {
      d.dxdt(r, k) = g[std::size_t(dof + k)];
      d.dxdt(r, dof + k) = -g[std::size_t(k)];
    }
  }
  return d;
}

std::string arg(int argc, char** argv, const std::string& name, const std::string& fallback) {
  for (int i = 1; i + 1 < argc; ++i) {
    if (argv[i] == "--" + name) return argv[i + 1];
  }
  return fallback;
}

double peak_rss_gb() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return double(usage.ru_maxrss) / (1024.0 * 1024.0);
}

}  // namespace

int main(int argc, char** argv) try {
  const System sys = system_named(arg(argc, argv, "system", "hh"));
  const Index width = std::stol(arg(argc, argv, "width", "5000"));
  const Index train = std::stol(arg(argc, argv, "train", "20000"));
  const Index test = std::stol(arg(argc, argv, "test", "20000"));
  const Index layers = std::stol(arg(argc, argv, "layers", "1"));
  nn::SampledFitConfig fit;
  fit.seed = std::stoull(arg(argc, argv, "seed", "0"));
  fit.sampler =
      nn::parse_name(nn::kHiddenSamplerNames, arg(argc, argv, "sampler", "uswim"), "sampler");
  fit.solver =
      nn::parse_name(nn::kLeastSquaresSolverNames, arg(argc, argv, "solver", "qr"), "solver");
  fit.regularization =
      std::stod(arg(argc, argv, "regularization", fmt::format("{}", fit.regularization)));
  if (const std::string r = arg(argc, argv, "rcond", "auto"); r != "auto") fit.rcond = std::stod(r);
  if (const std::string s = arg(argc, argv, "swim-scale", "auto"); s != "auto") {
    fit.swim_scale = std::stod(s);
  }
  fit.tolerance = std::stod(arg(argc, argv, "tolerance", fmt::format("{}", fit.tolerance)));
  fit.max_iterations =
      std::stoi(arg(argc, argv, "max-iterations", fmt::format("{}", fit.max_iterations)));
  fit.aswim_first_fraction =
      std::stod(arg(argc, argv, "first-fraction", fmt::format("{}", fit.aswim_first_fraction)));
  hnn::ad::set_num_threads(std::stoi(arg(argc, argv, "threads", "2")));

  std::mt19937_64 rng(fit.seed);
  const Data tr = draw(sys, train, rng), te = draw(sys, test, rng);
  nn::DynamicsConfig config;
  config.dim = sys.dim;
  config.hidden.assign(std::size_t(layers), width);
  std::mt19937_64 init(1);
  nn::Hnn<double> model(config, init);
  const auto start = std::chrono::steady_clock::now();
  const nn::SampledFitReport r = nn::fit_sampled(model, tr.x, tr.dxdt, fit);
  const double wall =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  const Eigen::VectorXd h = model.energy(te.x).col(0);
  const Eigen::VectorXd diff = h - te.h;
  const double shifted = (diff.array() - diff.mean()).matrix().norm() / te.h.norm();
  // The peer pins H at x0 = 0 to its true value there.
  const Mat zero = Mat::Zero(1, sys.dim);
  std::vector<double> g(std::size_t(sys.dim));
  const double h0 = model.energy(zero)(0, 0) - sys.energy(zero.data(), g.data());
  const double pinned = (diff.array() - h0).matrix().norm() / te.h.norm();
  const double syrk_flops = double(train) * double(width) * double(width);
  fmt::print(
      "{{\"system\": \"{}\", \"sampler\": \"{}\", \"solver\": \"{}\", \"width\": {}, \"layers\": "
      "{}, "
      "\"train\": {}, \"error_H_shifted\": {:.3e}, \"error_H_pinned\": {:.3e}, "
      "\"fit_seconds\": {:.2f}, \"sample_seconds\": {:.2f}, \"assemble_seconds\": {:.2f}, "
      "\"gram_seconds\": {:.2f}, \"solve_seconds\": {:.2f}, \"iterations\": {}, \"rows\": {}, "
      "\"columns\": {}, \"matrix_gb\": {:.2f}, \"peak_rss_gb\": {:.2f}, \"gram_gflops\": {:.1f}, "
      "\"residual_rms\": {:.3e}, \"rcond\": {:g}, \"validation_seconds\": {:.2f}, "
      "\"swim_scale\": {:.4g}, \"wall_seconds\": {:.2f}}}\n",
      arg(argc, argv, "system", "hh"), nn::name_of(nn::kHiddenSamplerNames, fit.sampler), r.solver,
      width, layers, train, shifted, pinned,
      r.sample_seconds + r.assemble_seconds + r.solve_seconds, r.sample_seconds, r.assemble_seconds,
      r.gram_seconds, r.solve_seconds, r.iterations, r.rows, r.columns,
      double(r.matrix_bytes) / 1e9, peak_rss_gb(), syrk_flops / r.gram_seconds * 1e-9,
      r.residual_rms, r.rcond, r.validation_seconds, r.swim_scale, wall);
  return 0;
} catch (const std::exception& e) {
  fmt::print(stderr, "sampled_fit_bench: {}\n", e.what());
  return 1;
}
