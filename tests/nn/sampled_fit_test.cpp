// The sampled fit (nn/sampled/): hidden layers sampled, the last layer by least squares.

#include "nn/sampled/sampled_fit.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <random>

#include "malloc_counter.h"
#include "nn/hnn.h"

namespace hnn::nn {
namespace {

// States uniform in a box with the exact field of a system, and its H.
struct Problem {
  Matrix<double> x, dxdt;
  std::function<double(double, double)> energy;
};

// The pendulum H = p^2 / 2 + (1 - cos q), q in [-pi, pi], p in [-1, 1]; with `damping`, a
// friction term -damping p in dp/dt (a dissipative field for the D-HNN).
Problem pendulum(int n, std::uint64_t seed, double damping = 0) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> q(-M_PI, M_PI), p(-1, 1);
  Problem out{Matrix<double>(n, 2), Matrix<double>(n, 2),
              [](double qq, double pp) { return pp * pp / 2 + 1 - std::cos(qq); }};
  for (int i = 0; i < n; ++i) {
    out.x(i, 0) = q(rng);
    out.x(i, 1) = p(rng);
    out.dxdt(i, 0) = out.x(i, 1);
    out.dxdt(i, 1) = -std::sin(out.x(i, 0)) - damping * out.x(i, 1);
  }
  return out;
}

// `data` with Gaussian noise of standard deviation `sigma` added to its dx/dt.
Problem with_noise(Problem data, double sigma, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0, sigma);
  for (Index i = 0; i < data.dxdt.size(); ++i) data.dxdt.data()[i] += noise(rng);
  return data;
}

DynamicsConfig model_config(ModelKind kind, std::vector<Index> hidden) {
  DynamicsConfig c;
  c.model = kind;
  c.dim = 2;
  c.hidden = std::move(hidden);
  if (kind == ModelKind::kDhnn) c.field = FieldType::kBoth;
  return c;
}

template <typename T>
std::unique_ptr<DynamicsModel<T>> fitted(const DynamicsConfig& c, const Problem& data,
                                         SampledFitConfig fit = {}) {
  std::mt19937_64 rng(1);
  auto model = make_model<T>(c, rng);
  fit_sampled(*model, data.x, data.dxdt, fit);
  return model;
}

// The field's relative L2 error on held-out points.
template <typename T>
double field_error(const DynamicsModel<T>& model, const Problem& test) {
  const Matrix<double> f = model.field(test.x.cast<T>()).template cast<double>();
  const double e = (f - test.dxdt).norm() / test.dxdt.norm();
  return e;
}

// H's largest error on held-out points after the best constant shift.
double energy_error(const Hnn<double>& model, const Problem& test) {
  const Matrix<double> h = model.energy(test.x);
  Eigen::VectorXd diff(test.x.rows());
  for (Index i = 0; i < test.x.rows(); ++i)
    diff(i) = h(i, 0) - test.energy(test.x(i, 0), test.x(i, 1));
  const double e = std::sqrt((diff.array() - diff.mean()).square().mean());
  return e;
}

// A width-100 HNN fitted to 300 pendulum points.
std::unique_ptr<DynamicsModel<double>> pendulum_hnn(const SampledFitConfig& fit) {
  return fitted<double>(model_config(ModelKind::kHnn, {100}), pendulum(300, 2), fit);
}

// Relative L2 errors on held-out points (a width-100 HNN on 300 points reaches about 2e-3 in
// the field, like the peer's numpy U-SWIM on the same data); LSQR reproduces dgelsd's solution,
// the regularised normal equations fall short of it; ridge (Tikhonov at mu = rcond sigma_max)
// is as close to it.
TEST(SampledFit, HnnMatchesThePendulumFieldAndEnergy) {
  const Problem test = pendulum(200, 3);
  std::vector<double> errors;
  for (LeastSquaresSolver solver : {LeastSquaresSolver::kQr, LeastSquaresSolver::kLsqr,
                                    LeastSquaresSolver::kCholesky, LeastSquaresSolver::kRidge}) {
    // the peer's scale and cutoff
    auto model = pendulum_hnn({.swim_scale = kPeerSwimScale, .rcond = 1e-13, .solver = solver});
    errors.push_back(field_error(*model, test));
    EXPECT_LT(errors.back(), 3e-2) << name_of(kLeastSquaresSolverNames, solver);
    EXPECT_LT(energy_error(dynamic_cast<Hnn<double>&>(*model), test), 3e-3);
  }
  EXPECT_LT(errors[0], 1e-2);
  EXPECT_NEAR(errors[1], errors[0], 1e-2 * errors[0]);
  EXPECT_NEAR(errors[3], errors[0], 0.2 * errors[0]);
}

