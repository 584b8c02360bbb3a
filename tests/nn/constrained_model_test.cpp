// The CHNN and CLNN fields (nn/constrained/): equal to the exact motion of 1- and 2-link Cartesian
// pendulums (from the angle equations) when given the true potential; tangent to the constraints
// and their time derivative at any state (the CHNN's projection) or accelerating along them (the
// CLNN); equal to each other on the constraint manifold, where they conserve the learned energy,
// with a non-diagonal mass matrix, for a chain and for a rigid triangle pinned at its centroid
// (a ball joint); a pinned pivot; a clear error at degenerate constraints.

#include <gtest/gtest.h>

#include <Eigen/QR>
#include <cmath>
#include <numbers>
#include <string>

#include "constrained_test_util.h"

namespace ad = hnn::ad;
namespace nn = hnn::nn;
using ad::Var;
using MatrixD = nn::Matrix<double>;
using nn::ModelKind;
using nn::testing::chain_spec;
using nn::testing::constrained_config;
using nn::testing::constraint_jacobian;

namespace constrained_model_test {

constexpr double kGravity = 9.81;

// States of a 2-D chain pendulum from random angles from the downward vertical and rates, their
// exact time derivatives, and the gradient of V = g sum_i m_i y_i.
struct Exact {
  MatrixD z, zdot, dv;
};

// Angular accelerations of a 1- or 2-link pendulum (the double pendulum's textbook equations).
std::vector<double> angular_accelerations(const std::vector<double>& th,
                                          const std::vector<double>& w,
                                          const std::vector<double>& m,
                                          const std::vector<double>& l) {
  if (th.size() == 1) return {-kGravity / l[0] * std::sin(th[0])};
  const double delta = th[0] - th[1], den = 2 * m[0] + m[1] - m[1] * std::cos(2 * delta);
  const double a1 =
      (-kGravity * (2 * m[0] + m[1]) * std::sin(th[0]) -
       m[1] * kGravity * std::sin(th[0] - 2 * th[1]) -
       2 * std::sin(delta) * m[1] * (w[1] * w[1] * l[1] + w[0] * w[0] * l[0] * std::cos(delta))) /
      (l[0] * den);
  const double a2 =
      2 * std::sin(delta) *
      (w[0] * w[0] * l[0] * (m[0] + m[1]) + kGravity * (m[0] + m[1]) * std::cos(th[0]) +
       w[1] * w[1] * l[1] * m[1] * std::cos(delta)) /
      (l[1] * den);
  return {a1, a2};
}

Exact exact_chain(const std::vector<double>& m, const std::vector<double>& l,
                  const std::vector<double>& pivot, Eigen::Index rows, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> angle(-std::numbers::pi, std::numbers::pi), rate(-2, 2);
  const auto n = Eigen::Index(m.size());
  Exact out{MatrixD(rows, 4 * n), MatrixD(rows, 4 * n), MatrixD::Zero(rows, 2 * n)};
  for (Eigen::Index r = 0; r < rows; ++r) {
    std::vector<double> th(m.size()), w(m.size());
    for (std::size_t k = 0; k < m.size(); ++k) th[k] = angle(rng), w[k] = rate(rng);
    const std::vector<double> alpha = angular_accelerations(th, w, m, l);
    Eigen::Vector2d x(pivot[0], pivot[1]), v = Eigen::Vector2d::Zero(), a = v;
    for (Eigen::Index k = 0; k < n; ++k) {
      const double s = std::sin(th[k]), c = std::cos(th[k]), lk = l[k];
      x += lk * Eigen::Vector2d(s, -c);
      v += lk * w[k] * Eigen::Vector2d(c, s);
      a += lk * alpha[k] * Eigen::Vector2d(c, s) + lk * w[k] * w[k] * Eigen::Vector2d(-s, c);
      out.z.block(r, 2 * k, 1, 2) = x.transpose();
      out.z.block(r, 2 * n + 2 * k, 1, 2) = v.transpose();
      out.zdot.block(r, 2 * k, 1, 2) = v.transpose();
      out.zdot.block(r, 2 * n + 2 * k, 1, 2) = a.transpose();
      out.dv(r, 2 * k + 1) = kGravity * m[k];
    }
  }
  return out;
}

// A random symmetric positive definite N x N mass matrix, far from diagonal.
Eigen::MatrixXd random_mass(Eigen::Index points, unsigned seed) {
  std::mt19937_64 rng(seed);
  const Eigen::MatrixXd b = nn::random_uniform<double>(points, points, rng, -1, 1);
  return b * b.transpose() + 0.5 * Eigen::MatrixXd::Identity(points, points);
}

// A 3-point chain in 3-D with a non-diagonal mass matrix, hanging from a point off the origin.
nn::ConstraintSpec chain_3d() {
  return chain_spec({1.0, 0.7, 1.3}, 3, random_mass(3, 5), {0.2, -0.4, 0.5});
}

// A rigid triangle in 3-D (three links) whose centroid is pinned at a point (a ball joint), with a
// non-diagonal mass matrix: its points relative to the centroid.
const Eigen::Matrix3d kTriangle =
    (Eigen::Matrix3d() << -0.4, -0.3, 0, 0.6, -0.3, 0, -0.2, 0.6, 0).finished();
const std::vector<double> kPinPoint{0.1, 0.4, -0.3};

nn::ConstraintSpec pinned_triangle() {
  nn::ConstraintSpec spec;
  spec.points = 3;
  spec.dim = 3;
  spec.mass = random_mass(3, 12);
  for (auto [i, j] : {std::pair{0, 1}, {1, 2}, {0, 2}})
    spec.links.push_back({i, j, (kTriangle.row(i) - kTriangle.row(j)).norm()});
  spec.pins.push_back({{1.0 / 3, 1.0 / 3, 1.0 / 3}, kPinPoint});
  return spec;
}

// Random states of a chain_spec or of pinned_triangle on its manifold: the triangle turned at
// random about its pinned centroid, velocities random and projected onto G v = 0.
MatrixD manifold_states(const nn::ConstraintSpec& spec, Eigen::Index rows, std::uint64_t seed) {
  if (spec.pins.empty()) return nn::testing::chain_states(spec, rows, seed);
  std::mt19937_64 rng(seed);
  MatrixD z(rows, 18);
  for (Eigen::Index r = 0; r < rows; ++r) {
    const Eigen::Matrix3d turn =
        nn::random_normal<double>(3, 3, rng, 0, 1).householderQr().householderQ();
    Eigen::VectorXd x(9);
    for (int i = 0; i < 3; ++i)
      x.segment(3 * i, 3) = Eigen::Vector3d(kPinPoint.data()) + turn * kTriangle.row(i).transpose();
    const Eigen::VectorXd u = nn::random_normal<double>(9, 1, rng, 0, 1);
    z.row(r) = nn::testing::tangent_state(spec, x, u);
  }
  return z;
}

}  // namespace constrained_model_test

