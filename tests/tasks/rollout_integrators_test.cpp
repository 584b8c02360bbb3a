// The rollout loss's integrators on the tape (tasks/integrate/integrator_step.h): their orders on
// known systems, energy over long runs, and the implicit midpoint's gradient against finite
// differences of the converged (off-tape) map.

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <random>

#include "autodiff/grad.h"
#include "autodiff/ops.h"
#include "autodiff/tape.h"
#include "nn/hnn.h"
#include "tasks/error.h"
#include "tasks/integrate/integrator_step.h"

namespace hnn::tasks {
namespace {

using Var = ad::Var<double>;
using Matrix = ad::Matrix<double>;

// A "model" whose field is written by hand with the engine's ops.
class KnownFieldModel : public nn::DynamicsModel<double> {
 public:
  using Fn = std::function<Var(const Var&)>;
  explicit KnownFieldModel(Fn f) : DynamicsModel(config(), mlp()), f_(std::move(f)) {}
  Var time_derivative(const Var& x) const override { return f_(x); }
  Matrix field(const ad::MatrixView<double>& x) const override {
    ad::TapeScope scope;
    ad::NoGradGuard values;
    return f_(Var::constant(x)).value();
  }

 private:
  static nn::DynamicsConfig config() {
    return {.model = nn::ModelKind::kBaseline, .dim = 2, .hidden = {2}};
  }
  static nn::Mlp<double> mlp() {
    std::mt19937_64 rng(0);
    return nn::Mlp<double>(nn::mlp_config(config()), rng);
  }
  Fn f_;
};

Var q_of(const Var& x) { return ad::slice_cols(x, 0, 1); }
Var p_of(const Var& x) { return ad::slice_cols(x, 1, 1); }

// H = (q^2 + p^2) / 2.
KnownFieldModel spring() {
  return KnownFieldModel([](const Var& x) { return ad::concat_cols<double>({p_of(x), -q_of(x)}); });
}
// H = p^2 / 2 + 1 - cos q.
KnownFieldModel pendulum() {
  return KnownFieldModel([](const Var& x) {
    return ad::concat_cols<double>({p_of(x), -ad::sin(q_of(x))});
  });
}
// H = (q^2 + p^2) / 2 + q^2 p^2 / 2: not separable.
KnownFieldModel coupled() {
  return KnownFieldModel([](const Var& x) {
    const Var q = q_of(x), p = p_of(x);
    return ad::concat_cols<double>({p + q * q * p, -(q + q * p * p)});
  });
}

Matrix run(const nn::DynamicsModel<double>& model, RolloutIntegrator method, Matrix x, double h,
           int steps) {
  ad::TapeScope scope;
  ad::NoGradGuard values;
  const Var hv = Var::constant(Matrix::Constant(x.rows(), 1, h));
  Var v = Var::constant(x);
  for (int i = 0; i < steps; ++i) v = integrator_step(model, v, hv, method);
  return v.value();
}

// The global error at t = 1 with n and 2n steps: log2 of their ratio estimates the order.
double measured_order(const nn::DynamicsModel<double>& model, RolloutIntegrator method, int n) {
  const Matrix x0{{0.7, 0.4}};
  const Matrix exact = run(model, RolloutIntegrator::kRk4, x0, 1.0 / 4096, 4096);
  const double coarse = (run(model, method, x0, 1.0 / n, n) - exact).norm();
  const double fine = (run(model, method, x0, 0.5 / n, 2 * n) - exact).norm();
  return std::log2(coarse / fine);
}

TEST(RolloutIntegrators, HaveTheirOrdersOnSeparableSystems) {
  for (const KnownFieldModel& model : {spring(), pendulum()}) {
    EXPECT_NEAR(measured_order(model, RolloutIntegrator::kLeapfrog, 16), 2.0, 0.15);
    EXPECT_NEAR(measured_order(model, RolloutIntegrator::kMidpoint, 16), 2.0, 0.15);
    EXPECT_NEAR(measured_order(model, RolloutIntegrator::kYoshida4, 8), 4.0, 0.3);
    EXPECT_NEAR(measured_order(model, RolloutIntegrator::kRk4, 8), 4.0, 0.3);
    EXPECT_NEAR(measured_order(model, RolloutIntegrator::kRk38, 8), 4.0, 0.3);
  }
}

// Kutta's 3/8 rule (torchdiffeq's "rk4") by its tableau, one step of the pendulum's field by
// hand; on a nonlinear field it is not the classic RK4.
TEST(RolloutIntegrators, TheThreeEighthsRuleIsKuttasTableau) {
  const KnownFieldModel model = pendulum();
  const Matrix x0{{0.9, -0.3}};
  const double h = 0.2;
  const auto f = [&](const Matrix& x) { return model.field(x); };
  const Matrix k1 = f(x0), k2 = f(x0 + h / 3 * k1), k3 = f(x0 + h * (k2 - k1 / 3)),
               k4 = f(x0 + h * (k1 - k2 + k3));
  const Matrix want = x0 + h / 8 * (k1 + 3 * k2 + 3 * k3 + k4);
  const Matrix got = run(model, RolloutIntegrator::kRk38, x0, h, 1);
  EXPECT_LT((got - want).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_GT((got - run(model, RolloutIntegrator::kRk4, x0, h, 1)).cwiseAbs().maxCoeff(), 1e-7);
}

// Not separable: the midpoint keeps order 2 and RK4 order 4; the explicit kick-drift-kick drops
// to order 1 (tasks/integrate/integrator_step.h), and Yoshida's composition of it with it.
TEST(RolloutIntegrators, OnANonSeparableFieldLeapfrogIsFirstOrder) {
  const KnownFieldModel model = coupled();
  EXPECT_NEAR(measured_order(model, RolloutIntegrator::kMidpoint, 16), 2.0, 0.15);
  EXPECT_NEAR(measured_order(model, RolloutIntegrator::kRk4, 8), 4.0, 0.3);
  EXPECT_NEAR(measured_order(model, RolloutIntegrator::kRk38, 8), 4.0, 0.3);
  EXPECT_NEAR(measured_order(model, RolloutIntegrator::kLeapfrog, 64), 1.0, 0.15);
  EXPECT_NEAR(measured_order(model, RolloutIntegrator::kYoshida4, 64), 1.0, 0.2);
}

// H = (q^2 + p^2)/2 over 2000 steps of h = 0.5 (160 periods): the symplectic methods keep the
// energy error bounded, without trend; RK4's energy decays steadily.
TEST(RolloutIntegrators, SymplecticOnesConserveAQuadraticEnergyWhereRk4Drifts) {
  const KnownFieldModel model = spring();
  const auto energy = [](const Matrix& x) { return 0.5 * x.squaredNorm(); };
  const Matrix x0{{1.0, 0.0}};
  for (RolloutIntegrator method : {RolloutIntegrator::kLeapfrog, RolloutIntegrator::kYoshida4,
                                   RolloutIntegrator::kMidpoint, RolloutIntegrator::kRk4}) {
    Matrix x = x0;
    double early = 0, late = 0;
    for (int block = 0; block < 20; ++block) {
      for (int i = 0; i < 100; ++i) {
        x = run(model, method, x, 0.5, 1);
        const double error = std::abs(energy(x) - 0.5) / 0.5;
        (block < 2 ? early : late) = std::max(block < 2 ? early : late, error);
      }
    }
    const std::string name(to_string(method));
    if (method == RolloutIntegrator::kRk4) {
      EXPECT_GT(late, 0.2) << name;  // (1 - h^6/72)^2000: about 0.35
    } else {
      EXPECT_LT(late, 0.1) << name;
      EXPECT_LT(late, 1.5 * early + 1e-9) << name;
    }
  }
  // The midpoint rule conserves a quadratic H exactly, up to its solve's tolerance.
  EXPECT_NEAR(energy(run(model, RolloutIntegrator::kMidpoint, x0, 0.5, 2000)), 0.5, 1e-8);
}

// L = sum(w * x1) through one midpoint step of a small HNN (a learned, non-separable H): its
// gradient in x0 and in a weight against central differences of the converged map.
TEST(RolloutIntegrators, MidpointGradientMatchesFiniteDifferencesOfTheConvergedMap) {
  std::mt19937_64 rng(5);
  auto model =
      nn::make_model<double>({.model = nn::ModelKind::kHnn, .dim = 2, .hidden = {16, 16}}, rng);
  const Matrix x0{{0.6, -0.3}, {-0.2, 0.9}};
  const Matrix h{{0.4}, {0.3}};
  const Matrix w{{1.0, -2.0}, {0.5, 1.5}};
  const auto loss = [&](const Matrix& x) {
    return (w.array() * midpoint_solve(*model, x, h, {.tolerance = 1e-14}).array()).sum();
  };
  Matrix dx0;
  double dweight = 0;
  ad::Var<double>* weight = nullptr;
  model->visit_parameters([&](const std::string& name, ad::Var<double>& p) {
    if (name == "mlp.layers.1.weight") weight = &p;
  });
  ASSERT_NE(weight, nullptr);
  {
    ad::TapeScope scope;
    const Var x = Var::leaf(x0);
    const Var x1 = integrator_step(*model, x, Var::constant(h), RolloutIntegrator::kMidpoint,
                                   {.tolerance = 1e-14});
    const Var l = ad::sum(Var::constant(w) * x1);
    const std::vector<Var> g = ad::grad<double>({l}, {x, *weight});
    dx0 = g[0].value();
    dweight = g[1].value()(3, 2);
  }
  EXPECT_GT(dx0.norm(), 0.5);  // not trivially zero: about I + h df/dx
  EXPECT_GT(std::abs(dweight), 1e-4);
  const double eps = 1e-6;
  for (Eigen::Index i = 0; i < x0.rows(); ++i) {
    for (Eigen::Index j = 0; j < x0.cols(); ++j) {
      Matrix plus = x0, minus = x0;
      plus(i, j) += eps;
      minus(i, j) -= eps;
      EXPECT_NEAR(dx0(i, j), (loss(plus) - loss(minus)) / (2 * eps), 1e-7) << i << "," << j;
    }
  }
  double& entry = weight->mutable_value()(3, 2);
  const double saved = entry;
  entry = saved + eps;
  const double up = loss(x0);
  entry = saved - eps;
  const double down = loss(x0);
  entry = saved;
  EXPECT_NEAR(dweight, (up - down) / (2 * eps), 1e-7);
}

TEST(RolloutIntegrators, AMidpointStepThatCannotConvergeNamesItsRow) {
  const KnownFieldModel model = spring();
  const Matrix x0{{1.0, 0.0}, {0.5, 0.5}};
  try {
    midpoint_solve<double>(model, x0, Matrix{{0.1}, {0.1}}, {.max_iterations = 1});
    FAIL() << "a solve with one iteration converged";
  } catch (const Error& e) {
    EXPECT_TRUE(
        std::string(e.what()).starts_with("the implicit midpoint step did not converge: row "))
        << e.what();
  }
}

TEST(RolloutIntegrators, NamesAreParsedAndUnknownOnesRefused) {
  for (const std::string& name : rollout_integrator_names())
    EXPECT_EQ(to_string(parse_rollout_integrator(name)), name);
  EXPECT_THROW(parse_rollout_integrator("euler"), Error);
}

// known_field_step runs integrator_step's formulas: a field's values through it give the bits a
// model with that field gives, and the midpoint, which needs the field's Jacobian, is refused.
TEST(RolloutIntegrators, AKnownFieldStepsByTheSameFormulasAsAModel) {
  const KnownFieldModel model = coupled();
  const KnownField field = [&](const Matrix& z, Matrix& dzdt) { dzdt = model.field(z); };
  const Matrix x0{{0.7, 0.4}, {-0.2, 0.9}};
  const Matrix h{{0.1}, {0.05}};
  for (RolloutIntegrator method : {RolloutIntegrator::kRk4, RolloutIntegrator::kRk38,
                                   RolloutIntegrator::kLeapfrog, RolloutIntegrator::kYoshida4}) {
    ad::TapeScope scope;
    ad::NoGradGuard values;
    const Matrix want = integrator_step(model, Var::constant(x0), Var::constant(h), method).value();
    EXPECT_EQ(known_field_step(field, x0, h, method), want) << to_string(method);
  }
  EXPECT_THROW(known_field_step(field, x0, h, RolloutIntegrator::kMidpoint), Error);
}

}  // namespace
}  // namespace hnn::tasks
