// Constrained systems in Cartesian coordinates (physics/constrained/): the truth keeps the
// constraints and the energy, the multipliers keep d^2 phi/dt^2 = 0, projections land on the
// manifold, and the angle-coordinate chain gives the Cartesian chain's trajectory.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstdio>
#include <functional>
#include <thread>
#include <vector>

#include "physics/constrained/chain_angles.h"
#include "physics/constrained/rigid_bodies.h"
#include "physics/constrained/systems.h"
#include "physics/dopri5.h"
#include "physics/double_pendulum.h"

namespace hnn::physics::constrained {
namespace {

double max_abs(const Batch& b) { return b.cwiseAbs().maxCoeff(); }

// Energy scale of each row: kinetic plus |potential|, so that a near-zero total (the chain's V
// is zero at the pivot's height) does not inflate the relative drift.
Eigen::VectorXd energy_scale(const ConstrainedSystem& system, const Batch& z) {
  Eigen::VectorXd scale(z.rows());
  for (Eigen::Index r = 0; r < z.rows(); ++r) {
    const double v = system.potential(&z(r, 0));
    scale[r] = std::abs(system.hamiltonian_batch(z.row(r)).value() - v) + std::abs(v);
  }
  return scale;
}

TEST(ConstrainedTruth, ConstraintsAndEnergyHoldAlongTheTruthOfEverySystem) {
  for (const std::string& name : constrained_system_names()) {
    SCOPED_TRACE(name);
    const ConstrainedSystem system = make_constrained_system(name);
    std::mt19937_64 rng(11);
    const Batch z0 = system.sample_initial_states(3, rng);
    ASSERT_LT(max_abs(system.constraint_values(z0)), 1e-10);
    ASSERT_LT(max_abs(system.constraint_velocities(z0)), 1e-10);
    const std::vector<double> times = system.output_times();
    ASSERT_EQ(times.size(), 100u);
    const Trajectory truth = simulate_constrained(system, z0, times);
    const Eigen::VectorXd e0 = system.hamiltonian_batch(z0), scale = energy_scale(system, z0);
    double phi = 0.0, phi_dot = 0.0, energy = 0.0;
    for (const Batch& z : truth.states) {
      phi = std::max(phi, max_abs(system.constraint_values(z)));
      phi_dot = std::max(phi_dot, max_abs(system.constraint_velocities(z)));
      energy = std::max(
          energy, ((system.hamiltonian_batch(z) - e0).array().abs() / scale.array()).maxCoeff());
    }
    std::printf("%-20s max |phi| %.1e  max |J v| %.1e  max energy drift %.1e  (%ld steps in all)\n",
                name.c_str(), phi, phi_dot, energy, truth.stats.steps);
    EXPECT_LT(phi, 5e-9);
    EXPECT_LT(phi_dot, 5e-8);
    EXPECT_LT(energy, 1e-7);
  }
}

TEST(ConstrainedField, MultipliersKeepTheSecondDerivativeOfTheConstraintsZero) {
  for (const char* name : {"chain_pendulum_3", "gyroscope", "coupled_pendulums_3"}) {
    SCOPED_TRACE(name);
    const ConstrainedSystem system = make_constrained_system(name);
    std::mt19937_64 rng(5);
    const Batch z = system.sample_initial_states(2, rng);
    const Batch a = system.acceleration(z);
    const int n = system.configuration_dim();
    for (Eigen::Index r = 0; r < z.rows(); ++r) {
      const Eigen::VectorXd x = z.row(r).head(n).transpose(), v = z.row(r).tail(n).transpose();
      const auto phi = [&](const Eigen::VectorXd& p) {
        return system.linearize(p.data(), v.data()).phi;
      };
      // Central second difference of phi along x + s v + s^2 a / 2: d^2 phi/dt^2 + c h^2, the
      // h^2 term removed by Richardson extrapolation from h and h / 2.
      const auto second_derivative = [&](const Eigen::VectorXd& acc) {
        const auto difference = [&](double h) -> Eigen::VectorXd {
          return (phi(x + h * v + 0.5 * h * h * acc) + phi(x - h * v + 0.5 * h * h * acc) -
                  2.0 * phi(x)) /
                 (h * h);
        };
        return ((4.0 * difference(5e-4) - difference(1e-3)) / 3.0).cwiseAbs().maxCoeff();
      };
      const Eigen::VectorXd free =
          -system.inverse_mass_full() * system.potential_gradient(x.data());
      const double with = second_derivative(a.row(r).transpose());
      const double without = second_derivative(free);
      std::printf("%-20s d2phi/dt2 with multipliers %.1e, without %.1e\n", name, with, without);
      EXPECT_LT(with, 1e-6 * without);
    }
    // On the manifold the projected field of the truth is (v, a).
    Batch dz;
    system.vector_field(z, dz);
    EXPECT_LT(max_abs(dz.leftCols(n) - z.rightCols(n)), 1e-12);
    EXPECT_LT(max_abs(dz.rightCols(n) - a), 1e-9 * (1.0 + max_abs(a)));
  }
}

// Three states from the system's sampler, and the same moved off the manifold by 1e-3 N(0, 1).
Batch sampled(const ConstrainedSystem& system, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  return system.sample_initial_states(3, rng);
}
Batch moved_off(const Batch& z0, std::uint64_t seed) {
  std::mt19937_64 rng(seed + 1000);
  std::normal_distribution<double> normal;
  Batch moved = z0;
  for (Eigen::Index i = 0; i < moved.size(); ++i) moved.data()[i] += 1e-3 * normal(rng);
  return moved;
}

TEST(ConstrainedProjection, LandsOnTheManifoldAndIsIdempotent) {
  for (const std::string& name : constrained_system_names()) {
    SCOPED_TRACE(name);
    const ConstrainedSystem system = make_constrained_system(name);
    const Batch moved = moved_off(sampled(system, 3), 3);
    const Batch once = system.project(moved);
    EXPECT_LT(max_abs(system.constraint_values(once)), 1e-11);
    EXPECT_LT(max_abs(system.constraint_velocities(once)), 1e-12 * (1.0 + max_abs(once)));
    EXPECT_LT(max_abs(once - moved), 5e-2);  // a small move, not another state
    EXPECT_LT(max_abs(system.project(once) - once), 1e-13 * (1.0 + max_abs(once)));
    const Batch peer = system.project_peer(moved);
    EXPECT_LT(max_abs(system.constraint_values(peer)), 1e-11);
    EXPECT_LT(max_abs(system.constraint_velocities(peer)), 1e-11);
  }
}

// Every system: its sampled states have no problem; moved by 1e-3, each has one that names a
// constraint in words, and projected back it has none again.
TEST(ConstrainedProjection, StateProblemNamesTheConstraintAStateIsOff) {
  for (const std::string& name : constrained_system_names()) {
    SCOPED_TRACE(name);
    const ConstrainedSystem system = make_constrained_system(name);
    const Batch z0 = sampled(system, 4);
    const Batch moved = moved_off(z0, 4);
    const Batch back = system.project(moved);
    for (Eigen::Index r = 0; r < z0.rows(); ++r) {
      EXPECT_EQ(system.state_problem(&z0(r, 0)), "");
      const std::string problem = system.state_problem(&moved(r, 0));
      EXPECT_TRUE(problem.find(" apart, their rod is ") != std::string::npos ||
                  problem.find("from its pivot") != std::string::npos)
          << problem;
      EXPECT_EQ(system.state_problem(&back(r, 0)), "");
    }
  }
}

// The two-link chain's words: which rod, how long it is, how long it must be; and a state whose
// positions keep the rods but whose velocities stretch one.
TEST(ConstrainedProjection, StateProblemOfTheChainSaysWhichRodAndHowFar) {
  const ConstrainedSystem chain = chain_pendulum(Eigen::Vector2d(1, 1), Eigen::Vector2d(1, 2));
  Eigen::VectorXd z(8);
  z << 0, -1, 0, -2.5, 0, 0, 0, 0;  // the rod from point 0 to 1 is 1.5, not 2
  EXPECT_EQ(chain.state_problem(z.data()), "points 0 and 1 are 1.5 apart, their rod is 2 long");
  z << 0, -0.5, 0, -2.5, 0, 0, 0, 0;
  EXPECT_EQ(chain.state_problem(z.data()),
            "point 0 and its anchor are 0.5 apart, their rod is 1 long");
  z << 0, -1, 0, -3, 0, 0, 0, 0.5;  // point 1 falls along its rod
  EXPECT_EQ(chain.state_problem(z.data()),
            "points 0 and 1 move apart at -0.5 a time unit, along a rod of fixed length");
  z << 0, -1, 0, -3, 1, 0, 2, 0;  // swinging: velocities across the rods
  EXPECT_EQ(chain.state_problem(z.data()), "");
}

TEST(ConstrainedTruth, ProjectedFormKeepsAViolationConstantWhereTheMultipliersWouldGrowIt) {
  // Velocities off the tangent space by ~1e-2: with the multiplier form phi would grow like
  // (J v) t; the projected form (Note [Projected form]) keeps phi and J v where they started.
  const ConstrainedSystem system = chain_pendulum(3);
  std::mt19937_64 rng(4);
  Batch z0 = system.sample_initial_states(2, rng);
  z0.rightCols(system.configuration_dim()).array() += 1e-2;
  const Batch jv0 = system.constraint_velocities(z0), phi0 = system.constraint_values(z0);
  ASSERT_GT(max_abs(jv0), 1e-3);
  const Trajectory path = simulate_constrained(system, z0, {0.0, 1.0, 2.0});
  EXPECT_LT(max_abs(system.constraint_values(path.states.back()) - phi0), 1e-9);
  EXPECT_LT(max_abs(system.constraint_velocities(path.states.back()) - jv0), 1e-8);
}

TEST(ConstrainedTruth, RowsSharedAmongThreadsGiveTheSameStatesAndSteps) {
  // The rows as simulate_constrained's parts, on three threads in reverse order: each row is
  // integrated on its own steps, so nothing may depend on which thread ran it or when.
  std::atomic<int> ran{0};
  const RowParallel three_threads = [&ran](int parts, const std::function<void(int)>& part) {
    std::vector<std::thread> threads;
    for (int t = 0; t < 3; ++t) {
      threads.emplace_back([&, t] {
        for (int i = parts - 1 - t; i >= 0; i -= 3, ++ran) part(i);
      });
    }
    for (std::thread& thread : threads) thread.join();
  };
  const ConstrainedSystem system = make_constrained_system("magnet_pendulum");
  std::mt19937_64 rng(5);
  const Batch z0 = system.sample_initial_states(7, rng);
  const std::vector<double> times = system.output_times();
  const Trajectory serial = simulate_constrained(system, z0, times);
  const Trajectory shared = simulate_constrained(system, z0, times, {.parallel = three_threads});
  for (std::size_t k = 0; k < times.size(); ++k)
    ASSERT_EQ(shared.states[k], serial.states[k]) << "at output " << k;
  EXPECT_EQ(shared.stats.steps, serial.stats.steps);
  EXPECT_EQ(shared.stats.nfev, serial.stats.nfev);
  EXPECT_EQ(ran.load(), 7);  // one part per row
  EXPECT_GT(serial.stats.steps, 7 * 99);
}

TEST(ConstrainedSystems, PeerParametersAndBadNames) {
  const ConstrainedSystem chain = chain_pendulum(2);
  EXPECT_DOUBLE_EQ(chain.spec().mass(0, 0), 1.1721514930979355);
  EXPECT_DOUBLE_EQ(chain.spec().anchors[0].length, 1.0359065463975174);
  EXPECT_DOUBLE_EQ(chain.spec().distances[0].length, 1.0822107008573152);
  EXPECT_DOUBLE_EQ(make_constrained_system("gyroscope").spec().dt, 0.02);
  EXPECT_EQ(make_constrained_system("rotor").output_times().size(), 100u);
  EXPECT_THROW(make_constrained_system("chain_pendulum_6"), std::invalid_argument);
  EXPECT_THROW(chain_pendulum(0), std::invalid_argument);
}

TEST(ConstrainedSystems, RigidBodyKineticEnergyIsTheInertiaTensors) {
  // The point masses' v^T M v / 2 equals m |v_c|^2 / 2 + w^T (tr S - S) w / 2 with S the
  // second moments and w the body-frame angular velocity: the mass matrix is a rigid body's.
  const ConstrainedSystem rotor_system = rotor();
  const Eigen::Vector3d angles(0.3, -1.1, 2.0), rates(0.7, -0.4, 1.9), vc(0.2, -0.1, 0.3);
  Batch z(1, 24);
  rigid_body_points(Eigen::Vector3d(0.1, 0.2, 0.3), vc, angles, rates, z.data());
  Eigen::Matrix3d r, r_dot;
  euler_frame(angles, rates, r, r_dot);
  const Eigen::Matrix3d w_cross = r.transpose() * r_dot;
  const Eigen::Vector3d w(w_cross(2, 1), w_cross(0, 2), w_cross(1, 0));
  const Eigen::Vector3d s =
      0.1 * Eigen::Vector3d(0.00298513426252909, 0.09906336523618609, 0.02110851337999703);
  const Eigen::Matrix3d inertia =
      s.sum() * Eigen::Matrix3d::Identity() - Eigen::Matrix3d(s.asDiagonal());
  const double expected = 0.5 * 0.1 * vc.squaredNorm() + 0.5 * w.dot(inertia * w);
  EXPECT_NEAR(rotor_system.hamiltonian_batch(z).value(), expected, 1e-14);
  EXPECT_LT((w_cross + w_cross.transpose()).cwiseAbs().maxCoeff(), 1e-14);
}

TEST(ConstrainedSystems, SamplersPlaceTheBodiesAsThePeers) {
  std::mt19937_64 rng(8);
  const Batch magnet = magnet_pendulum().sample_initial_states(200, rng);
  EXPECT_LT(magnet.col(2).mean(), -0.9);  // hangs down over the magnets, near (0, 0, -1)
  EXPECT_LT(magnet.col(0).cwiseAbs().mean(), 0.3);
  const Batch coupled = coupled_pendulums(3).sample_initial_states(200, rng);
  for (int b = 0; b < 3; ++b) EXPECT_NEAR(coupled.col(3 * b).mean(), b, 0.1);  // below (b, 0, 0)
  const Batch gyro = gyroscope().sample_initial_states(200, rng);
  EXPECT_GT(gyro.col(2).minCoeff(), 0.0);  // the centre stands above the tip at the origin
  EXPECT_NEAR(gyro.col(2).maxCoeff(), 0.2217, 1e-3);
}

TEST(ConstrainedSystems, EulerFrameIsScipysZxzAndItsDerivative) {
  const Eigen::Vector3d angles(0.3, -1.1, 2.0), rates(0.7, -0.4, 1.9);
  Eigen::Matrix3d r, r_dot, scipy;
  // Rotation.from_euler('ZXZ', [0.3, -1.1, 2.0]).as_matrix()
  scipy << -0.5194486858736262, -0.812901851411958, -0.2633697832234624, 0.2710523527349594,
      -0.44904755445759154, 0.8514029104439915, -0.810372559271972, 0.37087312359709634,
      0.4535961214255772;
  euler_frame(angles, rates, r, r_dot);
  EXPECT_LT((r - scipy).cwiseAbs().maxCoeff(), 1e-15);
  constexpr double h = 1e-6;
  Eigen::Matrix3d plus, minus, unused;
  euler_frame(angles + h * rates, rates, plus, unused);
  euler_frame(angles - h * rates, rates, minus, unused);
  EXPECT_LT((r_dot - (plus - minus) / (2.0 * h)).cwiseAbs().maxCoeff(), 1e-9);
}

TEST(ChainAngles, TwoLinkFieldIsTheDoublePendulums) {
  const ChainPendulumAngles chain(Eigen::Vector2d(1.0, 1.0), Eigen::Vector2d(1.0, 1.0), 9.81);
  const DoublePendulum reference;
  Batch x(2, 4);
  x << 0.3, -1.2, 0.5, 0.1, 2.0, 1.0, -0.4, 0.9;
  Batch ours, theirs;
  chain.vector_field(x, ours);
  reference.vector_field(x, theirs);
  EXPECT_LT(max_abs(ours - theirs), 1e-13);
  // Same H up to where V is zero: at the pivot here, at rest there (3 g lower).
  const Eigen::VectorXd shift = chain.hamiltonian_batch(x) - reference.hamiltonian_batch(x);
  EXPECT_NEAR(shift[0], -3.0 * 9.81, 1e-12);
  EXPECT_NEAR(shift[1], -3.0 * 9.81, 1e-12);
}

TEST(ChainAngles, VelocityFormFollowsTheCanonicalFieldForThreeLinks) {
  // d omega/dt of the Lagrangian form equals d/dt (M^-1 p) along the canonical field, by a
  // central difference of omega along the canonical flow's tangent.
  const ChainPendulumVelocities lagrangian(3);
  const ChainPendulumAngles& canonical = lagrangian.canonical();
  std::mt19937_64 rng(6);
  const Batch w = lagrangian.sample_initial_states(2, rng);
  const Batch x = canonical.momenta_from_velocities(w);
  Batch dw, dx;
  lagrangian.vector_field(w, dw);
  canonical.vector_field(x, dx);
  constexpr double h = 1e-6;
  const Batch ahead = canonical.velocities_from_momenta(x + h * dx);
  const Batch behind = canonical.velocities_from_momenta(x - h * dx);
  EXPECT_LT(max_abs(dw - (ahead - behind) / (2.0 * h)), 1e-6 * (1.0 + max_abs(dw)));
  EXPECT_LT(max_abs(lagrangian.hamiltonian_batch(w) - canonical.hamiltonian_batch(x)), 1e-12);
  EXPECT_LT(max_abs(lagrangian.to_cartesian(w) - canonical.to_cartesian(x)), 1e-12);
}

TEST(ChainAngles, GivesTheCartesianChainsTrajectoryForTwoLinks) {
  const ChainPendulumAngles angles(2);
  const ConstrainedSystem& cartesian = angles.cartesian();
  std::mt19937_64 rng(9);
  Batch z0(4, 8);
  z0.topRows(3) = cartesian.sample_initial_states(3, rng);
  // And one that swings over the top, through theta = pi, where chain_angles wraps.
  z0.bottomRows(1) = chain_cartesian(chain_pendulum_lengths(2), Batch{{3.0, 3.0, 4.0, 4.0}});
  const Batch x0 = angles.from_cartesian(z0);
  EXPECT_LT(max_abs(angles.to_cartesian(x0) - z0), 1e-12);
  EXPECT_LT(max_abs(angles.hamiltonian_batch(x0) - cartesian.hamiltonian_batch(z0)), 1e-10);
  const std::vector<double> times = cartesian.output_times();
  const Trajectory in_cartesian = simulate_constrained(cartesian, z0, times);
  IntegratorOptions options;
  options.rtol = 1e-10;
  options.atol = 1e-12;
  const Trajectory in_angles = Dopri5(options).integrate(angles.field(), x0, times);
  double gap = 0.0;
  for (std::size_t k = 0; k < times.size(); ++k)
    gap = std::max(gap, max_abs(angles.to_cartesian(in_angles.states[k]) - in_cartesian.states[k]));
  // The angles read back from the Cartesian path, made continuous, are the angle path's.
  std::vector<Batch> read_back;
  for (const Batch& z : in_cartesian.states) read_back.push_back(chain_angles(2, z));
  unwrap_angles(read_back, 2);
  double angle_gap = 0.0, largest_angle = 0.0;
  for (std::size_t k = 0; k < times.size(); ++k) {
    angle_gap =
        std::max(angle_gap, max_abs(read_back[k].leftCols(2) - in_angles.states[k].leftCols(2)));
    largest_angle = std::max(largest_angle, max_abs(in_angles.states[k].leftCols(2)));
  }
  EXPECT_LT(angle_gap, 1e-6);
  EXPECT_GT(largest_angle, 3.5);  // the path goes past pi, where chain_angles wraps
  std::printf("two-link chain, angles vs Cartesian over %.1f s: max |dz| %.1e\n", times.back(),
              gap);
  EXPECT_LT(gap, 1e-6);
}

}  // namespace
}  // namespace hnn::physics::constrained
