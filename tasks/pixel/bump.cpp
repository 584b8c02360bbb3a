// The paper's Figure 5: "bumping" the pendulum to a higher energy by integrating the Riemann
// gradient of the learned H between two stretches along its symplectic gradient.

#include "tasks/pixel/bump.h"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "nn/atomic_file.h"
#include "physics/integrator.h"
#include "tasks/error.h"
#include "tasks/pixel/rollouts.h"
#include "tasks/report/image_io.h"

namespace hnn::tasks::pixel {

namespace fs = std::filesystem;

namespace {

constexpr int kRiemannPoints = 11;      // outputs during the Riemann phase
constexpr double kMaxRiemannTime = 50;  // longest search along R_H for the asked rise of H
constexpr int kProbePoints = 5001;      // its resolution: 0.01 time units
constexpr int kScale = 3, kGap = 2, kSide = physics::GymPendulum::kSide;

struct Phase {
  const char* name;
  std::vector<double> t;  // times within the phase, from 0
  physics::Batch z;       // states at those times
};

Phase integrate_phase(const char* name, const physics::VectorField& field, const physics::Batch& z0,
                      double duration, int points) {
  const auto dopri = physics::make_integrator("dopri5", {.rtol = 1e-9, .atol = 1e-12});
  Phase p{name, physics::linspace(0.0, duration, points), {}};
  p.z = dopri->integrate(field, z0, p.t).path(0);
  return p;
}

// Each state advanced one frame along S_H: with it, a latent state's pendulum state is read
// from two decoded frames one time step apart (Note [Velocity from the rollout's frames]).
physics::Batch one_frame_later(const physics::VectorField& symplectic, const physics::Batch& z) {
  const auto dopri = physics::make_integrator("dopri5", {.rtol = 1e-9, .atol = 1e-12});
  return dopri->integrate(symplectic, z, {0.0, 1.0}).states.back();
}

double mean_of(const std::vector<double>& v) {
  double s = 0;
  for (double x : v) s += x;
  return v.empty() ? NAN : s / double(v.size());
}

void check_options(const PixelModel<double>& model, const PixelData& data, const BumpOptions& o) {
  HNN_TASKS_CHECK(model.is_hnn(), "the energy bump needs an HNN run: a baseline learns no H");
  HNN_TASKS_CHECK(o.trajectory >= -1 && o.trajectory < data.test_trials(),
                  "--trajectory must be in [0, {}) (or -1: automatic), got {}", data.test_trials(),
                  o.trajectory);
  HNN_TASKS_CHECK(o.before > 0 && o.after > 0 && o.dt > 0,
                  "bump: --before, --after and --dt must be positive");
  HNN_TASKS_CHECK(
      std::isfinite(o.riemann) && std::isfinite(o.raise) && (o.riemann != 0 || o.raise != 0),
      "bump: give a non-zero --raise or --riemann");
}

physics::VectorField symplectic_field(const nn::DynamicsModel<double>& dynamics) {
  return
      [&dynamics](double, const physics::Batch& z, physics::Batch& dz) { dz = dynamics.field(z); };
}

// S_H = (dH/dp, -dH/dq), so R_H = (dH/dq, dH/dp) = (-S_p, S_q): H grows along it at the rate
// |grad H|^2. Lowering H (sign -1) follows -R_H.
physics::VectorField riemann_field(const nn::DynamicsModel<double>& dynamics, double sign) {
  return [&dynamics, sign](double, const physics::Batch& z, physics::Batch& dz) {
    const physics::Batch s = dynamics.field(z);
    dz.resize(s.rows(), 2);
    dz.col(0) = -sign * s.col(1);
    dz.col(1) = sign * s.col(0);
  };
}

// The test trials' first pairs: their learned H sets the scale of `raise`; the default start is
// the trial at the 25th percentile of their H (room to rise; the 75th to fall).
struct Start {
  int trajectory;
  physics::Batch z0;
  Eigen::VectorXd h_firsts;
};

Start choose_start(const PixelModel<double>& model, const PixelData& data, int trajectory,
                   double sign) {
  std::vector<Eigen::Index> firsts;
  for (int i = 0; i < data.test_trials(); ++i)
    firsts.push_back(Eigen::Index(i) * data.pairs_per_trial());
  Start s{trajectory, {}, model.energy(model.encode(data.pairs_of<double>(firsts, false))).col(0)};
  if (s.trajectory < 0) {
    std::vector<int> order(firsts.size());
    std::iota(order.begin(), order.end(), 0);
    std::sort(order.begin(), order.end(),
              [&](int a, int b) { return s.h_firsts(a) < s.h_firsts(b); });
    s.trajectory = order[sign > 0 ? order.size() / 4 : order.size() * 3 / 4];
  }
  s.z0 = model.encode(data.pairs_of<double>({firsts[std::size_t(s.trajectory)]}, false));
  return s;
}

// The time along R_H at which H has risen (or fallen) from its value at z1 by `raise` times its
// spread over the test trials' first pairs.
double riemann_time_for_raise(const PixelModel<double>& model, const physics::VectorField& riemann,
                              const physics::Batch& z1, const Eigen::VectorXd& h_firsts,
                              double raise, double sign) {
  const double spread = h_firsts.maxCoeff() - h_firsts.minCoeff();
  HNN_TASKS_CHECK(spread > 0,
                  "bump: --raise is a fraction of the spread of H over the test trials, and {} "
                  "test trial(s) have none; give --riemann instead",
                  h_firsts.size());
  const double target = model.energy(z1)(0, 0) + raise * spread;
  const Phase probe = integrate_phase("riemann", riemann, z1, kMaxRiemannTime, kProbePoints);
  const Eigen::VectorXd h = model.energy(probe.z).col(0);
  for (Eigen::Index k = 1; k < h.size(); ++k) {
    if ((h(k) - target) * sign >= 0) {  // crossed: interpolate the time linearly
      const double f = (target - h(k - 1)) / (h(k) - h(k - 1));
      const double t0 = probe.t[std::size_t(k) - 1], t1 = probe.t[std::size_t(k)];
      return t0 + f * (t1 - t0);
    }
  }
  throw Error(
      fmt::format("bump: H did not change by {} x its spread within {} time units along "
                  "R_H",
                  raise, kMaxRiemannTime));
}

// What the phases show: the CSV rows, one image per output, and per phase the learned H, the
// energy recovered from the decoded frames and the swing's amplitude.
struct Record {
  std::string csv = "phase,t,z_q,z_p,learned_h,theta,p,energy\n";
  std::vector<GrayImage> images;
  std::vector<double> h[3], energy[3];
  double amplitude[3] = {0, 0, 0};
};

void record_phase(const PixelModel<double>& model, const physics::VectorField& symplectic,
                  const Phase& p, std::size_t phase, double t0, Record& r) {
  const physics::GymPendulum scene;
  const Eigen::VectorXd h = model.energy(p.z).col(0);
  const physics::Batch pairs = model.decode(p.z);
  const physics::Batch next = model.decode(one_frame_later(symplectic, p.z));
  for (Eigen::Index k = (phase == 0 ? 0 : 1); k < p.z.rows(); ++k) {  // phases share endpoints
    const Eigen::RowVector2d x =
        state_from_frames(scene, pairs.row(k).head(kFramePixels), next.row(k).head(kFramePixels));
    const double e = scene.energy(x);
    r.csv += fmt::format("{},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g}\n", p.name,
                         t0 + p.t[std::size_t(k)], p.z(k, 0), p.z(k, 1), h(k), x(0), x(1), e);
    r.h[phase].push_back(h(k));
    r.energy[phase].push_back(e);
    r.amplitude[phase] = std::max(r.amplitude[phase], std::abs(x(0)));
    GrayImage image(kSide * kScale + 2 * kGap, kSide * kScale + 2 * kGap,
                    phase == 1 ? 128 : 64);  // a lighter border while R_H is integrated
    draw_frame(image, kGap, kGap, pairs.row(k).tail(kFramePixels).cast<float>(), kSide, kScale,
               physics::GymPendulum::kIntensity);
    r.images.push_back(std::move(image));
  }
}

// bump.csv, bump.gif and bump_strip.png (every 4th image, in one row).
std::vector<fs::path> write_bump_files(const Record& r, const fs::path& out) {
  fs::create_directories(out);
  nn::write_file_atomic(out / "bump.csv", r.csv);
  write_gif(out / "bump.gif", r.images, 5);
  const int stride = 4, tile = kSide * kScale + 2 * kGap;
  const int cols = int((r.images.size() - 1) / stride) + 1;
  GrayImage strip(cols * tile, tile, 64);
  for (int c = 0; c < cols; ++c) {
    const GrayImage& img = r.images[std::size_t(c * stride)];
    for (int y = 0; y < img.height; ++y)
      for (int x = 0; x < img.width; ++x) strip.at(c * tile + x, y) = img.at(x, y);
  }
  write_png(out / "bump_strip.png", strip);
  return {out / "bump.csv", out / "bump.gif", out / "bump_strip.png"};
}

}  // namespace

BumpResult energy_bump(const PixelModel<double>& model, const PixelData& data, const PixelConfig&,
                       const BumpOptions& o) {
  check_options(model, data, o);
  const double sign = (o.riemann != 0 ? o.riemann : o.raise) >= 0 ? 1.0 : -1.0;
  const physics::VectorField symplectic = symplectic_field(model.dynamics());
  const physics::VectorField riemann = riemann_field(model.dynamics(), sign);
  const Start start = choose_start(model, data, o.trajectory, sign);
  const auto points = [&](double duration) {
    return std::max(2, int(std::lround(duration / o.dt)) + 1);
  };
  std::vector<Phase> phases;
  phases.push_back(integrate_phase("symplectic", symplectic, start.z0, o.before, points(o.before)));
  const physics::Batch z1 = phases[0].z.bottomRows(1);
  const double duration =
      o.riemann != 0 ? std::abs(o.riemann)
                     : riemann_time_for_raise(model, riemann, z1, start.h_firsts, o.raise, sign);
  phases.push_back(
      integrate_phase("riemann", riemann, z1, std::max(duration, 1e-9), kRiemannPoints));
  phases.push_back(integrate_phase("symplectic-after", symplectic, phases[1].z.bottomRows(1),
                                   o.after, points(o.after)));
  Record r;
  double t0 = 0;
  for (std::size_t ph = 0; ph < phases.size(); ++ph) {
    record_phase(model, symplectic, phases[ph], ph, t0, r);
    t0 += phases[ph].t.back();
  }
  BumpResult result{.trajectory = start.trajectory,
                    .riemann_time = duration,
                    .h_before = mean_of(r.h[0]),
                    .h_after = mean_of(r.h[2]),
                    .energy_before = mean_of(r.energy[0]),
                    .energy_after = mean_of(r.energy[2]),
                    .amplitude_before = r.amplitude[0],
                    .amplitude_after = r.amplitude[2]};
  if (!o.out.empty()) result.files = write_bump_files(r, o.out);
  return result;
}

}  // namespace hnn::tasks::pixel
