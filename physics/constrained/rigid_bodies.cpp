// The gyroscope and the rotor as constrained point masses (rigid_bodies.h).
#include "physics/constrained/rigid_bodies.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

namespace hnn::physics::constrained {
namespace {

// Second moments (volume-normalised covariance diagonal) and centre of the peer's meshes, by
// its compute_moments over read_obj's vertices (rolled to z, x, y; the gyroscope's shifted to
// its lowest point): gyro.obj and rotor.obj of mfinzi/constrained-hamiltonian-neural-networks.
const Eigen::Vector3d kGyroMoments{0.00241378386118703, 0.00241378380645191, 0.00036941541417881};
const Eigen::Vector3d kGyroCentre{-3.295067025785891e-08, -3.255806865761840e-08,
                                  0.2217285381709906};
const Eigen::Vector3d kRotorMoments{0.00298513426252909, 0.09906336523618609, 0.02110851337999703};

Eigen::Matrix3d rotation(int axis, double angle) {
  return Eigen::AngleAxisd(angle, Eigen::Vector3d::Unit(axis)).toRotationMatrix();
}

// d/dangle of rotation(axis, angle): the generator times the rotation.
Eigen::Matrix3d rotation_derivative(int axis, double angle) {
  Eigen::Matrix3d generator = Eigen::Matrix3d::Zero();
  const int i = (axis + 1) % 3, j = (axis + 2) % 3;
  generator(j, i) = 1.0;
  generator(i, j) = -1.0;
  return generator * rotation(axis, angle);
}

}  // namespace

void euler_frame(const Eigen::Vector3d& angles, const Eigen::Vector3d& rates, Eigen::Matrix3d& r,
                 Eigen::Matrix3d& r_dot) {
  const Eigen::Matrix3d a = rotation(2, angles[0]), b = rotation(0, angles[1]),
                        c = rotation(2, angles[2]);
  r = a * b * c;
  r_dot = rotation_derivative(2, angles[0]) * b * c * rates[0] +
          a * rotation_derivative(0, angles[1]) * c * rates[1] +
          a * b * rotation_derivative(2, angles[2]) * rates[2];
}

ConstrainedSpec rigid_body_spec(const std::string& name, double mass,
                                const Eigen::Vector3d& moments) {
  const Eigen::Vector3d inertia = mass * moments;
  ConstrainedSpec spec;
  spec.name = name;
  spec.points = 4;
  spec.dim = 3;
  spec.mass = Eigen::MatrixXd::Zero(4, 4);
  spec.mass(0, 0) = mass + inertia.sum();
  for (int k = 1; k <= 3; ++k) {
    spec.mass(k, k) = inertia[k - 1];
    spec.mass(0, k) = spec.mass(k, 0) = -inertia[k - 1];
    spec.distances.push_back({0, k, 1.0});
    for (int j = 1; j < k; ++j) spec.distances.push_back({j, k, std::sqrt(2.0)});
  }
  return spec;
}

void rigid_body_points(const Eigen::Vector3d& centre, const Eigen::Vector3d& centre_rate,
                       const Eigen::Vector3d& angles, const Eigen::Vector3d& rates, double* z) {
  Eigen::Matrix3d r, r_dot;
  euler_frame(angles, rates, r, r_dot);
  for (int k = 0; k < 3; ++k) {
    z[k] = centre[k];
    z[12 + k] = centre_rate[k];
    for (int axis = 0; axis < 3; ++axis) {
      z[3 * (axis + 1) + k] = centre[k] + r(k, axis);
      z[12 + 3 * (axis + 1) + k] = centre_rate[k] + r_dot(k, axis);
    }
  }
}

ConstrainedSystem gyroscope() {
  constexpr double kMass = 0.1;
  ConstrainedSpec spec = rigid_body_spec("gyroscope", kMass, 100.0 * kGyroMoments);
  // The tip, at body coordinates -centre, held at the origin: weights (1 - sum c, c) with c =
  // -centre over (centre point, axis tips).
  Eigen::VectorXd weights(4);
  weights << 1.0 + kGyroCentre.sum(), -kGyroCentre;
  spec.pins.push_back({weights, Eigen::Vector3d::Zero()});
  Eigen::VectorXd centre_mass = Eigen::VectorXd::Zero(4);
  centre_mass[0] = kMass;  // M's column sums: the body's weight acts on its centre alone
  spec.potential = {gravity(centre_mass, 3, 2)};
  spec.sampler = [weights](const ConstrainedSystem&, int n, std::mt19937_64& rng) {
    std::uniform_real_distribution<double> uniform(-1.5, 1.5);
    std::normal_distribution<double> normal;
    std::bernoulli_distribution coin;
    Batch z(n, 24);
    for (int row = 0; row < n; ++row) {
      Eigen::Vector3d angles, rates;
      for (int k = 0; k < 3; ++k) angles[k] = uniform(rng);
      rates[0] = 3.0 * uniform(rng);
      rates[1] = 0.2 * uniform(rng);
      rates[2] = (coin(rng) ? 1.0 : -1.0) * (normal(rng) + 7.0) * 1.5;
      rigid_body_points(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), angles, rates,
                        &z(row, 0));
      // Move the body so that the tip is at the origin and at rest.
      for (int half = 0; half < 2; ++half)
        for (int k = 0; k < 3; ++k) {
          double tip = 0.0;
          for (int p = 0; p < 4; ++p) tip += weights[p] * z(row, 12 * half + 3 * p + k);
          for (int p = 0; p < 4; ++p) z(row, 12 * half + 3 * p + k) -= tip;
        }
    }
    return z;
  };
  spec.dt = 0.02;
  spec.horizon = 2.0;
  return ConstrainedSystem(std::move(spec));
}

ConstrainedSystem rotor() {
  ConstrainedSpec spec = rigid_body_spec("rotor", 0.1, kRotorMoments);
  spec.sampler = [](const ConstrainedSystem&, int n, std::mt19937_64& rng) {
    std::normal_distribution<double> normal;
    const auto draw = [&] { return std::clamp(2.0 * normal(rng), -3.0, 3.0); };
    Batch z(n, 24);
    for (int row = 0; row < n; ++row) {
      Eigen::Vector3d centre, centre_rate, angles, rates;
      for (int k = 0; k < 3; ++k) centre[k] = 0.1 * draw();
      for (int k = 0; k < 3; ++k) angles[k] = draw();
      for (int k = 0; k < 3; ++k) centre_rate[k] = 0.1 * draw();
      for (int k = 0; k < 3; ++k) rates[k] = draw();
      rigid_body_points(centre, centre_rate, angles, rates, &z(row, 0));
    }
    return z;
  };
  spec.dt = 0.05;
  spec.horizon = 5.0;
  return ConstrainedSystem(std::move(spec));
}

}  // namespace hnn::physics::constrained