using namespace constrained_model_test;

TEST(ConstrainedFields, EqualTheExactMotionOfOneAndTwoLinkPendulums) {
  const std::vector<std::vector<double>> masses{{0.7}, {1.0, 2.5}}, lengths{{1.3}, {1.0, 0.6}};
  for (std::size_t c = 0; c < masses.size(); ++c) {
    const std::vector<double> pivot{0.3, -0.2};
    const Exact exact = exact_chain(masses[c], lengths[c], pivot, 16, 11 + c);
    const Eigen::VectorXd diag =
        Eigen::Map<const Eigen::VectorXd>(masses[c].data(), masses[c].size());
    const nn::ConstrainedMechanics<double> mechanics(
        chain_spec(lengths[c], 2, diag.asDiagonal(), pivot));
    ad::TapeScope scope;
    const Var<double> z = Var<double>::constant(exact.z), dv = Var<double>::constant(exact.dv);
    const MatrixD h = mechanics.hamiltonian_field(z, dv, mechanics.known_masses()).value();
    const MatrixD l = mechanics.lagrangian_field(z, dv, mechanics.known_masses()).value();
    const double scale = exact.zdot.cwiseAbs().maxCoeff();
    EXPECT_LT((h - exact.zdot).cwiseAbs().maxCoeff(), 1e-12 * scale)
        << masses[c].size() << " links";
    EXPECT_LT((l - exact.zdot).cwiseAbs().maxCoeff(), 1e-12 * scale)
        << masses[c].size() << " links";
  }
}

// A point pinned (weights (1, 0)) at the pivot with a second point on a link from it: the
// second swings as the anchored 1-link pendulum, the first stays, whatever its mass.
TEST(ConstrainedFields, APinnedPivotHoldsItsPointAndSwingsTheOther) {
  const std::vector<double> pivot{0.3, -0.2};
  const Exact one = exact_chain({0.7}, {1.3}, pivot, 16, 13);
  nn::ConstraintSpec spec;
  spec.points = 2;
  spec.dim = 2;
  spec.mass = Eigen::Vector2d(3.0, 0.7).asDiagonal();
  spec.links.push_back({0, 1, 1.3});
  spec.pins.push_back({{1.0, 0.0}, pivot});
  MatrixD z = MatrixD::Zero(16, 8), zdot = MatrixD::Zero(16, 8), dv = MatrixD::Zero(16, 4);
  z.col(0).setConstant(pivot[0]);
  z.col(1).setConstant(pivot[1]);
  for (int block : {0, 1}) {  // positions, then velocities: point 1 is the pendulum's point
    z.middleCols(4 * block + 2, 2) = one.z.middleCols(2 * block, 2);
    zdot.middleCols(4 * block + 2, 2) = one.zdot.middleCols(2 * block, 2);
  }
  dv.col(1).setConstant(kGravity * 3.0);
  dv.col(3) = one.dv.col(1);
  const nn::ConstrainedMechanics<double> mechanics(spec);
  ad::TapeScope scope;
  const Var<double> zv = Var<double>::constant(z), dvv = Var<double>::constant(dv);
  const double scale = zdot.cwiseAbs().maxCoeff();
  EXPECT_LT((mechanics.hamiltonian_field(zv, dvv, mechanics.known_masses()).value() - zdot)
                .cwiseAbs()
                .maxCoeff(),
            1e-12 * scale);
  EXPECT_LT((mechanics.lagrangian_field(zv, dvv, mechanics.known_masses()).value() - zdot)
                .cwiseAbs()
                .maxCoeff(),
            1e-12 * scale);
}

