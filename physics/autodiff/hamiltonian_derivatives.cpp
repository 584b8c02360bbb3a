// Each system's H a second time, with the engine's ops (the formulas of oscillators.cpp,
// nbody.cpp, double_pendulum.cpp and henon_heiles.cpp), and its derivatives of any order.
#include "physics/autodiff/hamiltonian_derivatives.h"

#include <fmt/format.h>

#include <stdexcept>

#include "autodiff/functional.h"
#include "autodiff/ops.h"
#include "autodiff/tape.h"
#include "physics/double_pendulum.h"
#include "physics/expression_system.h"
#include "physics/henon_heiles.h"
#include "physics/nbody.h"
#include "physics/oscillators.h"

namespace hnn::physics {
namespace {

using V = ad::Var<double>;

V col(const V& a, Eigen::Index j) { return ad::slice_cols(a, j, 1); }

AutodiffHamiltonian nbody(const NBody& s) {
  return [masses = s.masses(), g = s.gravity()](const V& q, const V& p) {
    const Eigen::Index n = Eigen::Index(masses.size());  // q = (x_1..x_n, y_1..y_n), p alike
    const auto kinetic = [&](Eigen::Index i) {
      return (ad::square(col(p, i)) + ad::square(col(p, n + i))) / (2.0 * masses[i]);
    };
    V h = kinetic(0);
    for (Eigen::Index i = 0; i < n; ++i) {
      if (i > 0) h = h + kinetic(i);
      for (Eigen::Index j = i + 1; j < n; ++j) {
        const V r2 = ad::square(col(q, i) - col(q, j)) + ad::square(col(q, n + i) - col(q, n + j));
        h = h - (g * masses[i] * masses[j]) * ad::pow(r2, -0.5);
      }
    }
    return h;
  };
}

AutodiffHamiltonian double_pendulum(const DoublePendulum& s) {
  return [c = s.parameters()](const V& q, const V& p) {
    const V t1 = col(q, 0), t2 = col(q, 1), p1 = col(p, 0), p2 = col(p, 1);
    const V d = t1 - t2;
    const V big_d = c.m1 + c.m2 * ad::square(ad::sin(d));
    const V num = c.m2 * c.l2 * c.l2 * ad::square(p1) +
                  (c.m1 + c.m2) * c.l1 * c.l1 * ad::square(p2) -
                  2.0 * c.m2 * c.l1 * c.l2 * p1 * p2 * ad::cos(d);
    const V kinetic = num / big_d / (2.0 * c.m2 * c.l1 * c.l1 * c.l2 * c.l2);
    const double rest = c.zero == DoublePendulum::PotentialZero::kAtRest ? 1.0 : 0.0;
    return kinetic + (c.m1 + c.m2) * c.g * c.l1 * (rest - ad::cos(t1)) +
           c.m2 * c.g * c.l2 * (rest - ad::cos(t2));
  };
}

AutodiffHamiltonian henon_heiles(double alpha) {
  return [alpha](const V& q, const V& p) {
    const V q1 = col(q, 0), q2 = col(q, 1);
    return ad::sum_cols(ad::square(p) + ad::square(q)) / 2.0 +
           alpha * (ad::square(q1) * q2 - ad::pow(q2, 3.0) / 3.0);
  };
}

void check_finite(const System& system, const Batch& d, int order) {
  if (d.allFinite()) return;
  Eigen::Index row = 0;
  while (d.row(row).allFinite()) ++row;
  throw std::invalid_argument(fmt::format(
      "{}: a derivative of order {} of H is not finite at state {}", system.name(), order, row));
}

}  // namespace

std::optional<AutodiffHamiltonian> engine_hamiltonian(const System& system) {
  if (const auto* s = dynamic_cast<const Spring*>(&system))
    return [k = s->stiffness(), b = s->kinetic()](const V& q, const V& p) {
      return k * ad::square(q) + b * ad::square(p);
    };
  if (const auto* s = dynamic_cast<const Pendulum*>(&system))
    return [a = s->potential(), b = s->kinetic()](const V& q, const V& p) {
      return a * (1.0 - ad::cos(q)) + b * ad::square(p);
    };
  if (const auto* s = dynamic_cast<const NBody*>(&system)) return nbody(*s);
  if (const auto* s = dynamic_cast<const DoublePendulum*>(&system)) return double_pendulum(*s);
  if (const auto* s = dynamic_cast<const HenonHeiles*>(&system)) return henon_heiles(s->alpha());
  if (const auto* s = dynamic_cast<const AutodiffSystem*>(&system))
    return s->hamiltonian_function();
  return std::nullopt;
}

Batch hamiltonian_derivatives(const System& system, const BatchView& x, int order) {
  if (x.cols() != system.dim())
    throw std::invalid_argument(fmt::format("{}: state has {} columns, expected {}", system.name(),
                                            x.cols(), system.dim()));
  if (order < 0)
    throw std::invalid_argument(
        fmt::format("{}: derivative of order {} (0 or more)", system.name(), order));
  if (const auto* s = dynamic_cast<const ExpressionSystem*>(&system))
    return s->derivatives(x, order);
  const std::optional<AutodiffHamiltonian> h = engine_hamiltonian(system);
  if (!h)
    throw std::invalid_argument(
        fmt::format("{}: its H has no derivatives beyond the field's", system.name()));
  ad::TapeScope scope;
  ad::GradModeGuard record(true);
  const V xv = V::variable(x);
  const Eigen::Index n = x.cols() / 2;
  V y = (*h)(ad::slice_cols(xv, 0, n), ad::slice_cols(xv, n, n));
  // Rows are independent, so each row_jacobian is row r's derivative in row r's state.
  for (int k = 0; k < order; ++k)
    y = ad::row_jacobian(y, xv, {.create_graph = k + 1 < order, .allow_unused = true});
  Batch d = y.value();
  check_finite(system, d, order);
  return d;
}

}  // namespace hnn::physics
