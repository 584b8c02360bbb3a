#include "physics/autodiff/autodiff_system.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <cmath>
#include <stdexcept>
#include <utility>

#include "autodiff/grad.h"
#include "autodiff/ops.h"
#include "autodiff/tape.h"

namespace hnn::physics {

namespace {

std::string value_text(double v) { return std::isnan(v) ? "NaN" : v > 0 ? "+inf" : "-inf"; }

void check_range(const std::string& system, const char* what, int column, const ValueRange& r) {
  if (!(r.lo < r.hi) || !std::isfinite(r.lo) || !std::isfinite(r.hi)) {
    throw std::invalid_argument(fmt::format("{}: {} of column {} is {}:{}; it needs finite lo < hi",
                                            system, what, column, r.lo, r.hi));
  }
}

}  // namespace

AutodiffSystem::AutodiffSystem(std::string name, int n_dof, AutodiffHamiltonian hamiltonian,
                               BoxSampling sampling)
    : name_(std::move(name)),
      n_dof_(n_dof),
      hamiltonian_(std::move(hamiltonian)),
      sampling_(std::move(sampling)) {
  if (name_.empty()) throw std::invalid_argument("AutodiffSystem: the name is empty");
  if (n_dof_ < 1) {
    throw std::invalid_argument(fmt::format(
        "{}: {} degrees of freedom; an AutodiffSystem needs at least 1", name_, n_dof_));
  }
  if (!hamiltonian_)
    throw std::invalid_argument(fmt::format("{}: the H(q, p) callable is empty", name_));
  if (sampling_.box.empty()) sampling_.box.assign(dim(), ValueRange{});
  if (int(sampling_.box.size()) != dim()) {
    throw std::invalid_argument(
        fmt::format("{}: a sampling box of {} ranges; it needs one per column ({}: q_1..q_{}, "
                    "p_1..p_{}) or none",
                    name_, sampling_.box.size(), dim(), n_dof_, n_dof_));
  }
  for (int j = 0; j < dim(); ++j) check_range(name_, "sampling range", j, sampling_.box[j]);
  if (sampling_.energy &&
      (!(sampling_.energy->lo <= sampling_.energy->hi) || !std::isfinite(sampling_.energy->lo) ||
       !std::isfinite(sampling_.energy->hi))) {
    throw std::invalid_argument(fmt::format("{}: energy band {}:{} needs finite lo <= hi", name_,
                                            sampling_.energy->lo, sampling_.energy->hi));
  }
  if (sampling_.max_draws < 1) {
    throw std::invalid_argument(
        fmt::format("{}: max_draws is {}; it needs at least 1", name_, sampling_.max_draws));
  }
  // A probe on two states: a callable that sums over the batch (1 x 1) or returns the wrong
  // columns fails here rather than at the first integration. Only shapes are checked.
  ad::TapeScope scope;
  ad::NoGradGuard values_only;
  const ad::Matrix<double> zeros = ad::Matrix<double>::Zero(2, n_dof_);
  evaluate(ad::Var<double>::constant(zeros), ad::Var<double>::constant(zeros));
}

AutodiffSystem::AutodiffSystem(std::string name, int n_dof, AutodiffHamiltonian hamiltonian,
                               StateSampler sampler)
    : AutodiffSystem(std::move(name), n_dof, std::move(hamiltonian), BoxSampling{}) {
  if (!sampler) throw std::invalid_argument(fmt::format("{}: the state sampler is empty", name_));
  sampler_ = std::move(sampler);
}

void AutodiffSystem::check_columns(const BatchView& x) const {
  if (x.cols() != dim()) {
    throw std::invalid_argument(
        fmt::format("{}: a batch of {} columns; states have {} (q_1..q_{}, "
                    "p_1..p_{})",
                    name_, x.cols(), dim(), n_dof_, n_dof_));
  }
}

ad::Var<double> AutodiffSystem::evaluate(const ad::Var<double>& q, const ad::Var<double>& p) const {
  const Eigen::Index rows = q.rows();
  ad::Var<double> h;
  try {
    h = hamiltonian_(q, p);
  } catch (const ad::Error& e) {
    throw std::invalid_argument(
        fmt::format("{}: H(q, p) failed on q and p of {}: {}", name_, q.shape(), e.what()));
  }
  if (!h.defined()) {
    throw std::invalid_argument(fmt::format("{}: H(q, p) returned an undefined Var", name_));
  }
  if (h.rows() != rows || h.cols() != 1) {
    throw std::invalid_argument(fmt::format(
        "{}: H(q, p) returned {} for q and p of {}; it must be {}x1, one H per state (row){}",
        name_, h.shape(), q.shape(), rows,
        h.rows() == 1 && h.cols() == 1
            ? " (a 1x1 result: was it summed over the batch? ad::sum_cols sums a row)"
            : ""));
  }
  return h;
}

void AutodiffSystem::check_finite(const BatchView& x, const Batch& out, const char* what) const {
  if (out.allFinite()) return;
  Eigen::Index row = 0, k = 0;
  while (std::isfinite(out(row, k))) {
    if (++k == out.cols()) k = 0, ++row;
  }
  std::vector<std::string> state;
  for (Eigen::Index j = 0; j < x.cols(); ++j) {
    state.push_back(fmt::format("{}_{} = {}", j < n_dof_ ? 'q' : 'p', j % n_dof_ + 1, x(row, j)));
  }
  throw std::invalid_argument(fmt::format("{}: {} is {} at state {} ({})", name_, what,
                                          value_text(out(row, k)), row, fmt::join(state, ", ")));
}

Eigen::VectorXd AutodiffSystem::hamiltonian_batch(const BatchView& x) const {
  check_columns(x);
  if (x.rows() == 0) return Eigen::VectorXd(0);
  ad::TapeScope scope;
  ad::NoGradGuard values_only;
  const ad::Var<double> h = evaluate(ad::Var<double>::constant(x.leftCols(n_dof_)),
                                     ad::Var<double>::constant(x.rightCols(n_dof_)));
  check_finite(x, h.value(), "H");
  return h.value().col(0);
}

Batch AutodiffSystem::gradient(const BatchView& x) const {
  check_columns(x);
  Batch dh(x.rows(), dim());
  if (x.rows() == 0) return dh;
  // Rows are independent, so d(sum_i H_i)/dx_i = dH_i/dx_i: one sweep gives every row.
  ad::TapeScope scope;
  ad::GradModeGuard record(true);
  const ad::Var<double> q = ad::Var<double>::leaf(x.leftCols(n_dof_));
  const ad::Var<double> p = ad::Var<double>::leaf(x.rightCols(n_dof_));
  const ad::Var<double> total = ad::sum(evaluate(q, p));
  if (!total.requires_grad()) {  // H depends on neither q nor p
    dh.setZero();
    return dh;
  }
  const std::vector<ad::Var<double>> d = ad::grad<double>({total}, {q, p}, {.allow_unused = true});
  dh.leftCols(n_dof_) = d[0].value();
  dh.rightCols(n_dof_) = d[1].value();
  return dh;
}

void AutodiffSystem::vector_field(const BatchView& x, Batch& dxdt) const {
  const Batch dh = gradient(x);
  dxdt.resize(x.rows(), dim());
  dxdt.leftCols(n_dof_) = dh.rightCols(n_dof_);
  dxdt.rightCols(n_dof_) = -dh.leftCols(n_dof_);
  check_finite(x, dxdt, "the field");
}

Batch AutodiffSystem::sample_box(int n, std::mt19937_64& rng) const {
  Batch x(n, dim());
  for (Eigen::Index i = 0; i < n; ++i) {
    for (int j = 0; j < dim(); ++j) {
      x(i, j) =
          std::uniform_real_distribution<double>(sampling_.box[j].lo, sampling_.box[j].hi)(rng);
    }
  }
  return x;
}

Batch AutodiffSystem::sample_initial_states(int n, std::mt19937_64& rng) const {
  if (n < 0) throw std::invalid_argument(fmt::format("{}: cannot sample {} states", name_, n));
  if (sampler_) {
    Batch x = sampler_(n, rng);
    if (x.rows() != n || x.cols() != dim()) {
      throw std::invalid_argument(
          fmt::format("{}: the state sampler returned {}x{} for {} states; it must be {}x{}", name_,
                      x.rows(), x.cols(), n, n, dim()));
    }
    return x;
  }
  if (!sampling_.energy) return sample_box(n, rng);
  constexpr int kDrawsPerRound = 1024;
  const ValueRange band = *sampling_.energy;
  Batch accepted(n, dim());
  Eigen::Index filled = 0;
  for (long draws = 0; filled < n; draws += kDrawsPerRound) {
    if (draws >= sampling_.max_draws) {
      throw std::invalid_argument(fmt::format(
          "{}: only {} of {} states with H in [{}, {}] after {} draws from the sampling box; "
          "widen the box or the band",
          name_, filled, n, band.lo, band.hi, draws));
    }
    const Batch x = sample_box(kDrawsPerRound, rng);
    Eigen::VectorXd h;
    {
      ad::TapeScope scope;
      ad::NoGradGuard values_only;
      h = evaluate(ad::Var<double>::constant(x.leftCols(n_dof_)),
                   ad::Var<double>::constant(x.rightCols(n_dof_)))
              .value()
              .col(0);
    }
    for (Eigen::Index i = 0; i < x.rows() && filled < n; ++i) {
      if (h(i) >= band.lo && h(i) <= band.hi) accepted.row(filled++) = x.row(i);  // NaN: never
    }
  }
  return accepted;
}

}  // namespace hnn::physics
