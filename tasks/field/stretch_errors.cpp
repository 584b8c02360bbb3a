// Errors along held-out stretches (stretch_errors.h).

#include "tasks/field/stretch_errors.h"

#include <algorithm>
#include <cmath>

#include "tasks/report/json_values.h"

namespace hnn::tasks {

using nlohmann::json;

namespace {

// Mean, standard deviation and standard error of the finite per-stretch values.
json spread(const std::string& name, std::vector<double> v) {
  std::erase_if(v, [](double x) { return !std::isfinite(x); });
  const double n = double(v.size());
  double mean = v.empty() ? NAN : 0, var = 0;
  for (double x : v) mean += x / n;
  for (double x : v) var += (x - mean) * (x - mean) / std::max(1.0, n - 1);
  return {{name, number(mean)},
          {name + "_std", number(std::sqrt(var))},
          {name + "_se", number(std::sqrt(var / n))}};
}

}  // namespace

std::vector<Batch> predict_paths(const std::vector<Stretch>& stretches, const Predictor& predict,
                                 int& failures) {
  const Eigen::VectorXd t0 = stretches[0].t.array() - stretches[0].t(0);
  const bool shared = std::all_of(stretches.begin(), stretches.end(), [&](const Stretch& s) {
    return s.t.size() == t0.size() && ((s.t.array() - s.t(0)) - t0.array()).abs().maxCoeff() < 1e-9;
  });
  std::vector<Batch> paths;
  if (shared) {
    Batch x0(Eigen::Index(stretches.size()), stretches[0].x.cols());
    for (std::size_t i = 0; i < stretches.size(); ++i)
      x0.row(Eigen::Index(i)) = stretches[i].x.row(0);
    try {
      const std::vector<Batch> states = predict(x0, t0);
      for (Eigen::Index i = 0; i < x0.rows(); ++i) {
        Batch path(t0.size(), x0.cols());
        for (Eigen::Index k = 0; k < t0.size(); ++k) path.row(k) = states[std::size_t(k)].row(i);
        paths.push_back(std::move(path));
      }
      return paths;
    } catch (const std::exception&) {
      paths.clear();  // one at a time below, to keep the stretches that do integrate
    }
  }
  for (const Stretch& s : stretches) {
    Batch path = Batch::Constant(s.t.size(), s.x.cols(), NAN);
    try {
      const std::vector<Batch> states = predict(s.x.topRows(1), s.t.array() - s.t(0));
      for (Eigen::Index k = 0; k < s.t.size(); ++k) path.row(k) = states[std::size_t(k)].row(0);
    } catch (const std::exception&) {
      ++failures;
    }
    paths.push_back(std::move(path));
  }
  return paths;
}

json stretch_errors(const std::string& prefix, const std::vector<Stretch>& stretches,
                    const std::vector<Batch>& paths, int per_body) {
  std::vector<double> mse, position;
  for (std::size_t i = 0; i < stretches.size(); ++i) {
    const Batch e = paths[i] - stretches[i].x;
    const Eigen::Index n = e.cols() / 2, bodies = n / per_body;
    mse.push_back(e.rows() > 1 ? e.bottomRows(e.rows() - 1).array().square().mean() : 0.0);
    if (!std::isfinite(mse.back())) mse.back() = NAN;
    double sum = 0;
    for (Eigen::Index k = 0; k < e.rows(); ++k)
      for (Eigen::Index b = 0; b < bodies; ++b)
        sum += e.row(k).segment(b * per_body, per_body).norm();
    position.push_back(std::isfinite(sum) ? sum / double(e.rows() * bodies) : NAN);
  }
  json j = spread(prefix + "state_mse", mse);
  j.update(spread(prefix + "position_error", position));
  return j;
}

}  // namespace hnn::tasks
