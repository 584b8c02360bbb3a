#include "tasks/evaluate/stretch_predictions.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "autodiff/tape.h"
#include "physics/integrator.h"
#include "tasks/evaluate/rollouts.h"

namespace hnn::tasks {

namespace {

// Whether every stretch has the first one's times after its start.
bool share_times(const std::vector<Stretch>& stretches, const Eigen::VectorXd& t0) {
  return std::all_of(stretches.begin(), stretches.end(), [&](const Stretch& s) {
    return s.t.size() == t0.size() && ((s.t.array() - s.t(0)) - t0.array()).abs().maxCoeff() < 1e-9;
  });
}

}  // namespace

Predictor dopri5_predictor(const physics::VectorField& field) {
  return [field](const Batch& x0, const Eigen::VectorXd& t) {
    const auto integrator = physics::make_integrator(
        "dopri5", {.rtol = 1e-9, .atol = 1e-12, .max_steps = kMaxLearnedSteps});
    return integrator->integrate(field, x0, {t.data(), t.data() + t.size()}).states;
  };
}

std::string StretchStepping::describe() const {
  if (!integrator) return "dopri5 (rtol 1e-9)";
  return fmt::format("{}, {} step(s) per interval", to_string(*integrator), substeps);
}

Predictor model_predictor(const nn::DynamicsModel<double>& model, const StretchStepping& stepping) {
  if (!stepping.integrator) {
    return dopri5_predictor(
        [&model](double, const Batch& x, Batch& dxdt) { dxdt = model.field(x); });
  }
  return [&model, integrator = *stepping.integrator, substeps = stepping.substeps](
             const Batch& x0, const Eigen::VectorXd& t) {
    ad::TapeScope scope;
    ad::NoGradGuard values_only;
    std::vector<Batch> states{x0};
    ad::Var<double> z = model.integrated_state(ad::Var<double>::constant(x0));
    for (Eigen::Index k = 1; k < t.size(); ++k) {
      const ad::Var<double> h =
          ad::Var<double>::constant(Batch::Constant(x0.rows(), 1, (t(k) - t(k - 1)) / substeps));
      for (int s = 0; s < substeps; ++s) z = integrator_step(model, z, h, integrator);
      states.push_back(model.observed_state(z).value());
    }
    return states;
  };
}

int PredictedPaths::failed() const {
  return int(std::count_if(failures.begin(), failures.end(),
                           [](const std::string& f) { return !f.empty(); }));
}

PredictedPaths predict_paths(const std::vector<Stretch>& stretches, const Predictor& predict,
                             bool batch) {
  PredictedPaths out;
  const Eigen::VectorXd t0 = stretches[0].t.array() - stretches[0].t(0);
  if (batch && share_times(stretches, t0)) {
    Batch x0(Eigen::Index(stretches.size()), stretches[0].x.cols());
    for (std::size_t i = 0; i < stretches.size(); ++i)
      x0.row(Eigen::Index(i)) = stretches[i].x.row(0);
    try {
      const std::vector<Batch> states = predict(x0, t0);
      for (Eigen::Index i = 0; i < x0.rows(); ++i) {
        Batch path(t0.size(), x0.cols());
        for (Eigen::Index k = 0; k < t0.size(); ++k) path.row(k) = states[std::size_t(k)].row(i);
        out.paths.push_back(std::move(path));
      }
      out.failures.assign(stretches.size(), "");
      return out;
    } catch (const std::exception&) {
      out.paths.clear();  // one at a time below, to keep the stretches that do integrate
    }
  }
  for (const Stretch& s : stretches) {
    Batch path = Batch::Constant(s.t.size(), s.x.cols(), NAN);
    std::string failure;
    try {
      const std::vector<Batch> states = predict(s.x.topRows(1), s.t.array() - s.t(0));
      for (Eigen::Index k = 0; k < s.t.size(); ++k) path.row(k) = states[std::size_t(k)].row(0);
    } catch (const std::exception& e) {
      failure = *e.what() ? e.what() : "the prediction failed";
    }
    out.paths.push_back(std::move(path));
    out.failures.push_back(std::move(failure));
  }
  return out;
}

}  // namespace hnn::tasks