TEST(SampledFit, EverySamplerFits) {
  const Problem test = pendulum(200, 3);
  const double elm = field_error(*pendulum_hnn({.sampler = HiddenSampler::kElm}), test);
  const double uswim = field_error(*pendulum_hnn({.sampler = HiddenSampler::kUswim}), test);
  const double aswim = field_error(*pendulum_hnn({.sampler = HiddenSampler::kAswim}), test);
  EXPECT_LT(elm, 1e-2);
  EXPECT_LT(uswim, 1e-2);
  EXPECT_LT(aswim, uswim);  // A-SWIM's resampling helps here (3e-4 against 2.4e-3)
}

// A-SWIM's first fit only weights the pairs of the second: at a fifth of the width (the default)
// it weights them about as well as at the full width (the peer's), and the model keeps its width.
TEST(SampledFit, AswimsFirstFitMayBeNarrower) {
  const Problem test = pendulum(200, 3);
  const double uswim = field_error(*pendulum_hnn({.sampler = HiddenSampler::kUswim}), test);
  for (double fraction : {0.2, 1.0}) {
    auto model = pendulum_hnn({.sampler = HiddenSampler::kAswim, .aswim_first_fraction = fraction});
    EXPECT_LT(field_error(*model, test), uswim) << "first fit at " << fraction << " of the width";
    EXPECT_EQ(model->config().hidden, pendulum_hnn({})->config().hidden);
  }
}

TEST(SampledFit, BaselineMatchesTheField) {
  const Problem train = pendulum(300, 2), test = pendulum(200, 3);
  auto model = fitted<double>(model_config(ModelKind::kBaseline, {100}), train);
  EXPECT_LT(field_error(*model, test), 1e-5);
}

TEST(SampledFit, DhnnMatchesADampedPendulum) {
  const Problem train = pendulum(300, 2, 0.3), test = pendulum(200, 3, 0.3);
  auto model = fitted<double>(model_config(ModelKind::kDhnn, {100}), train);
  EXPECT_LT(field_error(*model, test), 5e-4);
}

TEST(SampledFit, TwoHiddenLayersAndAnglesFit) {
  const Problem train = pendulum(300, 2), test = pendulum(200, 3);
  auto deep = fitted<double>(model_config(ModelKind::kHnn, {100, 100}), train);
  EXPECT_LT(field_error(*deep, test), 0.15);  // 0.05: the second layer does not help here
  DynamicsConfig angled = model_config(ModelKind::kHnn, {100});
  angled.angles = 1;
  EXPECT_LT(field_error(*fitted<double>(angled, train), test), 2e-3);  // 5.7e-4
}

TEST(SampledFit, FloatModelGetsTheWeights) {
  const Problem train = pendulum(300, 2), test = pendulum(200, 3);
  auto single = fitted<float>(model_config(ModelKind::kHnn, {100}), train);
  auto twin = fitted<double>(model_config(ModelKind::kHnn, {100}), train);
  EXPECT_LT(field_error(*single, test), 3e-2);
  const Matrix<double> w = single->mlp().layers()[1].weight().value().cast<double>();
  EXPECT_LT((w - twin->mlp().layers()[1].weight().value()).norm(), 1e-5 * w.norm());
}

