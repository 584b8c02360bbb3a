// System and SeparableSystem: the shared parts (single-state wrappers, field
// callables, assembling a separable field).
#include "physics/system.h"

#include <fmt/format.h>

#include <memory>

namespace hnn::physics {

double System::hamiltonian(const Eigen::Ref<const Eigen::RowVectorXd>& x) const {
  return hamiltonian_batch(Batch(x))(0);
}

double System::energy(const Eigen::Ref<const Eigen::RowVectorXd>& x) const {
  return energy_batch(Batch(x))(0);
}

std::optional<Batch> System::exact_flow(const Batch&, double) const { return std::nullopt; }

VectorField System::field() const {
  return [this](double, const Batch& x, Batch& dxdt) {
    if (x.cols() != dim()) {
      throw std::invalid_argument(
          fmt::format("{}: state has {} columns, expected {}", name(), x.cols(), dim()));
    }
    vector_field(x, dxdt);
  };
}

Batch sample_box(int n, const std::vector<ValueRange>& box, std::mt19937_64& rng) {
  Batch x(n, Eigen::Index(box.size()));
  for (Eigen::Index i = 0; i < x.rows(); ++i) {
    for (Eigen::Index j = 0; j < x.cols(); ++j) {
      const ValueRange& r = box[std::size_t(j)];
      x(i, j) = std::uniform_real_distribution<double>(r.lo, r.hi)(rng);
    }
  }
  return x;
}

SplitField split_field(const VectorField& f) {
  // The scratch full derivative is shared by both halves; each call refills it.
  auto full = std::make_shared<Batch>();
  auto half = [f, full](double t, const Batch& x, Batch& out, bool q_half) {
    full->resize(x.rows(), x.cols());
    f(t, x, *full);
    const Eigen::Index n = x.cols() / 2;
    out = q_half ? full->leftCols(n) : full->rightCols(n);
  };
  return {[half](double t, const Batch& x, Batch& dq) { half(t, x, dq, true); },
          [half](double t, const Batch& x, Batch& dp) { half(t, x, dp, false); }};
}

void SeparableSystem::vector_field(const BatchView& x, Batch& dxdt) const {
  const Eigen::Index n = x.cols() / 2;
  dxdt.resize(x.rows(), x.cols());
  velocity(x.rightCols(n), dxdt.leftCols(n));
  force(x.leftCols(n), dxdt.rightCols(n));
}

SplitField SeparableSystem::split() const {
  return {[this](double, const Batch& x, Batch& dq) {
            const Eigen::Index n = x.cols() / 2;
            dq.resize(x.rows(), n);
            velocity(x.rightCols(n), dq);
          },
          [this](double, const Batch& x, Batch& dp) {
            const Eigen::Index n = x.cols() / 2;
            dp.resize(x.rows(), n);
            force(x.leftCols(n), dp);
          }};
}

}  // namespace hnn::physics
