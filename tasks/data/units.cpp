#include "tasks/data/units.h"

#include <cmath>

#include "tasks/error.h"

namespace hnn::tasks {

Batch Units::to_model(const Batch& x) const {
  return ((x.rowwise() - mean).array().rowwise() / scale.array()).matrix();
}

Batch Units::to_file(const Batch& z) const {
  return (z.array().rowwise() * scale.array()).matrix().rowwise() + mean;
}

Batch Units::rate_to_model(const Batch& dxdt) const {
  return (dxdt.array().rowwise() * (time / scale.array())).matrix();
}

Batch Units::rate_to_file(const Batch& dzdt) const {
  return (dzdt.array().rowwise() * (scale.array() / time)).matrix();
}

double Units::energy_to_file() const {
  const Eigen::Index n = scale.size() / 2;
  return n > 0 ? scale(0) * scale(n) / time : 1.0;
}

Dataset Units::to_model(const Dataset& d) const {
  return {to_model(d.train_x), rate_to_model(d.train_dxdt), to_model(d.test_x),
          rate_to_model(d.test_dxdt)};
}

nlohmann::json Units::to_json() const {
  return {{"mean", std::vector<double>(mean.data(), mean.data() + mean.size())},
          {"scale", std::vector<double>(scale.data(), scale.data() + scale.size())},
          {"time", time}};
}

Units fit_units(const Dataset& data, Eigen::Index coordinates,
                const std::vector<std::string>& names) {
  const Batch& x = data.train_x;
  const Eigen::Index dim = x.cols();
  HNN_TASKS_CHECK(x.rows() >= 2 && dim == 2 * coordinates && Eigen::Index(names.size()) == dim,
                  "units: {} training rows of {} columns for {} coordinates and {} names", x.rows(),
                  dim, coordinates, names.size());
  Units u;
  u.mean = x.colwise().mean();
  u.scale = ((x.rowwise() - u.mean).colwise().squaredNorm() / double(x.rows() - 1)).cwiseSqrt();
  for (Eigen::Index c = 0; c < dim; ++c) {
    HNN_TASKS_CHECK(u.scale(c) > 0 && std::isfinite(u.scale(c)),
                    "column '{}' is constant over the training split: nothing to learn from it",
                    names[std::size_t(c)]);
  }
  // One product c for every (q_i, p_i): the geometric mean of their products.
  double log_c = 0;
  for (Eigen::Index i = 0; i < coordinates; ++i)
    log_c += std::log(u.scale(i) * u.scale(coordinates + i));
  const double c = std::exp(log_c / double(coordinates));
  for (Eigen::Index i = 0; i < coordinates; ++i) {
    const double factor = std::sqrt(c / (u.scale(i) * u.scale(coordinates + i)));
    u.scale(i) *= factor;
    u.scale(coordinates + i) *= factor;
  }
  const double rms =
      std::sqrt((data.train_dxdt.array().rowwise() / u.scale.array()).square().mean());
  HNN_TASKS_CHECK(rms > 0 && std::isfinite(rms),
                  "dx/dt is zero (or not finite) over the whole training split: nothing moves");
  u.time = 1 / rms;
  return u;
}

Units identity_units(Eigen::Index dim) {
  return {Eigen::RowVectorXd::Zero(dim), Eigen::RowVectorXd::Ones(dim), 1.0};
}

}  // namespace hnn::tasks