TEST(SampledFit, RefusesWhatItCannotFit) {
  const Problem train = pendulum(300, 2);
  auto refuses = [&](const DynamicsConfig& c, const Problem& data, const char* what) {
    std::mt19937_64 rng(1);
    auto model = make_model<double>(c, rng);
    try {
      fit_sampled(*model, data.x, data.dxdt, {});
      ADD_FAILURE() << "no error, expected: " << what;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
  };
  DynamicsConfig lnn = model_config(ModelKind::kLnn, {20});
  refuses(lnn, train, "not linear in the last layer");
  Problem three = pendulum(300, 2);  // three distinct points, each a hundred times
  for (Index i = 3; i < 300; ++i) three.x.row(i) = three.x.row(i % 3);
  refuses(model_config(ModelKind::kHnn, {250}), three, "distinct point pairs");
  refuses(model_config(ModelKind::kBaseline, {80}), pendulum(60, 2), "unknowns");
  // An HNN's equations are the points times the field's coordinates: 120 here.
  refuses(model_config(ModelKind::kHnn, {121}), pendulum(60, 2),
          "121 last-layer unknowns per output but only 120 equations from 60 points");
  refuses(model_config(ModelKind::kHnn, {}), train, "no hidden layer to sample");
  Problem bad = train;
  bad.dxdt(7, 1) = std::nan("");
  refuses(model_config(ModelKind::kHnn, {20}), bad, "dxdt row 7 column 1 is not finite");
}

// Every point the same, relu neurons drawn at random: some are off at that point, so their
// columns are zero.
TEST(SampledFit, SingularSystemIsRefused) {
  Problem same = pendulum(300, 2);
  same.x.setConstant(0.5);
  DynamicsConfig relu = model_config(ModelKind::kHnn, {20});
  relu.activation = Activation::kRelu;
  std::mt19937_64 rng(1);
  auto model = make_model<double>(relu, rng);
  const Matrix<double> before = model->mlp().layers()[1].weight().value();
  for (LeastSquaresSolver solver : {LeastSquaresSolver::kQr, LeastSquaresSolver::kLsqr,
                                    LeastSquaresSolver::kCholesky, LeastSquaresSolver::kRidge}) {
    try {
      fit_sampled(*model, same.x, same.dxdt, {.sampler = HiddenSampler::kElm, .solver = solver});
      ADD_FAILURE() << "a singular system was solved";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("singular"), std::string::npos) << e.what();
    }
  }
  EXPECT_EQ(model->mlp().layers()[1].weight().value(), before);  // nothing written
}

// --rcond auto (nn/sampled/rcond_choice.h): on exact derivatives the held-out error keeps
// falling to the smallest cutoffs; on noisy ones a fit that keeps the small singular values
// interpolates the noise, and a large cutoff wins.
TEST(SampledFit, AutoRcondIsLargeOnNoisyDataAndSmallOnExactData) {
  const Problem exact = pendulum(300, 2);
  const Problem noisy = with_noise(exact, 0.1, 5);
  const auto chosen = [](const Problem& data) {
    std::mt19937_64 init(1);
    auto model = make_model<double>(model_config(ModelKind::kHnn, {100}), init);
    return fit_sampled(*model, data.x, data.dxdt, {});
  };
  const SampledFitReport on_exact = chosen(exact), on_noisy = chosen(noisy);
  EXPECT_LE(on_exact.rcond, 1e-9);
  EXPECT_GE(on_noisy.rcond, 1e-5);
  ASSERT_EQ(on_noisy.rcond_validation.size(), 14u);  // 1e-14 ... 1e-1
  EXPECT_DOUBLE_EQ(on_noisy.rcond_validation.front().rcond, 1e-14);
  for (std::size_t i = 1; i < on_noisy.rcond_validation.size(); ++i) {
    const RcondTrial &smaller = on_noisy.rcond_validation[i - 1], &t = on_noisy.rcond_validation[i];
    EXPECT_LE(t.rank, smaller.rank);
    if (t.rcond == on_noisy.rcond) {  // the smallest held-out error
      for (const RcondTrial& other : on_noisy.rcond_validation) EXPECT_GE(other.error, t.error);
    }
  }
  EXPECT_GT(on_noisy.validation_seconds, 0);
}

// ridge's auto walks the ladder from the smallest cutoff and stops where the held-out error
// passes a hundred times the best: on exact derivatives after a few cutoffs, on noisy ones at a
// large cutoff; then it refits at the chosen one.
TEST(SampledFit, RidgeAutoRcondWalksTheLadderFromTheSmallest) {
  const Problem exact = pendulum(300, 2);
  const Problem noisy = with_noise(exact, 0.1, 5);
  const SampledFitConfig ridge{.solver = LeastSquaresSolver::kRidge};
  std::mt19937_64 init(1);
  auto on_exact = make_model<double>(model_config(ModelKind::kHnn, {100}), init);
  auto on_noisy = make_model<double>(model_config(ModelKind::kHnn, {100}), init);
  auto refit = make_model<double>(model_config(ModelKind::kHnn, {100}), init);
  const SampledFitReport exact_report = fit_sampled(*on_exact, exact.x, exact.dxdt, ridge);
  const SampledFitReport noisy_report = fit_sampled(*on_noisy, noisy.x, noisy.dxdt, ridge);
  EXPECT_LE(exact_report.rcond, 1e-9);
  EXPECT_GE(noisy_report.rcond, 1e-5);
  const std::vector<RcondTrial>& walked = exact_report.rcond_validation;
  ASSERT_GE(walked.size(), 2u);
  EXPECT_LT(walked.size(), 14u);  // stopped early
  EXPECT_DOUBLE_EQ(walked.front().rcond, 1e-14);
  double best = walked.front().error;
  for (std::size_t i = 0; i + 1 < walked.size(); ++i) {
    best = std::min(best, walked[i].error);
    EXPECT_LE(walked[i].error, 100 * best);  // the walk went on
  }
  EXPECT_GT(walked.back().error, 100 * best);  // and stopped there
  fit_sampled(*refit, noisy.x, noisy.dxdt, {.rcond = noisy_report.rcond, .solver = ridge.solver});
  EXPECT_EQ(refit->mlp().layers()[1].weight().value(),
            on_noisy->mlp().layers()[1].weight().value());
}

