// Core types of the physics module: batches of states, vector fields, errors.
#pragma once

#include <Eigen/Core>
#include <functional>
#include <stdexcept>
#include <string>

namespace hnn::physics {

/// A batch of states: one row per trajectory, columns (q_1..q_n, p_1..p_n).
/// Row-major so that each state is contiguous.
using Batch = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

/// A closed interval [lo, hi].
struct ValueRange {
  double lo = -1.0;
  double hi = 1.0;
};

/// Read-only view of a batch or of a column block of one (e.g. the p half), no copy.
using BatchView = Eigen::Ref<const Batch>;

/// Writable view of a batch or of a column block of one.
using BatchSpan = Eigen::Ref<Batch>;

/// dx/dt = f(t, x) over a whole batch. `dxdt` arrives sized like `x`; the field
/// fills it. Integrators call it once per stage for all rows together.
using VectorField = std::function<void(double t, const Batch& x, Batch& dxdt)>;

/// Malformed measured data; the message names the file, the line and the reason.
class DataError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// An integration that cannot go on (non-finite state, step-size underflow,
/// implicit solve not converging). time() is the last time the state was valid.
class IntegrationError : public std::runtime_error {
 public:
  IntegrationError(const std::string& message, double time)
      : std::runtime_error(message), time_(time) {}
  double time() const { return time_; }

 private:
  double time_;
};

}  // namespace hnn::physics
