#include "nn/sampled/lsqr.h"

#include <cmath>

namespace hnn::nn::sampled {

void Preconditioner::apply(const ColMat& y, ColMat& c) const {
  c = y;
  solve_upper(r, false, c);
  if (s.size() > 0) c.array().colwise() *= s.array();
}

void Preconditioner::apply_t(const ColMat& c, ColMat& y) const {
  y = c;
  if (s.size() > 0) y.array().colwise() *= s.array();
  solve_upper(r, true, y);
}

Lsqr::Lsqr(const LinearSystem& system, const Preconditioner& preconditioner, double mu)
    : a_(system),
      m_(preconditioner),
      mu_(mu),
      u_(system.equations(), system.rhs_columns()),
      av_(u_),
      u_damped_(system.unknowns(), system.rhs_columns()),
      av_damped_(u_damped_),
      v_(preconditioner.r.rows(), system.rhs_columns()),
      w_(v_),
      x_(v_),
      atu_(v_),
      c_space_(system.unknowns(), system.rhs_columns()) {}

std::size_t Lsqr::bytes() const {
  return std::size_t(u_.size() * 2 + u_damped_.size() * 3 + v_.size() * 4) * sizeof(double);
}

void Lsqr::forward(const ColMat& y) {
  m_.apply(y, c_space_);
  a_.apply(c_space_, av_);
  av_damped_ = mu_ * c_space_;
}

void Lsqr::backward(ColMat& out) {
  a_.apply_t(u_, c_space_);
  c_space_ += mu_ * u_damped_;
  m_.apply_t(c_space_, out);
}

double Lsqr::u_norm() const { return std::sqrt(u_.squaredNorm() + u_damped_.squaredNorm()); }

int Lsqr::run(ColMat& c, double tolerance, int max_iterations) {
  const BlasThreads serial(1);
  a_.apply(c, u_);
  u_ = a_.rhs() - u_;
  u_damped_ = -mu_ * c;
  double beta = u_norm();
  if (beta == 0) return 0;
  u_ /= beta;
  u_damped_ /= beta;
  backward(v_);
  double alpha = v_.norm();
  if (alpha == 0) return 0;
  v_ /= alpha;
  w_ = v_;
  x_.setZero();
  double phibar = beta, rhobar = alpha, anorm2 = 0;
  int it = 0;
  while (it < max_iterations) {
    ++it;
    forward(v_);
    u_ = av_ - alpha * u_;
    u_damped_ = av_damped_ - alpha * u_damped_;
    beta = u_norm();
    if (beta > 0) {
      u_ /= beta;
      u_damped_ /= beta;
    }
    anorm2 += alpha * alpha + beta * beta;
    backward(atu_);
    v_ = atu_ - beta * v_;
    alpha = v_.norm();
    if (alpha > 0) v_ /= alpha;
    const double rho = std::hypot(rhobar, beta), cs = rhobar / rho, sn = beta / rho;
    const double theta = sn * alpha, phi = cs * phibar;
    rhobar = -cs * alpha;
    phibar = sn * phibar;
    x_ += (phi / rho) * w_;
    w_ = v_ - (theta / rho) * w_;
    // |(A M)^T r| = phibar alpha |cs| against |A M| |r| (Paige & Saunders' test 2).
    if (alpha * std::abs(cs) <= tolerance * std::sqrt(anorm2) || alpha == 0) break;
  }
  m_.apply(x_, c_space_);
  c += c_space_;
  return it;
}

}  // namespace hnn::nn::sampled
