// HenonHeiles: closed-form H and its separable field.
#include "physics/henon_heiles.h"

#include <cmath>
#include <stdexcept>

namespace hnn::physics {

HenonHeiles::HenonHeiles(double alpha, double half_width) : alpha_(alpha), half_width_(half_width) {
  if (!(alpha >= 0.0) || !std::isfinite(alpha))
    throw std::invalid_argument("HenonHeiles alpha must be finite and >= 0");
  if (!(half_width > 0.0) || !std::isfinite(half_width))
    throw std::invalid_argument("HenonHeiles half width must be finite and positive");
}

Eigen::VectorXd HenonHeiles::hamiltonian_batch(const BatchView& x) const {
  const Eigen::ArrayXd q1 = x.col(0).array(), q2 = x.col(1).array();
  const Eigen::ArrayXd kinetic = (x.col(2).array().square() + x.col(3).array().square()) / 2.0;
  const Eigen::ArrayXd potential =
      (q1.square() + q2.square()) / 2.0 + alpha_ * (q1.square() * q2 - q2.cube() / 3.0);
  return (kinetic + potential).matrix();
}

void HenonHeiles::velocity(const BatchView& p, BatchSpan dq) const { dq = p; }

void HenonHeiles::force(const BatchView& q, BatchSpan dp) const {
  const Eigen::ArrayXd q1 = q.col(0).array(), q2 = q.col(1).array();
  dp.col(0).array() = -(q1 + 2.0 * alpha_ * q1 * q2);
  dp.col(1).array() = -(q2 + alpha_ * (q1.square() - q2.square()));
}

Batch HenonHeiles::sample_initial_states(int n, std::mt19937_64& rng) const {
  return sample_box(n, std::vector<ValueRange>(4, {-half_width_, half_width_}), rng);
}

}  // namespace hnn::physics
