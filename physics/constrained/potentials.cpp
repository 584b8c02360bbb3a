// Gravity, springs and magnet dipoles as potential terms (potentials.h).
#include "physics/constrained/potentials.h"

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <unsupported/Eigen/AutoDiff>

namespace hnn::physics::constrained {
namespace {

class GravityTerm : public PotentialTerm {
 public:
  GravityTerm(Eigen::VectorXd weights, int dim, int axis, double g)
      : weights_(std::move(weights)), dim_(dim), axis_(axis), g_(g) {
    if (axis < 0 || axis >= dim) throw std::invalid_argument("gravity: axis out of range");
  }
  double value(const double* x) const override {
    double v = 0.0;
    for (Eigen::Index i = 0; i < weights_.size(); ++i) v += weights_[i] * x[i * dim_ + axis_];
    return g_ * v;
  }
  void add_gradient(const double*, double* grad) const override {
    for (Eigen::Index i = 0; i < weights_.size(); ++i) grad[i * dim_ + axis_] += g_ * weights_[i];
  }

 private:
  Eigen::VectorXd weights_;
  int dim_, axis_;
  double g_;
};

class SpringTerm : public PotentialTerm {
 public:
  SpringTerm(std::vector<Spring> list, int dim) : list_(std::move(list)), dim_(dim) {}
  double value(const double* x) const override {
    double v = 0.0;
    for (const Spring& s : list_) {
      const double stretch = distance(x, s) - s.rest;
      v += 0.5 * s.stiffness * stretch * stretch;
    }
    return v;
  }
  // dV/dx_i = k (|r| - rest) r / |r| with r = x_i - x_j, and the opposite on x_j.
  void add_gradient(const double* x, double* grad) const override {
    for (const Spring& s : list_) {
      const double r = distance(x, s);
      const double scale = s.stiffness * (r - s.rest) / r;
      for (int k = 0; k < dim_; ++k) {
        const double component = scale * (x[s.i * dim_ + k] - x[s.j * dim_ + k]);
        grad[s.i * dim_ + k] += component;
        grad[s.j * dim_ + k] -= component;
      }
    }
  }

 private:
  double distance(const double* x, const Spring& s) const {
    double r2 = 0.0;
    for (int k = 0; k < dim_; ++k) {
      const double diff = x[s.i * dim_ + k] - x[s.j * dim_ + k];
      r2 += diff * diff;
    }
    return std::sqrt(r2);
  }
  std::vector<Spring> list_;
  int dim_;
};

class DipoleTerm : public PotentialTerm {
 public:
  DipoleTerm(double q, Eigen::MatrixXd positions, Eigen::MatrixXd moments)
      : q_(q), positions_(std::move(positions)), moments_(std::move(moments)) {
    if (positions_.cols() != 3 || moments_.cols() != 3 || positions_.rows() != moments_.rows())
      throw std::invalid_argument("magnet_dipoles: positions and moments must be magnets x 3");
  }
  double value(const double* x) const override { return energy(Eigen::Vector3d(x[0], x[1], x[2])); }
  void add_gradient(const double* x, double* grad) const override {
    using Dual = Eigen::AutoDiffScalar<Eigen::Vector3d>;
    Eigen::Matrix<Dual, 3, 1> r0;
    for (int k = 0; k < 3; ++k) r0[k] = Dual(x[k], 3, k);
    const Dual v = energy(r0);
    for (int k = 0; k < 3; ++k) grad[k] += v.derivatives()[k];
  }

 private:
  template <class S>
  S energy(const Eigen::Matrix<S, 3, 1>& r0) const {
    using std::sqrt;  // and Eigen's for the dual numbers, by argument-dependent lookup
    const Eigen::Matrix<S, 3, 1> m0 = r0 * (S(q_) / r0.squaredNorm());
    S total(0.0);
    for (Eigen::Index i = 0; i < positions_.rows(); ++i) {
      const Eigen::Matrix<S, 3, 1> mi = moments_.row(i).transpose().cast<S>();
      const Eigen::Matrix<S, 3, 1> s = positions_.row(i).transpose().cast<S>() - r0;
      const S s2 = s.squaredNorm();
      const S numerator = -3.0 * m0.dot(s) * mi.dot(s) - s2 * m0.dot(mi);
      total += numerator / (4.0 * std::numbers::pi * s2 * s2 * sqrt(s2));
    }
    return total;
  }
  double q_;
  Eigen::MatrixXd positions_, moments_;
};

}  // namespace

std::shared_ptr<const PotentialTerm> gravity(Eigen::VectorXd weights, int dim, int axis, double g) {
  return std::make_shared<GravityTerm>(std::move(weights), dim, axis, g);
}

std::shared_ptr<const PotentialTerm> springs(std::vector<Spring> list, int dim) {
  return std::make_shared<SpringTerm>(std::move(list), dim);
}

std::shared_ptr<const PotentialTerm> magnet_dipoles(double q, Eigen::MatrixXd positions,
                                                    Eigen::MatrixXd moments) {
  return std::make_shared<DipoleTerm>(q, std::move(positions), std::move(moments));
}

}  // namespace hnn::physics::constrained