TEST(ConstrainedFields, ChnnIsTangentToTheConstraintsAtAnyState) {
  for (const nn::ConstraintSpec& spec : {chain_3d(), pinned_triangle()}) {
    std::mt19937_64 rng(3);
    const nn::ConstrainedModel<double> chnn(constrained_config(ModelKind::kChnn, spec, {16, 16}),
                                            rng);
    const MatrixD on = manifold_states(spec, 8, 4);
    const MatrixD off = on + 0.05 * nn::random_uniform<double>(8, on.cols(), rng, -1, 1);
    for (const MatrixD* states : {&on, &off}) {
      const MatrixD zdot = chnn.field(*states);
      const Eigen::Index n = spec.positions();
      for (Eigen::Index r = 0; r < states->rows(); ++r) {
        const Eigen::VectorXd x = states->row(r).head(n), v = states->row(r).tail(n);
        const Eigen::VectorXd xdot = zdot.row(r).head(n), vdot = zdot.row(r).tail(n);
        const Eigen::MatrixXd g = constraint_jacobian(spec, x),
                              gdot = constraint_jacobian(spec, v, true);
        const double scale = 1 + zdot.row(r).cwiseAbs().maxCoeff();
        EXPECT_LT((g * xdot).cwiseAbs().maxCoeff(), 1e-12 * scale) << "row " << r;
        EXPECT_LT((gdot * xdot + g * vdot).cwiseAbs().maxCoeff(), 1e-11 * scale) << "row " << r;
      }
    }
  }
}

TEST(ConstrainedFields, ClnnAcceleratesAlongTheConstraintsAtAnyState) {
  for (const nn::ConstraintSpec& spec : {chain_3d(), pinned_triangle()}) {
    std::mt19937_64 rng(6);
    const nn::ConstrainedModel<double> clnn(constrained_config(ModelKind::kClnn, spec, {16, 16}),
                                            rng);
    const MatrixD z = manifold_states(spec, 8, 7) +
                      0.05 * nn::random_uniform<double>(8, 2 * spec.positions(), rng, -1, 1);
    const MatrixD zdot = clnn.field(z);
    const Eigen::Index n = spec.positions();
    EXPECT_EQ(zdot.leftCols(n), z.rightCols(n));
    for (Eigen::Index r = 0; r < z.rows(); ++r) {
      const Eigen::VectorXd x = z.row(r).head(n), v = z.row(r).tail(n), a = zdot.row(r).tail(n);
      const Eigen::MatrixXd g = constraint_jacobian(spec, x),
                            gdot = constraint_jacobian(spec, v, true);
      EXPECT_LT((g * a + gdot * v).cwiseAbs().maxCoeff(), 1e-11 * (1 + a.cwiseAbs().maxCoeff()));
    }
  }
}

TEST(ConstrainedFields, AgreeOnTheManifoldAndConserveTheLearnedEnergy) {
  for (const nn::ConstraintSpec& spec : {chain_3d(), pinned_triangle()}) {
    std::mt19937_64 rng(8);
    const nn::DynamicsConfig config = constrained_config(ModelKind::kChnn, spec, {16, 16});
    const nn::ConstrainedModel<double> chnn(config, rng);
    nn::DynamicsConfig clnn_config = config;
    clnn_config.model = ModelKind::kClnn;
    const nn::ConstrainedModel<double> clnn(clnn_config, chnn.mlp().cast<double>());
    const MatrixD z = manifold_states(spec, 8, 9);
    const MatrixD h = chnn.field(z), l = clnn.field(z);
    EXPECT_LT((h - l).cwiseAbs().maxCoeff(), 1e-11 * (1 + h.cwiseAbs().maxCoeff()));
    const double step = 1e-5;  // dE/dt along the field, by central differences
    const MatrixD rate = (chnn.energy(z + step * h) - chnn.energy(z - step * h)) / (2 * step);
    EXPECT_LT(rate.cwiseAbs().maxCoeff(), 1e-6 * (1 + h.cwiseAbs().maxCoeff()));
  }
}

TEST(ConstrainedFields, DegenerateConstraintsNameTheRow) {
  const nn::ConstraintSpec spec =
      chain_spec({1.0, 1.0}, 2, Eigen::MatrixXd::Identity(2, 2), {0, 0});
  std::mt19937_64 rng(10);
  const nn::ConstrainedModel<double> chnn(constrained_config(ModelKind::kChnn, spec, {4}), rng);
  MatrixD z = nn::testing::chain_states(spec, 3, 11);
  z.block(1, 2, 1, 2) = z.block(1, 0, 1, 2);  // row 1: the link's two points coincide
  const std::string message = nn::testing::message_of<ad::Error>([&] { chnn.field(z); });
  EXPECT_NE(message.find("block 1 of 3 is not positive definite"), std::string::npos) << message;
}
