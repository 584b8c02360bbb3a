// DoublePendulum: closed-form H, Hamilton's equations and the velocity map.
#include "physics/double_pendulum.h"

#include <cmath>
#include <numbers>
#include <stdexcept>

namespace hnn::physics {

DoublePendulum::DoublePendulum(double m1, double m2, double l1, double l2, double g,
                               PotentialZero zero)
    : m1_(m1), m2_(m2), l1_(l1), l2_(l2), g_(g), zero_(zero) {
  for (double v : {m1, m2, l1, l2, g}) {
    if (!(v > 0.0) || !std::isfinite(v)) {
      throw std::invalid_argument("DoublePendulum masses, lengths and g must be positive");
    }
  }
}

// With d = theta1 - theta2 and D = m1 + m2 sin^2 d (det M = m2 l1^2 l2^2 D):
// T = N / (2 m2 l1^2 l2^2 D), N = m2 l2^2 p1^2 + (m1+m2) l1^2 p2^2 - 2 m2 l1 l2 p1 p2 cos d.
Eigen::VectorXd DoublePendulum::hamiltonian_batch(const BatchView& x) const {
  const Eigen::ArrayXd t1 = x.col(0).array(), t2 = x.col(1).array(), p1 = x.col(2).array(),
                       p2 = x.col(3).array();
  const Eigen::ArrayXd d = t1 - t2;
  const Eigen::ArrayXd big_d = m1_ + m2_ * d.sin().square();
  const Eigen::ArrayXd num = m2_ * l2_ * l2_ * p1.square() + (m1_ + m2_) * l1_ * l1_ * p2.square() -
                             2.0 * m2_ * l1_ * l2_ * p1 * p2 * d.cos();
  const Eigen::ArrayXd kinetic = num / (2.0 * m2_ * l1_ * l1_ * l2_ * l2_ * big_d);
  const double rest = zero_ == PotentialZero::kAtRest ? 1.0 : 0.0;
  const Eigen::ArrayXd potential =
      (m1_ + m2_) * g_ * l1_ * (rest - t1.cos()) + m2_ * g_ * l2_ * (rest - t2.cos());
  return (kinetic + potential).matrix();
}

// dp1/dt = -dV/dtheta1 - dT/dd with dT/dd = C1 - C2, C1 = p1 p2 sin d / (l1 l2 D),
// C2 = N sin 2d / (2 l1^2 l2^2 D^2); dp2/dt = -dV/dtheta2 + dT/dd.
void DoublePendulum::vector_field(const BatchView& x, Batch& dxdt) const {
  const Eigen::ArrayXd t1 = x.col(0).array(), t2 = x.col(1).array(), p1 = x.col(2).array(),
                       p2 = x.col(3).array();
  const Eigen::ArrayXd d = t1 - t2, c = d.cos(), s = d.sin();
  const Eigen::ArrayXd big_d = m1_ + m2_ * s.square();
  const Eigen::ArrayXd num = m2_ * l2_ * l2_ * p1.square() + (m1_ + m2_) * l1_ * l1_ * p2.square() -
                             2.0 * m2_ * l1_ * l2_ * p1 * p2 * c;
  const Eigen::ArrayXd c1 = p1 * p2 * s / (l1_ * l2_ * big_d);
  const Eigen::ArrayXd c2 = num * (2.0 * d).sin() / (2.0 * l1_ * l1_ * l2_ * l2_ * big_d.square());
  dxdt.resize(x.rows(), 4);
  dxdt.col(0).array() = (l2_ * p1 - l1_ * p2 * c) / (l1_ * l1_ * l2_ * big_d);
  dxdt.col(1).array() =
      ((m1_ + m2_) * l1_ * p2 - m2_ * l2_ * p1 * c) / (m2_ * l1_ * l2_ * l2_ * big_d);
  dxdt.col(2).array() = -(m1_ + m2_) * g_ * l1_ * t1.sin() - c1 + c2;
  dxdt.col(3).array() = -m2_ * g_ * l2_ * t2.sin() + c1 - c2;
}

Batch DoublePendulum::momenta_from_velocities(const Batch& v) const {
  const Eigen::ArrayXd c = (v.col(0) - v.col(1)).array().cos();
  const Eigen::ArrayXd w1 = v.col(2).array(), w2 = v.col(3).array();
  Batch x = v;
  x.col(2).array() = (m1_ + m2_) * l1_ * l1_ * w1 + m2_ * l1_ * l2_ * c * w2;
  x.col(3).array() = m2_ * l2_ * l2_ * w2 + m2_ * l1_ * l2_ * c * w1;
  return x;
}

Batch DoublePendulum::velocities_from_momenta(const Batch& x) const {
  Batch dxdt;
  vector_field(x, dxdt);  // dtheta/dt = M^-1 p is the first half of the field
  Batch v = x;
  v.col(2) = dxdt.col(0);
  v.col(3) = dxdt.col(1);
  return v;
}

Batch DoublePendulum::sample_initial_states(int n, std::mt19937_64& rng) const {
  std::uniform_real_distribution<double> angle(-std::numbers::pi / 2, std::numbers::pi / 2);
  std::uniform_real_distribution<double> rate(-1.0, 1.0);
  Batch v(n, 4);
  for (int i = 0; i < n; ++i) {
    v(i, 0) = angle(rng);
    v(i, 1) = angle(rng);
    v(i, 2) = rate(rng);
    v(i, 3) = rate(rng);
  }
  return momenta_from_velocities(v);
}

}  // namespace hnn::physics

