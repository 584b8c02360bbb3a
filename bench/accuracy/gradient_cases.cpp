// The gradient cases of the finite-difference chart and the routines it times.
#include "bench/accuracy/gradient_cases.h"

#include <fmt/format.h>

#include <cmath>
#include <memory>
#include <stdexcept>

#include "bench/accuracy/mlp_reference.h"
#include "physics/nbody.h"
#include "physics/oscillators.h"

namespace hnn::accuracy {
namespace {

using MatrixD = nn::Matrix<double>;

// max |g - ref| / max |ref|.
double relative_error(const LongMatrix& g, const LongMatrix& ref) {
  return static_cast<double>((g - ref).cwiseAbs().maxCoeff() / ref.cwiseAbs().maxCoeff());
}
template <typename T>
double relative_error(const nn::Matrix<T>& g, const LongMatrix& ref) {
  return relative_error(LongMatrix(g.template cast<long double>()), ref);
}

// dH/dx of a batch function of ad ops, by reverse mode in scalar type T.
template <typename T>
MatrixD autodiff_gradient(const std::function<ad::Var<T>(const ad::Var<T>&)>& h, const MatrixD& x) {
  ad::TapeScope scope;
  const ad::Var<T> leaf = ad::Var<T>::leaf(x.cast<T>());
  return ad::grad<T>({ad::sum(h(leaf))}, {leaf})[0].value().template cast<double>();
}

// A gradient of H at `points`, compared by FD (from `value`) and autodiff (float, double).
GradientCase state_case(std::string name, const MatrixD& points, const LongMatrix& reference,
                        const BatchFunction& value,
                        const std::function<MatrixD(const MatrixD&)>& ad_double,
                        const std::function<MatrixD(const MatrixD&)>& ad_float,
                        std::string reference_kind) {
  GradientCase c;
  c.name = std::move(name);
  c.points = static_cast<int>(points.rows());
  c.coordinates = static_cast<int>(points.cols());
  c.reference = std::move(reference_kind);
  c.ad_double_error = relative_error(ad_double(points), reference);
  c.ad_float_error = relative_error(ad_float(points), reference);
  c.fd_errors = [points, reference, value](double h) {
    return FdErrors{relative_error(finite_difference_gradient(value, points, h, false), reference),
                    relative_error(finite_difference_gradient(value, points, h, true), reference)};
  };
  return c;
}

// H = 3 (1 - cos q) + p^2 (physics::Pendulum's defaults): dH/dq = 3 sin q, dH/dp = 2 p.
template <typename T>
ad::Var<T> pendulum_h(const ad::Var<T>& x) {
  const ad::Var<T> q = ad::slice_cols(x, 0, 1), p = ad::slice_cols(x, 1, 1);
  return T(3) * (T(1) - ad::cos(q)) + ad::square(p);
}

GradientCase pendulum_case() {
  auto system = std::make_shared<physics::Pendulum>();
  std::mt19937_64 rng(11);
  const MatrixD x = system->sample_initial_states(16, rng);
  LongMatrix ref(x.rows(), 2);
  for (Eigen::Index r = 0; r < x.rows(); ++r) {
    ref(r, 0) = 3.0L * std::sin(static_cast<long double>(x(r, 0)));
    ref(r, 1) = 2.0L * static_cast<long double>(x(r, 1));
  }
  return state_case(
      "pendulum_H", x, ref, [system](const MatrixD& at) { return system->hamiltonian_batch(at); },
      [](const MatrixD& at) { return autodiff_gradient<double>(pendulum_h<double>, at); },
      [](const MatrixD& at) { return autodiff_gradient<float>(pendulum_h<float>, at); },
      "analytic");
}

// Two unit masses, G = 1, columns (qx1, qx2, qy1, qy2, px1, px2, py1, py2):
// H = |p|^2 / 2 - 1 / |q_1 - q_2|.
template <typename T>
ad::Var<T> two_body_h(const ad::Var<T>& x) {
  const ad::Var<T> dx = ad::slice_cols(x, 0, 1) - ad::slice_cols(x, 1, 1);
  const ad::Var<T> dy = ad::slice_cols(x, 2, 1) - ad::slice_cols(x, 3, 1);
  const ad::Var<T> r = ad::sqrt(ad::square(dx) + ad::square(dy));
  return T(0.5) * ad::sum_cols(ad::square(ad::slice_cols(x, 4, 4))) - ad::pow(r, T(-1));
}

GradientCase two_body_case() {
  auto system = std::make_shared<physics::NBody>(physics::NBody::equal_masses(2));
  std::mt19937_64 rng(12);
  const MatrixD x = system->sample_initial_states(16, rng);
  const MatrixD h_ad = [&] {
    ad::TapeScope scope;
    return two_body_h(ad::Var<double>::constant(x)).value();
  }();
  if ((h_ad.col(0) - system->hamiltonian_batch(x)).cwiseAbs().maxCoeff() > 1e-12) {
    throw std::logic_error("two_body_h does not match physics::NBody's H");
  }
  const LongMatrix xl = x.cast<long double>();
  LongMatrix ref(x.rows(), 8);
  for (Eigen::Index r = 0; r < x.rows(); ++r) {
    const long double dx = xl(r, 0) - xl(r, 1), dy = xl(r, 2) - xl(r, 3);
    const long double r3 = std::pow(dx * dx + dy * dy, 1.5L);
    ref(r, 0) = dx / r3, ref(r, 1) = -dx / r3, ref(r, 2) = dy / r3, ref(r, 3) = -dy / r3;
    for (int j = 4; j < 8; ++j) ref(r, j) = xl(r, j);
  }
  return state_case(
      "two_body_H", x, ref, [system](const MatrixD& at) { return system->hamiltonian_batch(at); },
      [](const MatrixD& at) { return autodiff_gradient<double>(two_body_h<double>, at); },
      [](const MatrixD& at) { return autodiff_gradient<float>(two_body_h<float>, at); },
      "analytic");
}

GradientCase hnn_h_case(bool quick) {
  double loss = 0;
  const SpringData data = spring_data(25, 30, 0.1, /*seed=*/0);
  auto model = std::make_shared<nn::Hnn<double>>(
      train_spring_hnn(data, {200, 200}, quick ? 100 : 1000, /*seed=*/1, &loss));
  fmt::print("hnn_H: 2-200-200-1 HNN trained {} steps on spring data, loss {:.3e}\n",
             quick ? 100 : 1000, loss);
  auto model32 = std::make_shared<nn::Hnn<float>>(model->cast<float>());
  std::mt19937_64 rng(13);
  const MatrixD x = physics::Spring().sample_initial_states(16, rng);
  const LongMatrix ref = input_gradient(widen(model->mlp()), x.cast<long double>());
  return state_case(
      "hnn_H", x, ref, [model](const MatrixD& at) { return model->energy(at); },
      [model](const MatrixD& at) {
        return autodiff_gradient<double>([&](const ad::Var<double>& v) { return model->energy(v); },
                                         at);
      },
      [model32](const MatrixD& at) {
        return autodiff_gradient<float>([&](const ad::Var<float>& v) { return model32->energy(v); },
                                        at);
      },
      "hand-derived MLP backprop");
}

// A coordinate of one parameter tensor.
struct Coordinate {
  std::size_t tensor;
  Eigen::Index index;  // row-major flat index
};

GradientCase loss_case(bool quick) {
  const auto data = std::make_shared<SpringData>(spring_data(25, 30, 0.1, /*seed=*/0));
  nn::DynamicsConfig config;  // 2-200-200-1, at initialisation
  std::mt19937_64 rng(14);
  auto model = std::make_shared<nn::Hnn<double>>(config, rng);
  std::vector<ad::Var<double>> params = model->parameters();
  const LongLossGradient ref_full = hnn_loss_gradient(
      widen(model->mlp()), data->x.cast<long double>(), data->dxdt.cast<long double>());
  if (ref_full.gradients.size() != params.size()) throw std::logic_error("parameter count");
  // 8 coordinates per tensor (all of a smaller one), drawn uniformly.
  std::vector<Coordinate> coords;
  const Eigen::Index per_tensor = quick ? 4 : 8;
  for (std::size_t t = 0; t < params.size(); ++t) {
    const Eigen::Index size = params[t].value().size();
    for (Eigen::Index k = 0; k < std::min(per_tensor, size); ++k) {
      coords.push_back({t, size <= per_tensor ? k : static_cast<Eigen::Index>(rng() % size)});
    }
  }
  const auto pick = [coords](const auto& grads) {
    LongMatrix g(static_cast<Eigen::Index>(coords.size()), 1);
    for (std::size_t i = 0; i < coords.size(); ++i) {
      // Reference matrices are column-major: map the row-major index to (row, col).
      const auto& m = grads[coords[i].tensor];
      const Eigen::Index r = coords[i].index / m.cols(), c = coords[i].index % m.cols();
      g(static_cast<Eigen::Index>(i), 0) = static_cast<long double>(m(r, c));
    }
    return g;
  };
  const LongMatrix ref = pick(ref_full.gradients);
  GradientCase c;
  c.name = "hnn_loss_params";
  c.points = static_cast<int>(data->x.rows());
  c.coordinates = static_cast<int>(coords.size());
  c.reference = "hand-derived MLP backprop";
  c.ad_double_error = relative_error(pick(hnn_loss_autodiff(*model, *data)), ref);
  c.ad_float_error = relative_error(pick(hnn_loss_autodiff(model->cast<float>(), *data)), ref);
  c.fd_errors = [model, data, coords, ref, params, pick](double h) mutable {
    std::vector<MatrixD> forward, central;
    for (const ad::Var<double>& p : params) {
      forward.push_back(MatrixD::Zero(p.rows(), p.cols()));
      central.push_back(MatrixD::Zero(p.rows(), p.cols()));
    }
    const double base = hnn_loss(*model, *data);
    for (const Coordinate& k : coords) {
      double& theta = params[k.tensor].mutable_value().data()[k.index];
      const double saved = theta;
      theta = saved + h;
      const double plus = hnn_loss(*model, *data);
      theta = saved - h;
      const double minus = hnn_loss(*model, *data);
      theta = saved;
      forward[k.tensor].data()[k.index] = (plus - base) / h;
      central[k.tensor].data()[k.index] = (plus - minus) / (2 * h);
    }
    return FdErrors{relative_error(pick(forward), ref), relative_error(pick(central), ref)};
  };
  return c;
}

}  // namespace

std::vector<GradientCase> gradient_cases(bool quick) {
  std::vector<GradientCase> cases;
  cases.push_back(pendulum_case());
  cases.push_back(two_body_case());
  cases.push_back(hnn_h_case(quick));
  cases.push_back(loss_case(quick));
  return cases;
}

MatrixD finite_difference_gradient(const BatchFunction& f, const MatrixD& x, double h,
                                   bool central) {
  MatrixD g(x.rows(), x.cols());
  const MatrixD base = central ? MatrixD() : f(x);
  MatrixD shifted = x;
  for (Eigen::Index j = 0; j < x.cols(); ++j) {
    shifted.col(j).array() += h;
    const MatrixD plus = f(shifted);
    shifted.col(j) = x.col(j);
    if (central) {
      shifted.col(j).array() -= h;
      g.col(j) = (plus - f(shifted)) / (2 * h);
      shifted.col(j) = x.col(j);
    } else {
      g.col(j) = (plus - base) / h;
    }
  }
  return g;
}

double hnn_loss(const nn::Hnn<double>& model, const SpringData& data) {
  return (model.field(data.x) - data.dxdt).squaredNorm() / static_cast<double>(data.x.size());
}

template <typename T>
std::vector<nn::Matrix<T>> hnn_loss_autodiff(const nn::Hnn<T>& model, const SpringData& data) {
  ad::TapeScope scope;
  const ad::Var<T> x = ad::Var<T>::constant(data.x.cast<T>());
  const ad::Var<T> target = ad::Var<T>::constant(data.dxdt.cast<T>());
  const ad::Var<T> loss = nn::mse(model.time_derivative(x), target);
  std::vector<nn::Matrix<T>> out;
  for (const ad::Var<T>& g : ad::grad<T>({loss}, model.parameters())) out.push_back(g.value());
  return out;
}
template std::vector<nn::Matrix<float>> hnn_loss_autodiff(const nn::Hnn<float>&, const SpringData&);
template std::vector<nn::Matrix<double>> hnn_loss_autodiff(const nn::Hnn<double>&,
                                                           const SpringData&);

std::vector<MatrixD> loss_fd_gradient(nn::Hnn<double>& model, const SpringData& data, double h,
                                      bool central) {
  std::vector<MatrixD> grads;
  const double base = central ? 0.0 : hnn_loss(model, data);
  for (ad::Var<double> p : model.parameters()) {
    MatrixD g(p.rows(), p.cols());
    double* theta = p.mutable_value().data();
    for (Eigen::Index k = 0; k < g.size(); ++k) {
      const double saved = theta[k];
      theta[k] = saved + h;
      const double plus = hnn_loss(model, data);
      double minus = base;
      if (central) {
        theta[k] = saved - h;
        minus = hnn_loss(model, data);
      }
      theta[k] = saved;
      g.data()[k] = (plus - minus) / (central ? 2 * h : h);
    }
    grads.push_back(std::move(g));
  }
  return grads;
}

}  // namespace hnn::accuracy