// After the choice the fit runs again on every point at the chosen cutoff: the same weights as
// an explicit --rcond of that value (the hidden layers' draws do not see the split); the
// baseline (several outputs, a formed matrix) alike.
TEST(SampledFit, AutoRcondRefitsOnEveryPointAtTheChosenCutoff) {
  const Problem data = with_noise(pendulum(300, 2), 0.05, 7);
  for (ModelKind kind : {ModelKind::kHnn, ModelKind::kBaseline}) {
    std::mt19937_64 init(1);
    auto automatic = make_model<double>(model_config(kind, {60}), init);
    auto explicit_model = make_model<double>(model_config(kind, {60}), init);
    const SampledFitReport report = fit_sampled(*automatic, data.x, data.dxdt, {});
    EXPECT_EQ(report.rcond_validation.size(), 14u);
    fit_sampled(*explicit_model, data.x, data.dxdt, {.rcond = report.rcond});
    for (Index layer : {0, 1}) {
      EXPECT_EQ(automatic->mlp().layers()[layer].weight().value(),
                explicit_model->mlp().layers()[layer].weight().value())
          << to_string(kind) << " layer " << layer;
    }
  }
}

// With one held-out fold (10,000 points or more) the validation's two halves, merged, are the
// whole problem's triangle: the refit reduces nothing again, and fits as an explicit --rcond of
// the chosen value does, up to rounding.
TEST(SampledFit, AutoRcondReusesTheFoldsTriangleForTheRefit) {
  const Problem data = with_noise(pendulum(10000, 2), 0.01, 7);
  for (LeastSquaresSolver solver : {LeastSquaresSolver::kQr, LeastSquaresSolver::kRidge}) {
    for (ModelKind kind : {ModelKind::kHnn, ModelKind::kBaseline}) {
      std::mt19937_64 init(1);
      auto automatic = make_model<double>(model_config(kind, {40}), init);
      auto explicit_model = make_model<double>(model_config(kind, {40}), init);
      const SampledFitReport report =
          fit_sampled(*automatic, data.x, data.dxdt, {.solver = solver});
      fit_sampled(*explicit_model, data.x, data.dxdt, {.rcond = report.rcond, .solver = solver});
      const Matrix<double> a = automatic->field(data.x), b = explicit_model->field(data.x);
      EXPECT_LT((a - b).norm(), 1e-7 * b.norm()) << to_string(kind) << " " << int(solver);
      EXPECT_LT((a - data.dxdt).norm(), 0.1 * data.dxdt.norm()) << to_string(kind);
    }
  }
}

// auto holds out points: one point leaves none to hold out.
TEST(SampledFit, AutoRcondNeedsTwoPoints) {
  const Problem one = pendulum(1, 2);
  std::mt19937_64 init(1);
  auto model = make_model<double>(model_config(ModelKind::kHnn, {1}), init);
  try {
    fit_sampled(*model, one.x, one.dxdt, {.sampler = HiddenSampler::kElm});
    ADD_FAILURE() << "one point was validated";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("needs at least 2, got 1; give --rcond"),
              std::string::npos)
        << e.what();
  }
  EXPECT_NO_THROW(
      fit_sampled(*model, one.x, one.dxdt, {.sampler = HiddenSampler::kElm, .rcond = 1e-13}));
}