namespace hnn::physics {

DoublePendulumVelocities::DoublePendulumVelocities(double m1, double m2, double l1, double l2,
                                                   double g)
    : m1_(m1), m2_(m2), l1_(l1), l2_(l2), g_(g), canonical_(m1, m2, l1, l2, g) {}

Eigen::VectorXd DoublePendulumVelocities::hamiltonian_batch(const BatchView& x) const {
  const Eigen::ArrayXd t1 = x.col(0).array(), t2 = x.col(1).array(), w1 = x.col(2).array(),
                       w2 = x.col(3).array();
  const Eigen::ArrayXd kinetic = 0.5 * (m1_ + m2_) * l1_ * l1_ * w1.square() +
                                 0.5 * m2_ * l2_ * l2_ * w2.square() +
                                 m2_ * l1_ * l2_ * w1 * w2 * (t1 - t2).cos();
  const Eigen::ArrayXd potential =
      (m1_ + m2_) * g_ * l1_ * (1.0 - t1.cos()) + m2_ * g_ * l2_ * (1.0 - t2.cos());
  return (kinetic + potential).matrix();
}

// M(theta) alpha = f(theta, omega), M's rows normalised by their diagonals: alpha1 + a1 alpha2 =
// f1 and a2 alpha1 + alpha2 = f2, solved in closed form (1 - a1 a2 = m1 / (m1 + m2 sin^2 d) > 0).
void DoublePendulumVelocities::vector_field(const BatchView& x, Batch& dxdt) const {
  const Eigen::ArrayXd t1 = x.col(0).array(), t2 = x.col(1).array(), w1 = x.col(2).array(),
                       w2 = x.col(3).array();
  const Eigen::ArrayXd d = t1 - t2, c = d.cos(), s = d.sin();
  const double mu = m2_ / (m1_ + m2_);
  const Eigen::ArrayXd a1 = (l2_ / l1_) * mu * c, a2 = (l1_ / l2_) * c;
  const Eigen::ArrayXd f1 = -(l2_ / l1_) * mu * w2.square() * s - (g_ / l1_) * t1.sin();
  const Eigen::ArrayXd f2 = (l1_ / l2_) * w1.square() * s - (g_ / l2_) * t2.sin();
  const Eigen::ArrayXd det = 1.0 - a1 * a2;
  dxdt.resize(x.rows(), 4);
  dxdt.col(0) = x.col(2);
  dxdt.col(1) = x.col(3);
  dxdt.col(2).array() = (f1 - a1 * f2) / det;
  dxdt.col(3).array() = (f2 - a2 * f1) / det;
}

Batch DoublePendulumVelocities::sample_initial_states(int n, std::mt19937_64& rng) const {
  std::uniform_real_distribution<double> angle(0.0, 2.0 * std::numbers::pi), speed(0.0, 0.1);
  Batch x(n, 4);
  for (int i = 0; i < n; ++i) x.row(i) << angle(rng), angle(rng), speed(rng), speed(rng);
  return x;
}

}  // namespace hnn::physics
