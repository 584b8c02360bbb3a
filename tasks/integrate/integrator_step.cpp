#include "tasks/integrate/integrator_step.h"

#include <cmath>
#include <limits>
#include <optional>
#include <type_traits>

#include "autodiff/functional.h"
#include "autodiff/grad.h"
#include "autodiff/ops.h"
#include "autodiff/tape.h"
#include "nn/enum_names.h"
#include "tasks/error.h"

namespace hnn::tasks {

namespace {

// In --help's order (tasks/options/train_options.cpp lists them).
constexpr nn::NameTable<RolloutIntegrator, 5> kIntegratorNames{{
    {RolloutIntegrator::kLeapfrog, "leapfrog"},
    {RolloutIntegrator::kYoshida4, "yoshida4"},
    {RolloutIntegrator::kMidpoint, "midpoint"},
    {RolloutIntegrator::kRk4, "rk4"},
    {RolloutIntegrator::kRk38, "rk4-38"},
}};

thread_local long t_midpoint_iterations = 0;

template <typename T>
using Var = ad::Var<T>;
template <typename T>
using Matrix = ad::Matrix<T>;

// [q | p] through a reused parts vector: an initializer list would allocate one per call, and
// a warmed-up training step allocates nothing.
template <typename T>
Var<T> join(const Var<T>& q, const Var<T>& p) {
  thread_local std::vector<Var<T>> parts(2);
  parts[0] = q;
  parts[1] = p;
  return ad::concat_cols(parts);
}

// The explicit methods take the field as any callable f(z) -> dz/dt on the tape: a model's
// integrated_derivative (integrator_step), or a known system's values (known_field_step).

// Kick-drift-kick (the file header): three field calls, each on the whole state.
template <typename T, typename Field>
Var<T> leapfrog(const Field& f, const Var<T>& x, const Var<T>& h) {
  const Eigen::Index n = x.cols() / 2;
  const Var<T> half = h * T(0.5);
  const Var<T> q = ad::slice_cols(x, 0, n);
  const Var<T> p_half = ad::slice_cols(x, n, n) + half * ad::slice_cols(f(x), n, n);
  const Var<T> q1 = q + h * ad::slice_cols(f(join(q, p_half)), 0, n);
  const Var<T> p1 = p_half + half * ad::slice_cols(f(join(q1, p_half)), n, n);
  return join(q1, p1);
}

template <typename T, typename Field>
Var<T> rk4(const Field& f, const Var<T>& x, const Var<T>& h) {
  const Var<T> half = h * T(0.5);
  const Var<T> k1 = f(x);
  const Var<T> k2 = f(x + half * k1);
  const Var<T> k3 = f(x + half * k2);
  const Var<T> k4 = f(x + h * k3);
  return x + (h * T(1.0 / 6.0)) * (k1 + T(2) * k2 + T(2) * k3 + k4);
}

// Kutta's 3/8 rule (Butcher tableau c = 0, 1/3, 2/3, 1; b = 1/8, 3/8, 3/8, 1/8): torchdiffeq's
// "rk4", which the peers train through. Fourth order as the classic one, with other error
// terms, so a model trained through one has learned to undo that one's truncation error.
template <typename T, typename Field>
Var<T> rk4_38(const Field& f, const Var<T>& x, const Var<T>& h) {
  const Var<T> third = h * T(1.0 / 3.0);
  const Var<T> k1 = f(x);
  const Var<T> k2 = f(x + third * k1);
  const Var<T> k3 = f(x + h * k2 - third * k1);
  const Var<T> k4 = f(x + h * (k1 - k2 + k3));
  return x + (h * T(1.0 / 8.0)) * (k1 + T(3) * (k2 + k3) + k4);
}

// Yoshida (1990): leapfrog steps of w1 h, w0 h and w1 h, w1 = 1 / (2 - 2^(1/3)), w0 = 1 - 2 w1.
template <typename T, typename Field>
Var<T> yoshida4(const Field& f, const Var<T>& x, const Var<T>& h) {
  const double w1 = 1.0 / (2.0 - std::cbrt(2.0)), w0 = 1.0 - 2.0 * w1;
  const Var<T> outer = h * T(w1);
  Var<T> y = leapfrog(f, x, outer);
  y = leapfrog(f, y, h * T(w0));
  return leapfrog(f, y, outer);
}

// Every method but the midpoint, whose solve needs the field's Jacobian.
template <typename T, typename Field>
Var<T> explicit_step(const Field& f, const Var<T>& x, const Var<T>& h, RolloutIntegrator method) {
  switch (method) {
    case RolloutIntegrator::kRk4:
      return rk4(f, x, h);
    case RolloutIntegrator::kRk38:
      return rk4_38(f, x, h);
    case RolloutIntegrator::kLeapfrog:
      return leapfrog(f, x, h);
    case RolloutIntegrator::kYoshida4:
      return yoshida4(f, x, h);
    case RolloutIntegrator::kMidpoint:
      break;
  }
  throw Error(fmt::format("the {} step is not explicit", to_string(method)));
}

template <typename T>
T default_tolerance() {
  return std::is_same_v<T, float> ? T(1e-5) : T(1e-12);
}

// Per row, the largest |r| / (1 + |x|); the row where it is largest.
template <typename T>
std::pair<double, Eigen::Index> worst_residual(const Matrix<T>& r, const Matrix<T>& x) {
  double worst = 0;
  Eigen::Index row = 0;
  for (Eigen::Index i = 0; i < r.rows(); ++i) {
    const double e = double((r.row(i).array().abs() / (T(1) + x.row(i).array().abs())).maxCoeff());
    if (!(e <= worst)) {  // NaN counts as the worst
      worst = e;
      row = i;
      if (std::isnan(e)) break;
    }
  }
  return {worst, row};
}

// A_r = I - (h_r / 2) J_r per row, flattened row-major (R x d^2): the matrix of the Newton
// correction.
template <typename T>
Matrix<T> newton_matrix(const Matrix<T>& jac, const Matrix<T>& h, Eigen::Index d) {
  Matrix<T> a = (jac.array().colwise() * (T(-0.5) * h.col(0).array())).matrix();
  for (Eigen::Index i = 0; i < d; ++i) a.col(i * d + i).array() += T(1);
  return a;
}

// A_r^-1 b_r per row, as values.
template <typename T>
Matrix<T> solve_rows(const Matrix<T>& a, const Matrix<T>& b) {
  ad::TapeScope scope;
  ad::NoGradGuard values;
  return ad::batched_solve(Var<T>::constant(a), Var<T>::constant(b)).value();
}

// A row whose residual grew (Newton from a poor guess or with a stale Jacobian, a diverging
// fixed-point iteration: h L / 2 > 1) goes back to its last accepted iterate, and its Newton
// steps are halved; a row that improved is accepted and its steps doubled back towards full.
// Not near the rounding floor, where residuals wander. True when some row went back.
template <typename T>
bool backtrack_rows(const Matrix<T>& residual, T tolerance, int it, Matrix<T>& x1,
                    Matrix<T>& accepted, Eigen::VectorXd& accepted_norm,
                    Eigen::Matrix<T, Eigen::Dynamic, 1>& damping) {
  bool backtracked = false;
  for (Eigen::Index r = 0; r < x1.rows(); ++r) {
    const double norm =
        double((residual.row(r).array().abs() / (T(1) + x1.row(r).array().abs())).maxCoeff());
    if (norm > accepted_norm(r) && norm > 100 * double(tolerance)) {
      x1.row(r) = accepted.row(r);
      damping(r) *= T(0.5);
      backtracked = true;
    } else {
      if (it > 0) damping(r) = std::min(T(1), T(2) * damping(r));
      accepted.row(r) = x1.row(r);
      accepted_norm(r) = norm;
    }
  }
  return backtracked;
}

// Note [Midpoint on the tape]
// x1* solves x1 = x0 + h f((x0 + x1)/2) off the tape. On the tape goes one Newton correction
// from it, x1 = x1* - A^-1 F with F = x1* - x0 - h f(m), m = (x0 + x1*)/2, x1* a constant and
// A = I - (h/2) df/dx(m) a constant. F ~ 0, so A's own derivative (times F) vanishes and
//   dx1 = A^-1 ((I + hJ/2) dx0 + h df/dtheta dtheta),
// the implicit function theorem's derivative of the converged map, at the cost of one field
// call and one Jacobian, whatever the number of iterations the solve took.
template <typename T>
Var<T> midpoint(const nn::DynamicsModel<T>& model, const Var<T>& x, const Var<T>& h,
                const MidpointSolve& solve) {
  const Matrix<T> x1 = midpoint_solve(model, x.value(), h.value(), solve);
  if (!ad::grad_enabled()) return Var<T>::constant(x1);
  const Var<T> x1c = Var<T>::constant(x1);
  const Var<T> m = (x + x1c) * T(0.5);
  const Var<T> residual = x1c - x - h * model.integrated_derivative(m);
  const Matrix<T> a = newton_matrix<T>(field_row_jacobian(model, m.value()), h.value(), x.cols());
  return x1c - ad::batched_solve(Var<T>::constant(a), residual);
}

}  // namespace

std::string_view to_string(RolloutIntegrator integrator) {
  return nn::name_of(kIntegratorNames, integrator);
}

std::vector<std::string> rollout_integrator_names() { return nn::names_of(kIntegratorNames); }

RolloutIntegrator parse_rollout_integrator(std::string_view name) {
  if (const std::optional<RolloutIntegrator> i = nn::find_name(kIntegratorNames, name)) return *i;
  throw Error(fmt::format("the rollout loss's integrator '{}' is not one of {}", name,
                          nn::join_names(kIntegratorNames)));
}

long midpoint_iterations() { return t_midpoint_iterations; }

template <typename T>
Matrix<T> field_row_jacobian(const nn::DynamicsModel<T>& model, const Matrix<T>& x) {
  ad::TapeScope scope;
  ad::GradModeGuard recording(true);
  const Var<T> xv = Var<T>::leaf(x);
  // Rows are independent samples: row r of f depends on row r of x only.
  return ad::row_jacobian(model.integrated_derivative(xv), xv, {.allow_unused = true}).value();
}

template <typename T>
Matrix<T> midpoint_solve(const nn::DynamicsModel<T>& model, const Matrix<T>& x0, const Matrix<T>& h,
                         const MidpointSolve& solve) {
  const T tolerance = solve.tolerance > 0 ? T(solve.tolerance) : default_tolerance<T>();
  const auto step = [&](const Matrix<T>& f) -> Matrix<T> {
    return x0 + (f.array().colwise() * h.col(0).array()).matrix();
  };
  Matrix<T> x1 = step(model.integrated_field(x0));  // explicit Euler: the first guess
  Matrix<T> accepted = x1;  // per row, the last iterate that did not raise its residual
  Eigen::VectorXd accepted_norm = Eigen::VectorXd::Constant(x0.rows(), INFINITY);
  Eigen::Matrix<T, Eigen::Dynamic, 1> damping =
      Eigen::Matrix<T, Eigen::Dynamic, 1>::Ones(x0.rows());
  double previous = std::numeric_limits<double>::infinity();
  bool newton = false;
  Matrix<T> a;  // A of the chord iterations, refreshed when they slow down
  std::pair<double, Eigen::Index> worst{0, 0};
  for (int it = 0; it <= solve.max_iterations; ++it) {
    const Matrix<T> m = (x0 + x1) * T(0.5);
    const Matrix<T> next = step(model.integrated_field(m));
    const Matrix<T> residual = x1 - next;
    worst = worst_residual<T>(residual, x1);
    if (worst.first <= double(tolerance)) return x1;
    if (it == solve.max_iterations) break;
    ++t_midpoint_iterations;
    const bool backtracked =
        backtrack_rows<T>(residual, tolerance, it, x1, accepted, accepted_norm, damping);
    if (backtracked) {
      newton = true;
      a.resize(0, 0);
      continue;
    }
    // Fixed-point iteration while it contracts fast; then Newton's chord method (the Jacobian
    // kept while the residual falls at least fourfold per iteration: a Jacobian costs one
    // backward sweep per state column, a chord iteration one field call).
    const double ratio = worst.first / previous;
    if (!newton && it > 0 && ratio > 0.25) newton = true;
    if (newton) {
      if (a.size() == 0 || ratio > 0.25)
        a = newton_matrix<T>(field_row_jacobian(model, m), h, x0.cols());
      x1 -= (solve_rows<T>(a, residual).array().colwise() * damping.array()).matrix();
    } else {
      x1 = next;
    }
    previous = worst.first;
  }
  throw Error(fmt::format(
      "the implicit midpoint step did not converge: row {} keeps a residual of {:.3g} (tolerance "
      "{:.1g}) after {} iterations; a smaller --dt helps",
      worst.second, worst.first, double(tolerance), solve.max_iterations));
}

template <typename T>
Var<T> integrator_step(const nn::DynamicsModel<T>& model, const Var<T>& x, const Var<T>& h,
                       RolloutIntegrator method, const MidpointSolve& solve) {
  if (method == RolloutIntegrator::kMidpoint) return midpoint(model, x, h, solve);
  return explicit_step([&](const Var<T>& z) { return model.integrated_derivative(z); }, x, h,
                       method);
}

Matrix<double> known_field_step(const KnownField& field, const Matrix<double>& x,
                                const Matrix<double>& h, RolloutIntegrator method) {
  HNN_TASKS_CHECK(method != RolloutIntegrator::kMidpoint,
                  "a known field is not stepped by the implicit midpoint: its solve needs the "
                  "field's Jacobian");
  ad::TapeScope scope;
  ad::NoGradGuard values_only;
  const auto f = [&](const Var<double>& z) {
    Matrix<double> dz;
    field(z.value(), dz);
    return Var<double>::constant(dz);
  };
  return explicit_step(f, Var<double>::constant(x), Var<double>::constant(h), method).value();
}

#define HNN_INSTANTIATE(T)                                                                   \
  template Var<T> integrator_step(const nn::DynamicsModel<T>&, const Var<T>&, const Var<T>&, \
                                  RolloutIntegrator, const MidpointSolve&);                  \
  template Matrix<T> midpoint_solve(const nn::DynamicsModel<T>&, const Matrix<T>&,           \
                                    const Matrix<T>&, const MidpointSolve&);                 \
  template Matrix<T> field_row_jacobian(const nn::DynamicsModel<T>&, const Matrix<T>&);
HNN_INSTANTIATE(float)
HNN_INSTANTIATE(double)
#undef HNN_INSTANTIATE

}  // namespace hnn::tasks
