// The constrained field, its multipliers, the energy and the linearised constraints
// (constrained_system.h); the projections are in projection.cpp.
#include "physics/constrained/constrained_system.h"

#include <fmt/format.h>

#include <Eigen/Dense>
#include <cmath>
#include <stdexcept>

#include "physics/dopri5.h"

namespace hnn::physics::constrained {
namespace {

void check_spec(const ConstrainedSpec& spec) {
  const auto fail = [&](const std::string& what) {
    throw std::invalid_argument(fmt::format("constrained system '{}': {}", spec.name, what));
  };
  if (spec.points < 1 || (spec.dim != 2 && spec.dim != 3))
    fail(fmt::format("needs points >= 1 and dim 2 or 3, got {} and {}", spec.points, spec.dim));
  if (spec.mass.rows() != spec.points || spec.mass.cols() != spec.points)
    fail(fmt::format("mass matrix is {}x{}, not {}x{}", spec.mass.rows(), spec.mass.cols(),
                     spec.points, spec.points));
  if (spec.mass.llt().info() != Eigen::Success) fail("mass matrix is not positive definite");
  for (const auto& c : spec.distances)
    if (c.i < 0 || c.j < 0 || c.i >= spec.points || c.j >= spec.points || c.i == c.j)
      fail(fmt::format("distance constraint ({}, {}) names a bad point", c.i, c.j));
  for (const auto& c : spec.anchors)
    if (c.i < 0 || c.i >= spec.points || c.anchor.size() != spec.dim)
      fail(fmt::format("anchor constraint on point {} is malformed", c.i));
  for (const auto& c : spec.pins)
    if (c.weights.size() != spec.points || c.point.size() != spec.dim)
      fail("pin constraint needs one weight per point and a point of dim coordinates");
  if (!(spec.dt > 0.0) || !(spec.horizon >= spec.dt)) fail("needs 0 < dt <= horizon");
}

}  // namespace

ConstrainedSystem::ConstrainedSystem(ConstrainedSpec spec) : spec_(std::move(spec)) {
  check_spec(spec_);
  const Eigen::MatrixXd eye = Eigen::MatrixXd::Identity(spec_.dim, spec_.dim);
  mass_full_ = Eigen::MatrixXd::Zero(configuration_dim(), configuration_dim());
  for (int i = 0; i < spec_.points; ++i)
    for (int j = 0; j < spec_.points; ++j)
      mass_full_.block(i * spec_.dim, j * spec_.dim, spec_.dim, spec_.dim) = spec_.mass(i, j) * eye;
  inverse_mass_full_ =
      mass_full_.llt().solve(Eigen::MatrixXd::Identity(configuration_dim(), configuration_dim()));
}

int ConstrainedSystem::constraint_count() const {
  return static_cast<int>(spec_.distances.size() + spec_.anchors.size() +
                          spec_.pins.size() * spec_.dim);
}

std::vector<double> ConstrainedSystem::output_times() const {
  // As torch.arange(0, horizon, dt): the count is ceil(horizon / dt), the times k dt.
  const auto count = static_cast<int>(std::ceil(spec_.horizon / spec_.dt - 1e-9));
  std::vector<double> t(count);
  for (int k = 0; k < count; ++k) t[k] = k * spec_.dt;
  return t;
}

double ConstrainedSystem::potential(const double* x) const {
  double v = 0.0;
  for (const auto& term : spec_.potential) v += term->value(x);
  return v;
}

Eigen::VectorXd ConstrainedSystem::potential_gradient(const double* x) const {
  Eigen::VectorXd grad = Eigen::VectorXd::Zero(configuration_dim());
  for (const auto& term : spec_.potential) term->add_gradient(x, grad.data());
  return grad;
}

Eigen::VectorXd ConstrainedSystem::hamiltonian_batch(const BatchView& z) const {
  const int n = configuration_dim();
  Eigen::VectorXd energy(z.rows());
  for (Eigen::Index r = 0; r < z.rows(); ++r) {
    const Eigen::VectorXd v = z.row(r).segment(n, n).transpose();
    energy[r] = 0.5 * v.dot(mass_full_ * v) + potential(z.row(r).data());
  }
  return energy;
}

void ConstrainedSystem::add_distance_rows(const double* x, const double* v, Linearization& out,
                                          int& row) const {
  const int d = spec_.dim;
  // One tethered or two-point squared distance: r = x_i - (x_j or anchor), u its velocity.
  const auto add = [&](int i, int j, const double* anchor, double length) {
    // At most 3 coordinates: on the stack, not the heap (this runs in every field call). Plain
    // arrays: GCC 12 warns of out-of-bounds AVX-512 loads in Eigen's size-3-at-most vectors.
    double r[3] = {0, 0, 0}, u[3] = {0, 0, 0};
    double rr = 0, ru = 0;
    for (int k = 0; k < d; ++k) {
      r[k] = x[i * d + k] - (j >= 0 ? x[j * d + k] : anchor[k]);
      u[k] = v[i * d + k] - (j >= 0 ? v[j * d + k] : 0.0);
      rr += r[k] * r[k];
      ru += r[k] * u[k];
    }
    out.phi[row] = rr - length * length;
    out.jv[row] = 2.0 * ru;
    for (int k = 0; k < d; ++k) {
      out.jacobian(row, i * d + k) = 2.0 * r[k];
      out.h(row, i * d + k) = 2.0 * u[k];
      if (j >= 0) {
        out.jacobian(row, j * d + k) = -2.0 * r[k];
        out.h(row, j * d + k) = -2.0 * u[k];
      }
    }
    ++row;
  };
  for (const auto& c : spec_.distances) add(c.i, c.j, nullptr, c.length);
  for (const auto& c : spec_.anchors) add(c.i, -1, c.anchor.data(), c.length);
}

void ConstrainedSystem::add_pin_rows(const double* x, const double* v, Linearization& out,
                                     int& row) const {
  const int d = spec_.dim;
  for (const auto& pin : spec_.pins) {
    for (int k = 0; k < d; ++k, ++row) {
      double position = -pin.point[k], velocity = 0.0;
      for (int j = 0; j < spec_.points; ++j) {
        position += pin.weights[j] * x[j * d + k];
        velocity += pin.weights[j] * v[j * d + k];
        out.jacobian(row, j * d + k) = pin.weights[j];
      }
      out.phi[row] = position;
      out.jv[row] = velocity;  // linear: H = 0
    }
  }
}

Linearization ConstrainedSystem::linearize(const double* x, const double* v) const {
  const int c = constraint_count(), n = configuration_dim();
  Linearization out{Eigen::VectorXd(c), Eigen::VectorXd(c), Eigen::MatrixXd::Zero(c, n),
                    Eigen::MatrixXd::Zero(c, n)};
  int row = 0;
  add_distance_rows(x, v, out, row);
  add_pin_rows(x, v, out, row);
  return out;
}

Batch ConstrainedSystem::constraint_values(const Batch& z) const {
  Batch out(z.rows(), constraint_count());
  for (Eigen::Index r = 0; r < z.rows(); ++r)
    out.row(r) = linearize(&z(r, 0), &z(r, configuration_dim())).phi.transpose();
  return out;
}

Batch ConstrainedSystem::constraint_velocities(const Batch& z) const {
  Batch out(z.rows(), constraint_count());
  for (Eigen::Index r = 0; r < z.rows(); ++r)
    out.row(r) = linearize(&z(r, 0), &z(r, configuration_dim())).jv.transpose();
  return out;
}

Batch ConstrainedSystem::multipliers(const Batch& z) const {
  const int n = configuration_dim();
  Batch out(z.rows(), constraint_count());
  for (Eigen::Index r = 0; r < z.rows(); ++r) {
    const Linearization lin = linearize(&z(r, 0), &z(r, n));
    const Eigen::VectorXd v = z.row(r).segment(n, n).transpose();
    const Eigen::VectorXd free = -inverse_mass_full_ * potential_gradient(&z(r, 0));
    const Eigen::MatrixXd minv_jt = inverse_mass_full_ * lin.jacobian.transpose();
    const Eigen::MatrixXd a = lin.jacobian * minv_jt;
    out.row(r) = a.ldlt().solve(lin.jacobian * free + lin.h * v).transpose();
  }
  return out;
}

Batch ConstrainedSystem::acceleration(const Batch& z) const {
  const int n = configuration_dim();
  const Batch lambda = multipliers(z);
  Batch out(z.rows(), n);
  for (Eigen::Index r = 0; r < z.rows(); ++r) {
    const Linearization lin = linearize(&z(r, 0), &z(r, n));
    const Eigen::VectorXd force =
        -potential_gradient(&z(r, 0)) - lin.jacobian.transpose() * lambda.row(r).transpose();
    out.row(r) = (inverse_mass_full_ * force).transpose();
  }
  return out;
}

// Note [Projected form]. With the constraints G = (phi, J v) (2C of them), the peer's
// ConstrainedHamiltonianDynamics (biases/dynamics/hamiltonian.py) projects the free Hamiltonian
// field onto the tangent space of {G = 0} along the symplectic directions. In (x, v) with
// p = M v that is: x' = v + M^-1 Gv^T mu, v' = M^-1 f - M^-1 Gx^T mu, with Gx = (J; H),
// Gv = (0; J) and mu from (Gx M^-1 Gv^T - Gv M^-1 Gx^T) mu = -(Gx v + Gv M^-1 f), so that
// dG/dt = 0 exactly. On the manifold (J v = 0) it gives mu = (lambda, 0) and the field is
// (v, acceleration()); off it, phi and J v stay constant along the exact flow, so the drift
// of a numerical solution is the integrator's error alone (the multiplier form would let a
// velocity error grow phi linearly in time).
void ConstrainedSystem::vector_field(const BatchView& z, Batch& dzdt) const {
  const int n = configuration_dim();
  dzdt.resize(z.rows(), 2 * n);
  for (Eigen::Index r = 0; r < z.rows(); ++r) {
    const double* positions = z.row(r).data();  // then the velocities (rows are contiguous)
    const Linearization lin = linearize(positions, positions + n);
    const Eigen::VectorXd v = z.row(r).segment(n, n).transpose();
    const Eigen::VectorXd free = -inverse_mass_full_ * potential_gradient(positions);
    // The system for mu = (mu1, mu2) is [[0, A], [-A, B]] mu = -(J v, H v + J M^-1 f) with
    // A = J M^-1 J^T and B = H M^-1 J^T - J M^-1 H^T: two solves with A's factors.
    const Eigen::MatrixXd minv_jt = inverse_mass_full_ * lin.jacobian.transpose();
    const Eigen::MatrixXd minv_ht = inverse_mass_full_ * lin.h.transpose();
    const Eigen::LDLT<Eigen::MatrixXd> a(lin.jacobian * minv_jt);
    const Eigen::MatrixXd b = lin.h * minv_jt - lin.jacobian * minv_ht;
    const Eigen::VectorXd mu2 = a.solve(-lin.jv);
    const Eigen::VectorXd mu1 = a.solve(b * mu2 + lin.h * v + lin.jacobian * free);
    dzdt.row(r).head(n) = (v + minv_jt * mu2).transpose();
    dzdt.row(r).tail(n) = (free - minv_jt * mu1 - minv_ht * mu2).transpose();
  }
}

Batch ConstrainedSystem::sample_initial_states(int n, std::mt19937_64& rng) const {
  if (!spec_.sampler) throw std::logic_error(fmt::format("'{}' has no sampler", spec_.name));
  return spec_.sampler(*this, n, rng);
}

Trajectory simulate_constrained(const ConstrainedSystem& system, const Batch& z0,
                                const std::vector<double>& t_eval, const TruthOptions& options) {
  IntegratorOptions tolerances;
  tolerances.rtol = options.rtol;
  tolerances.atol = options.atol;
  const Dopri5 dopri5(tolerances);
  const VectorField field = system.field();
  Trajectory out;
  out.t = t_eval;
  out.states.assign(t_eval.size(), Batch(z0.rows(), z0.cols()));
  std::vector<IntegrationStats> stats(static_cast<std::size_t>(z0.rows()));
  const auto integrate_row = [&](int r) {  // writes only row r: the rows may run at once
    const Trajectory row = dopri5.integrate(field, z0.row(r), t_eval);
    for (std::size_t k = 0; k < t_eval.size(); ++k) out.states[k].row(r) = row.states[k];
    stats[static_cast<std::size_t>(r)] = row.stats;
  };
  const auto rows = static_cast<int>(z0.rows());
  if (options.parallel) {
    options.parallel(rows, integrate_row);
  } else {
    for (int r = 0; r < rows; ++r) integrate_row(r);
  }
  for (const IntegrationStats& s : stats) {
    out.stats.steps += s.steps;
    out.stats.rejected += s.rejected;
    out.stats.nfev += s.nfev;
  }
  return out;
}

ChunkSample sample_chunks(const ConstrainedSystem& system, int n, int chunk_len,
                          std::mt19937_64& rng, const TruthOptions& options) {
  const std::vector<double> times = system.output_times();
  const auto outputs = static_cast<int>(times.size());
  if (chunk_len < 1 || outputs % chunk_len != 0)
    throw std::invalid_argument(
        fmt::format("sample_chunks: '{}' has {} outputs, not a multiple "
                    "of the chunk length {}",
                    system.name(), outputs, chunk_len));
  const Trajectory full =
      simulate_constrained(system, system.sample_initial_states(n, rng), times, options);
  std::uniform_int_distribution<int> chunk(0, outputs / chunk_len - 1);
  ChunkSample out;
  out.states.assign(chunk_len, Batch(n, system.dim()));
  for (int r = 0; r < n; ++r) {
    out.first_output.push_back(chunk_len * chunk(rng));
    for (int k = 0; k < chunk_len; ++k)
      out.states[k].row(r) = full.states[out.first_output.back() + k].row(r);
  }
  return out;
}

}  // namespace hnn::physics::constrained
