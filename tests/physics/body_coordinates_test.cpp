// Body coordinates of the constrained systems that are not chains (physics/constrained/
// body_coordinates.h): the maps invert each other, the positions' Jets are their derivatives, and
// the field in (q, qdot) moves the system as the Cartesian truth does.
#include "physics/constrained/body_coordinates.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "physics/constrained/systems.h"
#include "physics/dopri5.h"

namespace hnn::physics::constrained {
namespace {

const char* const kBodySystems[] = {"coupled_pendulums_3", "magnet_pendulum", "gyroscope", "rotor"};

double largest_abs(const Batch& b) { return b.cwiseAbs().maxCoeff(); }

TEST(BodyCoordinates, MapTheSampledStatesThereAndBack) {
  for (const std::string name : kBodySystems) {
    SCOPED_TRACE(name);
    const BodyCoordinates body(make_constrained_system(name));
    std::mt19937_64 rng(3);
    const Batch z = body.cartesian().sample_initial_states(20, rng);
    const Batch x = body.from_cartesian(z);
    ASSERT_EQ(x.cols(), body.dim());
    EXPECT_LT(largest_abs(body.to_cartesian(x) - z), 1e-10);
    EXPECT_LT(largest_abs(body.from_cartesian(body.to_cartesian(x)) - x), 1e-8);
    EXPECT_LT(largest_abs(x.leftCols(body.angles())), M_PI + 1e-12);
    EXPECT_LT(largest_abs(body.hamiltonian_batch(x) - body.cartesian().hamiltonian_batch(z)),
              1e-10);
  }
}

TEST(BodyCoordinates, PositionJetsAreTheFirstAndSecondDerivativesAlongAPath) {
  for (const std::string name : kBodySystems) {
    SCOPED_TRACE(name);
    const ConstrainedSystem system = make_constrained_system(name);
    const BodyMap map = body_map(system);
    std::mt19937_64 rng(5);
    std::normal_distribution<double> normal;
    Eigen::VectorXd q(map.dof), u(map.dof);
    for (int i = 0; i < map.dof; ++i) {
      q[i] = 0.3 + normal(rng);
      u[i] = normal(rng);
    }
    const double h = 1e-4;
    const PositionJet at = map.positions(q, u);
    const Eigen::VectorXd ahead = map.positions(q + h * u, u).x0,
                          behind = map.positions(q - h * u, u).x0;
    EXPECT_LT(((ahead - behind) / (2 * h) - at.x1).cwiseAbs().maxCoeff(), 1e-7);
    // x2 is half the second derivative.
    EXPECT_LT(((ahead - 2 * at.x0 + behind) / (2 * h * h) - at.x2).cwiseAbs().maxCoeff(), 1e-5);
  }
}

TEST(BodyCoordinates, FieldMovesTheSystemAsTheCartesianTruth) {
  for (const std::string name : kBodySystems) {
    SCOPED_TRACE(name);
    const BodyCoordinates body(make_constrained_system(name));
    const ConstrainedSystem& cartesian = body.cartesian();
    std::mt19937_64 rng(7);
    const Batch z0 = cartesian.sample_initial_states(3, rng);
    const std::vector<double> times = cartesian.output_times();
    const Trajectory truth = simulate_constrained(cartesian, z0, times);
    IntegratorOptions options;
    options.rtol = 1e-10;
    options.atol = 1e-12;
    const Trajectory moved =
        Dopri5(options).integrate(body.field(), body.from_cartesian(z0), times);
    double gap = 0.0, scale = 0.0;
    for (std::size_t k = 0; k < times.size(); ++k) {
      gap = std::max(gap, largest_abs(body.to_cartesian(moved.states[k]) - truth.states[k]));
      scale = std::max(scale, largest_abs(truth.states[k]));
    }
    std::printf("%s in body coordinates vs Cartesian over %.1f s: max |dz| %.1e of %.1f\n",
                name.c_str(), times.back(), gap, scale);
    EXPECT_LT(gap, 1e-6 * scale);
  }
}

TEST(BodyCoordinates, AChainIsRefusedNamingWhereItsAnglesAre) {
  try {
    body_map(make_constrained_system("chain_pendulum_2"));
    FAIL() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("chain_angles.h"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace hnn::physics::constrained
