// The constraint manifold's states (constrained_system.h): why a state is off it, the
// M-weighted Gauss-Newton projection the floor and `hnn rollout --project` use, and the peer's
// joint Euclidean one its samplers use.
#include <fmt/format.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "physics/constrained/constrained_system.h"

namespace hnn::physics::constrained {

namespace {

// Whether |value| exceeds tol on a scale of at least 1.
bool off(double value, double scale, double tol) {
  return !(std::abs(value) <= tol * std::max(1.0, scale));
}

}  // namespace

std::string ConstrainedSystem::state_problem(const double* z, double tol) const {
  const int d = spec_.dim;
  // linearize's rows: one per rod (phi = |r|^2 - l^2, J v = 2 r . u), then d per pin (its
  // offset from the pivot and its velocity, an axis each).
  const Linearization lin = linearize(z, z + configuration_dim());
  const double speeds =
      Eigen::Map<const Eigen::VectorXd>(z + configuration_dim(), configuration_dim()).norm();
  int row = 0;
  const auto rod = [&](const std::string& ends, double length) -> std::string {
    const double distance = std::sqrt(std::max(0.0, lin.phi[row] + length * length));
    const double stretch = distance > 0 ? lin.jv[row] / (2 * distance) : 0.0;
    ++row;
    if (off(distance - length, length, tol))
      return fmt::format("{} are {:.6g} apart, their rod is {:.6g} long", ends, distance, length);
    if (off(stretch, speeds, tol))
      return fmt::format("{} move apart at {:.3g} a time unit, along a rod of fixed length", ends,
                         stretch);
    return "";
  };
  for (const auto& c : spec_.distances) {
    const auto ends = fmt::format("points {} and {}", std::min(c.i, c.j), std::max(c.i, c.j));
    if (std::string p = rod(ends, c.length); !p.empty()) return p;
  }
  for (const auto& c : spec_.anchors) {
    if (std::string p = rod(fmt::format("point {} and its anchor", c.i), c.length); !p.empty())
      return p;
  }
  for (std::size_t n = 0; n < spec_.pins.size(); ++n, row += d) {
    const double offset = lin.phi.segment(row, d).norm(), speed = lin.jv.segment(row, d).norm();
    if (off(offset, spec_.pins[n].point.norm(), tol))
      return fmt::format("pinned point {} is {:.3g} from its pivot", n, offset);
    if (off(speed, speeds, tol))
      return fmt::format("pinned point {} moves at {:.3g}, held at its pivot", n, speed);
  }
  return "";
}

Batch ConstrainedSystem::project(const Batch& z) const {
  constexpr int kMaxSteps = 50;
  const int n = configuration_dim();
  Batch out = z;
  for (Eigen::Index r = 0; r < out.rows(); ++r) {
    double* x = &out(r, 0);
    double* v = &out(r, n);
    Eigen::Map<Eigen::VectorXd> xs(x, n), vs(v, n);
    const double tol = 1e-13 * (1.0 + xs.squaredNorm());
    Linearization lin = linearize(x, v);
    int step = 0;
    // Gauss-Newton of least M-norm: the smallest kinetic-metric move that zeroes phi to first
    // order; it converges quadratically from a state near the manifold.
    for (; lin.phi.lpNorm<Eigen::Infinity>() > tol; ++step) {
      if (step == kMaxSteps || !lin.phi.allFinite())
        throw std::runtime_error(fmt::format(
            "project: '{}' row {} still off the manifold by {:.3g} after {} Gauss-Newton steps",
            spec_.name, r, lin.phi.lpNorm<Eigen::Infinity>(), step));
      const Eigen::MatrixXd minv_jt = inverse_mass_full_ * lin.jacobian.transpose();
      xs -= minv_jt * (lin.jacobian * minv_jt).ldlt().solve(lin.phi);
      lin = linearize(x, v);
    }
    // Velocities: the M-orthogonal projection onto the tangent space J v = 0.
    const Eigen::MatrixXd minv_jt = inverse_mass_full_ * lin.jacobian.transpose();
    vs -= minv_jt * (lin.jacobian * minv_jt).ldlt().solve(lin.jacobian * vs);
  }
  return out;
}

Batch ConstrainedSystem::project_peer(const Batch& z, double tol) const {
  constexpr int kMaxSteps = 500;
  const int n = configuration_dim(), c = constraint_count();
  Batch out = z;
  for (int step = 0;; ++step) {
    // The peer's norms are over the whole batch: RMS violation and RMS state size.
    double violation = 0.0;
    std::vector<Linearization> lins;
    lins.reserve(out.rows());
    for (Eigen::Index r = 0; r < out.rows(); ++r) {
      lins.push_back(linearize(&out(r, 0), &out(r, n)));
      violation += lins.back().phi.squaredNorm() + lins.back().jv.squaredNorm();
    }
    violation = std::sqrt(violation / static_cast<double>(2 * c * out.rows()));
    if (violation < tol) return out;
    if (step == kMaxSteps || !std::isfinite(violation))
      throw std::runtime_error(
          fmt::format("project_peer: '{}' still off the manifold by {:.3g} (RMS) after {} steps",
                      spec_.name, violation, step));
    const double half_scale = 0.5 * std::sqrt(out.squaredNorm() / static_cast<double>(out.size()));
    for (Eigen::Index r = 0; r < out.rows(); ++r) {
      const Linearization& lin = lins[r];
      Eigen::MatrixXd k = Eigen::MatrixXd::Zero(2 * c, 2 * n);
      k.topLeftCorner(c, n) = lin.jacobian;
      k.bottomLeftCorner(c, n) = lin.h;
      k.bottomRightCorner(c, n) = lin.jacobian;
      Eigen::VectorXd g(2 * c);
      g << lin.phi, lin.jv;
      const Eigen::VectorXd delta = -k.transpose() * (k * k.transpose()).ldlt().solve(g);
      out.row(r) += delta.cwiseMax(-half_scale).cwiseMin(half_scale).transpose();
    }
  }
}

}  // namespace hnn::physics::constrained
