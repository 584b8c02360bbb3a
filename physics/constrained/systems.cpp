// The peer's chain, coupled and magnet pendulums (systems.h), and the registry by name.
#include "physics/constrained/systems.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <cmath>
#include <numbers>
#include <stdexcept>

#include "physics/constrained/chain_angles.h"
#include "physics/constrained/rigid_bodies.h"

namespace hnn::physics::constrained {
namespace {

// .6 + .8 U(0, 1) from numpy's np.random.seed(0), in draw order: ChainPendulum(links) takes
// draws 0..links-1 as masses and links..2 links-1 as lengths, and pops each list from its end,
// so link 1 gets the last of each.
constexpr double kPeerDraws[10] = {1.0390508031418597, 1.1721514930979355, 1.0822107008573152,
                                   1.0359065463975174, 0.9389238394711238, 1.1167152904533248,
                                   0.950069769010154,  1.3134184006256637, 1.3709302084008235,
                                   0.9067532150606221};

void check_links(int links) {
  if (links < 1 || links > 5)
    throw std::invalid_argument(fmt::format("chain_pendulum: links must be 1..5, got {}", links));
}

Eigen::VectorXd peer_draws_reversed(int first, int links) {
  Eigen::VectorXd out(links);
  for (int k = 0; k < links; ++k) out[k] = kPeerDraws[first + links - 1 - k];
  return out;
}

constexpr int kSamplerAttempts = 10;

Batch sample_chain(const ConstrainedSystem& system, const Eigen::VectorXd& lengths, int n,
                   std::mt19937_64& rng) {
  const int links = static_cast<int>(lengths.size()), dims = 2 * links;
  std::normal_distribution<double> normal;
  for (int attempt = 1;; ++attempt) {
    Batch angles(n, dims);
    for (Eigen::Index i = 0; i < angles.size(); ++i) angles.data()[i] = normal(rng);
    Batch z = chain_cartesian(lengths, angles);
    for (int r = 0; r < n; ++r) {
      for (int c = 0; c < dims; ++c) z(r, c) += 0.2 * normal(rng);
      for (int c = dims; c < 2 * dims; ++c) z(r, c) = (0.5 * z(r, c) + 0.4 * normal(rng)) * 3.0;
    }
    // The peer draws the whole batch again when its projection fails to converge.
    try {
      return system.project_peer(z);
    } catch (const std::runtime_error&) {
      if (attempt == kSamplerAttempts) throw;
    }
  }
}

Batch sample_spherical(int n, int bobs, const Eigen::MatrixXd& pivots, double phi_sd,
                       double phi_rate_sd, double theta_sd, double theta_rate_sd,
                       std::mt19937_64& rng) {
  std::normal_distribution<double> normal;
  const int half = 3 * bobs;
  Batch z(n, 2 * half);
  for (int r = 0; r < n; ++r) {
    for (int b = 0; b < bobs; ++b) {
      const double phi = std::numbers::pi + phi_sd * normal(rng);
      const double theta = std::numbers::pi / 2 + theta_sd * normal(rng);
      const double phi_dot = phi_rate_sd * normal(rng);
      const double theta_dot = theta_rate_sd * normal(rng);
      spherical_point(phi, theta, phi_dot, theta_dot, &z(r, 3 * b), &z(r, half + 3 * b));
      for (int k = 0; k < 3; ++k) z(r, 3 * b + k) += pivots(b, k);
    }
  }
  return z;
}

}  // namespace

Eigen::VectorXd chain_pendulum_masses(int links) {
  check_links(links);
  return peer_draws_reversed(0, links);
}

Eigen::VectorXd chain_pendulum_lengths(int links) {
  check_links(links);
  return peer_draws_reversed(links, links);
}

ConstrainedSystem chain_pendulum(Eigen::VectorXd masses, Eigen::VectorXd lengths) {
  const auto links = static_cast<int>(masses.size());
  if (links < 1 || lengths.size() != links)
    throw std::invalid_argument("chain_pendulum: needs one mass and one length per link");
  ConstrainedSpec spec;
  spec.name = fmt::format("chain_pendulum_{}", links);
  spec.points = links;
  spec.dim = 2;
  spec.mass = masses.asDiagonal();
  spec.anchors.push_back({0, Eigen::Vector2d::Zero(), lengths[0]});
  for (int k = 1; k < links; ++k) spec.distances.push_back({k - 1, k, lengths[k]});
  spec.potential = {gravity(masses, 2, 1)};
  spec.sampler = [lengths](const ConstrainedSystem& system, int n, std::mt19937_64& rng) {
    return sample_chain(system, lengths, n, rng);
  };
  spec.dt = 0.03;
  spec.horizon = 3.0;
  return ConstrainedSystem(std::move(spec));
}

ConstrainedSystem chain_pendulum(int links) {
  return chain_pendulum(chain_pendulum_masses(links), chain_pendulum_lengths(links));
}

void spherical_point(double phi, double theta, double phi_dot, double theta_dot, double* x,
                     double* v) {
  const double sp = std::sin(phi), cp = std::cos(phi), st = std::sin(theta), ct = std::cos(theta);
  x[0] = -ct;
  x[1] = sp * st;
  x[2] = cp * st;
  v[0] = st * theta_dot;
  v[1] = cp * st * phi_dot + sp * ct * theta_dot;
  v[2] = -sp * st * phi_dot + cp * ct * theta_dot;
}

ConstrainedSystem coupled_pendulums(int bobs) {
  if (bobs < 2) throw std::invalid_argument("coupled_pendulums: needs at least 2 bobs");
  Eigen::MatrixXd pivots = Eigen::MatrixXd::Zero(bobs, 3);
  for (int b = 0; b < bobs; ++b) pivots(b, 0) = b;
  ConstrainedSpec spec;
  spec.name = fmt::format("coupled_pendulums_{}", bobs);
  spec.points = bobs;
  spec.dim = 3;
  spec.mass = Eigen::MatrixXd::Identity(bobs, bobs);
  std::vector<Spring> list;
  for (int b = 0; b < bobs; ++b) {
    spec.anchors.push_back({b, pivots.row(b).transpose(), 1.0});
    if (b > 0) list.push_back({b - 1, b, 10.0, 1.0});
  }
  spec.potential = {gravity(Eigen::VectorXd::Ones(bobs), 3, 2), springs(std::move(list), 3)};
  spec.sampler = [pivots](const ConstrainedSystem&, int n, std::mt19937_64& rng) {
    return sample_spherical(n, static_cast<int>(pivots.rows()), pivots, 0.3, 0.3, 0.3, 0.3, rng);
  };
  spec.dt = 0.05;
  spec.horizon = 5.0;
  return ConstrainedSystem(std::move(spec));
}

ConstrainedSystem magnet_pendulum() {
  constexpr double kMass = 3.0, kCharge = 0.3;
  Eigen::MatrixXd magnets(2, 3), moments = Eigen::MatrixXd::Zero(2, 3);
  for (int i = 0; i < 2; ++i) {
    const double angle = std::numbers::pi * i;  // linspace(0, 2 pi, 3)[:-1]
    magnets.row(i) << 0.1 * std::cos(angle), 0.1 * std::sin(angle), -1.05;
    moments(i, 2) = kCharge;
  }
  ConstrainedSpec spec;
  spec.name = "magnet_pendulum";
  spec.points = 1;
  spec.dim = 3;
  spec.mass = Eigen::MatrixXd::Constant(1, 1, kMass);
  spec.anchors.push_back({0, Eigen::Vector3d::Zero(), 1.0});
  spec.potential = {gravity(Eigen::VectorXd::Constant(1, kMass), 3, 2),
                    magnet_dipoles(kCharge, magnets, moments)};
  spec.sampler = [](const ConstrainedSystem&, int n, std::mt19937_64& rng) {
    return sample_spherical(n, 1, Eigen::MatrixXd::Zero(1, 3), 0.3, 0.05, 0.2, 0.4, rng);
  };
  spec.dt = 0.05;
  spec.horizon = 5.0;
  return ConstrainedSystem(std::move(spec));
}

std::vector<std::string> constrained_system_names() {
  std::vector<std::string> names;
  for (int links = 1; links <= 5; ++links) names.push_back(fmt::format("chain_pendulum_{}", links));
  names.insert(names.end(), {"coupled_pendulums_3", "magnet_pendulum", "gyroscope", "rotor"});
  return names;
}

ConstrainedSystem make_constrained_system(const std::string& name) {
  for (int links = 1; links <= 5; ++links)
    if (name == fmt::format("chain_pendulum_{}", links)) return chain_pendulum(links);
  if (name == "coupled_pendulums_3") return coupled_pendulums(3);
  if (name == "magnet_pendulum") return magnet_pendulum();
  if (name == "gyroscope") return gyroscope();
  if (name == "rotor") return rotor();
  throw std::invalid_argument(fmt::format("unknown constrained system '{}'; known: {}", name,
                                          fmt::join(constrained_system_names(), ", ")));
}

}  // namespace hnn::physics::constrained