// A regularisation above the retries' cap (1e-6) is used as given.
TEST(SampledFit, RegularizationAboveTheCapIsUsed) {
  const Problem train = pendulum(300, 2);
  std::mt19937_64 init(1);
  auto model = make_model<double>(model_config(ModelKind::kHnn, {60}), init);
  const SampledFitReport report =
      fit_sampled(*model, train.x, train.dxdt,
                  {.solver = LeastSquaresSolver::kCholesky, .regularization = 1e-3});
  EXPECT_EQ(report.regularization, 1e-3);
}

// The fit allocates its matrices once: LSQR's iterations allocate nothing, so a fit of 25
// iterations makes as many allocations as one of 5.
TEST(SampledFit, LsqrIterationsAllocateNothing) {
  if (!HNN_COUNTS_ALLOCATIONS) GTEST_SKIP() << "allocations are not counted here";
  const Problem train = pendulum(300, 2);
  for (LeastSquaresSolver solver : {LeastSquaresSolver::kLsqr, LeastSquaresSolver::kSketch}) {
    auto allocations = [&](int iterations) {
      std::mt19937_64 rng(1);
      auto model = make_model<double>(model_config(ModelKind::kHnn, {60}), rng);
      const SampledFitConfig fit{.swim_scale = kPeerSwimScale,  // no walk: one fit
                                 .rcond = 1e-12,
                                 .solver = solver,
                                 .tolerance = 0,
                                 .max_iterations = iterations};
      const long before = hnn::testing::allocation_count();
      const SampledFitReport report = fit_sampled(*model, train.x, train.dxdt, fit);
      EXPECT_EQ(report.iterations, iterations);
      return hnn::testing::allocation_count() - before;
    };
    allocations(5);  // warms up the engine's and OpenBLAS's threads
    EXPECT_EQ(allocations(25), allocations(5)) << int(solver);
  }
}

// The sketch solver fits as ridge does (the same problem, solved iteratively from a sketch's QR
// instead of the whole data's), given or with --rcond auto's walk.
TEST(SampledFit, SketchFitsAsRidgeDoes) {
  const Problem train = pendulum(3000, 2), test = pendulum(1000, 3);
  for (ModelKind kind : {ModelKind::kHnn, ModelKind::kBaseline}) {
    for (std::optional<double> rcond : {std::optional<double>(1e-10), std::optional<double>()}) {
      std::mt19937_64 init(1);
      auto ridge = make_model<double>(model_config(kind, {100}), init);
      auto sketch = make_model<double>(model_config(kind, {100}), init);
      // the peer's scale: no scale walk
      const SampledFitConfig fit{.swim_scale = kPeerSwimScale, .rcond = rcond};
      SampledFitConfig ridge_fit = fit, sketch_fit = fit;
      ridge_fit.solver = LeastSquaresSolver::kRidge;
      sketch_fit.solver = LeastSquaresSolver::kSketch;
      const SampledFitReport ridge_report = fit_sampled(*ridge, train.x, train.dxdt, ridge_fit);
      const SampledFitReport sketch_report = fit_sampled(*sketch, train.x, train.dxdt, sketch_fit);
      EXPECT_EQ(sketch_report.solver, "sketch");
      EXPECT_GT(sketch_report.iterations, 0);
      // The same cutoff, or, where the walk's held-out errors tie to rounding (the smallest
      // cutoffs often do), one whose error under ridge is ridge's best to 1e-4.
      EXPECT_EQ(sketch_report.rcond_validation.size(), ridge_report.rcond_validation.size());
      const auto ridge_error_at = [&](double at) {
        for (const RcondTrial& trial : ridge_report.rcond_validation) {
          if (trial.rcond == at) return trial.error;
        }
        return at == ridge_report.rcond ? 0.0 : std::numeric_limits<double>::infinity();
      };
      EXPECT_NEAR(ridge_error_at(sketch_report.rcond), ridge_error_at(ridge_report.rcond),
                  1e-4 * ridge_error_at(ridge_report.rcond))
          << to_string(kind) << ": sketch chose " << sketch_report.rcond << ", ridge "
          << ridge_report.rcond;
      const double ridge_error = field_error(*ridge, test),
                   sketch_error = field_error(*sketch, test);
      EXPECT_LT(ridge_error, 1e-3) << to_string(kind);
      EXPECT_NEAR(sketch_error, ridge_error, 0.05 * ridge_error)
          << to_string(kind) << " rcond " << sketch_report.rcond << (rcond ? " given" : " auto");
    }
  }
}

}  // namespace
}  // namespace hnn::nn
