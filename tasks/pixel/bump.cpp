// The paper's Figure 5: "bumping" the pendulum to a higher energy by integrating the Riemann
// gradient of the learned H between two stretches along its symplectic gradient.

#include "tasks/pixel/bump.h"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "physics/integrator.h"
#include "tasks/error.h"
#include "tasks/pixel/rollouts.h"
#include "tasks/report/atomic_file.h"
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

}  // namespace

BumpResult energy_bump(const PixelModel<double>& model, const PixelData& data,
                       const PixelConfig& config, const BumpOptions& o) {
  (void)config;
  HNN_TASKS_CHECK(model.is_hnn(), "the energy bump needs an HNN run: a baseline learns no H");
  HNN_TASKS_CHECK(o.trajectory >= -1 && o.trajectory < data.test_trials(),
                  "--trajectory must be in [0, {}) (or -1: automatic), got {}", data.test_trials(),
                  o.trajectory);
  HNN_TASKS_CHECK(o.before > 0 && o.after > 0 && o.dt > 0,
                  "bump: --before, --after and --dt must be positive");
  HNN_TASKS_CHECK(
      std::isfinite(o.riemann) && std::isfinite(o.raise) && (o.riemann != 0 || o.raise != 0),
      "bump: give a non-zero --raise or --riemann");
  const physics::GymPendulum scene;
  const nn::DynamicsModel<double>& dynamics = model.dynamics();
  const physics::VectorField symplectic =
      [&dynamics](double, const physics::Batch& z, physics::Batch& dz) { dz = dynamics.field(z); };
  // S_H = (dH/dp, -dH/dq), so R_H = (dH/dq, dH/dp) = (-S_p, S_q): H grows along it at the rate
  // |grad H|^2. Lowering H follows -R_H.
  const double target_sign = o.riemann != 0 ? o.riemann : o.raise;
  const double sign = target_sign >= 0 ? 1.0 : -1.0;
  const physics::VectorField riemann = [&dynamics, sign](double, const physics::Batch& z,
                                                         physics::Batch& dz) {
    const physics::Batch s = dynamics.field(z);
    dz.resize(s.rows(), 2);
    dz.col(0) = -sign * s.col(1);
    dz.col(1) = sign * s.col(0);
  };
  // The test trials' first pairs: their learned H sets the scale of `raise`; the default start
  // is the trial at the 25th percentile of their H (room to rise; the 75th to fall).
  std::vector<Eigen::Index> firsts;
  for (int i = 0; i < data.test_trials(); ++i)
    firsts.push_back(Eigen::Index(i) * data.pairs_per_trial());
  const Eigen::VectorXd h_firsts =
      model.energy(model.encode(data.pairs_of<double>(firsts, false))).col(0);
  int trajectory = o.trajectory;
  if (trajectory < 0) {
    std::vector<int> order(firsts.size());
    std::iota(order.begin(), order.end(), 0);
    std::sort(order.begin(), order.end(), [&](int a, int b) { return h_firsts(a) < h_firsts(b); });
    trajectory = order[sign > 0 ? order.size() / 4 : order.size() * 3 / 4];
  }
  const physics::Batch z0 =
      model.encode(data.pairs_of<double>({firsts[std::size_t(trajectory)]}, false));
  const auto points = [&](double duration) {
    return std::max(2, int(std::lround(duration / o.dt)) + 1);
  };
  std::vector<Phase> phases;
  phases.push_back(integrate_phase("symplectic", symplectic, z0, o.before, points(o.before)));
  const physics::Batch z1 = phases[0].z.bottomRows(1);
  double duration = std::abs(o.riemann);
  if (o.riemann == 0) {  // find the time at which H has risen (or fallen) by raise x spread
    const double h1 = model.energy(z1)(0, 0);
    const double spread = h_firsts.maxCoeff() - h_firsts.minCoeff();
    HNN_TASKS_CHECK(spread > 0,
                    "bump: --raise is a fraction of the spread of H over the test trials, and {} "
                    "test trial(s) have none; give --riemann instead",
                    h_firsts.size());
    const double target = h1 + o.raise * spread;
    const Phase probe = integrate_phase("riemann", riemann, z1, kMaxRiemannTime, kProbePoints);
    const Eigen::VectorXd h = model.energy(probe.z).col(0);
    duration = kMaxRiemannTime;
    for (Eigen::Index k = 1; k < h.size(); ++k) {
      if ((h(k) - target) * sign >= 0) {  // crossed: interpolate the time linearly
        const double f = (target - h(k - 1)) / (h(k) - h(k - 1));
        duration = probe.t[std::size_t(k) - 1] +
                   f * (probe.t[std::size_t(k)] - probe.t[std::size_t(k) - 1]);
        break;
      }
    }
    HNN_TASKS_CHECK(duration < kMaxRiemannTime,
                    "bump: H did not change by {} x its spread within {} time units along R_H",
                    o.raise, kMaxRiemannTime);
  }
  phases.push_back(
      integrate_phase("riemann", riemann, z1, std::max(duration, 1e-9), kRiemannPoints));
  phases.push_back(integrate_phase("symplectic-after", symplectic, phases[1].z.bottomRows(1),
                                   o.after, points(o.after)));

  BumpResult result;
  result.trajectory = trajectory;
  result.riemann_time = duration;
  std::string csv = "phase,t,z_q,z_p,learned_h,theta,p,energy\n";
  std::vector<GrayImage> images;
  std::vector<double> h_before, h_after, e_before, e_after;
  double amp_before = 0, amp_after = 0, t0 = 0;
  for (std::size_t ph = 0; ph < phases.size(); ++ph) {
    const Phase& p = phases[ph];
    const Eigen::VectorXd h = model.energy(p.z).col(0);
    const physics::Batch pairs = model.decode(p.z);
    const physics::Batch next = model.decode(one_frame_later(symplectic, p.z));
    for (Eigen::Index k = (ph == 0 ? 0 : 1); k < p.z.rows(); ++k) {  // phases share endpoints
      const Eigen::RowVector2d x =
          state_from_frames(scene, pairs.row(k).head(kFramePixels), next.row(k).head(kFramePixels));
      const double e = scene.energy(x);
      csv += fmt::format("{},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g}\n", p.name,
                         t0 + p.t[std::size_t(k)], p.z(k, 0), p.z(k, 1), h(k), x(0), x(1), e);
      if (ph == 0) {
        h_before.push_back(h(k));
        e_before.push_back(e);
        amp_before = std::max(amp_before, std::abs(x(0)));
      } else if (ph == 2) {
        h_after.push_back(h(k));
        e_after.push_back(e);
        amp_after = std::max(amp_after, std::abs(x(0)));
      }
      GrayImage image(kSide * kScale + 2 * kGap, kSide * kScale + 2 * kGap,
                      ph == 1 ? 128 : 64);  // a lighter border while R_H is integrated
      draw_frame(image, kGap, kGap, pairs.row(k).tail(kFramePixels).cast<float>(), kSide, kScale,
                 physics::GymPendulum::kIntensity);
      images.push_back(std::move(image));
    }
    t0 += p.t.back();
  }
  result.h_before = mean_of(h_before);
  result.h_after = mean_of(h_after);
  result.energy_before = mean_of(e_before);
  result.energy_after = mean_of(e_after);
  result.amplitude_before = amp_before;
  result.amplitude_after = amp_after;

  if (!o.out.empty()) {
    fs::create_directories(o.out);
    write_file_atomic(o.out / "bump.csv", csv);
    write_gif(o.out / "bump.gif", images, 5);
    // The strip: every 4th image, in one row.
    const int stride = 4, tile = kSide * kScale + 2 * kGap;
    const int cols = int((images.size() - 1) / stride) + 1;
    GrayImage strip(cols * tile, tile, 64);
    for (int c = 0; c < cols; ++c) {
      const GrayImage& img = images[std::size_t(c * stride)];
      for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x) strip.at(c * tile + x, y) = img.at(x, y);
    }
    write_png(o.out / "bump_strip.png", strip);
    result.files = {o.out / "bump.csv", o.out / "bump.gif", o.out / "bump_strip.png"};
  }
  return result;
}

}  // namespace hnn::tasks::pixel
