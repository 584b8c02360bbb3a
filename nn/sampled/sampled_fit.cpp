#include "nn/sampled/sampled_fit.h"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <optional>
#include <random>
#include <stdexcept>

#include "nn/sampled/features.h"
#include "nn/sampled/least_squares.h"
#include "nn/sampled/rcond_choice.h"
#include "nn/sampled/samplers.h"
#include "nn/sampled/scale_choice.h"

namespace hnn::nn {

using Eigen::Index;
using sampled::ColMat;
using sampled::HiddenLayer;

namespace {

using Clock = std::chrono::steady_clock;

double seconds_from(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

void check_matrix(const char* what, const Matrix<double>& m, Index dim) {
  if (m.cols() != dim || m.rows() < 1) {
    throw std::invalid_argument(fmt::format("sampled fit: {} is {} x {}, the model takes N x {}",
                                            what, m.rows(), m.cols(), dim));
  }
  for (Index r = 0; r < m.rows(); ++r) {
    for (Index c = 0; c < m.cols(); ++c) {
      if (!std::isfinite(m(r, c))) {
        throw std::invalid_argument(fmt::format(
            "sampled fit: {} row {} column {} is not finite ({})", what, r, c, m(r, c)));
      }
    }
  }
}

void check_inputs(const DynamicsConfig& config, const Matrix<double>& x,
                  const Matrix<double>& dxdt) {
  if (config.model == ModelKind::kLnn) {
    throw std::invalid_argument(
        "sampled fit: an LNN's accelerations solve a system with the Hessian d2L/dv2, which is not "
        "linear in the last layer's weights, so no least-squares fit exists; train it with Adam");
  }
  if (config.model == ModelKind::kMassHnn) {
    throw std::invalid_argument(
        "sampled fit: an hnn-mass's field passes through its learned mass matrix, which is not "
        "linear in the last layers' weights, so no least-squares fit exists; train it with Adam");
  }
  if (is_constrained(config.model)) {
    throw std::invalid_argument(fmt::format(
        "sampled fit: a {}'s field solves for constraint forces, which are not linear in the last "
        "layer's weights; train it with Adam",
        to_string(config.model)));
  }
  if (config.hidden.empty()) {
    throw std::invalid_argument("sampled fit: the MLP has no hidden layer to sample");
  }
  check_matrix("x", x, config.dim);
  check_matrix("dxdt", dxdt, config.dim);
  if (x.rows() != dxdt.rows()) {
    throw std::invalid_argument(
        fmt::format("sampled fit: x has {} rows but dxdt has {}", x.rows(), dxdt.rows()));
  }
}

// The last layer's least-squares problem, known before anything is sampled: the baseline fits
// each output over the points, the other models one field equation per point and coordinate.
// Checked first, so that a width the data cannot support fails at once, not after the sampling
// and --rcond auto's fold solves (seconds at width 1000 on the spring).
struct LastLayerShape {
  Index equations, unknowns;
};

LastLayerShape last_layer_shape(const DynamicsConfig& mc, Index points) {
  const Index width = mc.hidden.back();
  if (mc.model == ModelKind::kBaseline) return {points, width};
  return {points * mc.dim, Index(sampled::field_terms(mc).size()) * width};
}

void check_width(const DynamicsConfig& mc, Index points) {
  const LastLayerShape shape = last_layer_shape(mc, points);
  if (shape.unknowns > shape.equations) {
    throw std::invalid_argument(fmt::format(
        "sampled fit: {} last-layer unknowns per output but only {} equations from {} points; "
        "lower the width or give more points",
        shape.unknowns, shape.equations, points));
  }
}

// The hidden layers and the last layer's weights (unknowns x m) of one fit.
struct Fitted {
  std::vector<HiddenLayer> layers;
  ColMat last_hidden;  // the last hidden layer's outputs at the data (N x width), when kept
  ColMat c;
};

std::vector<HiddenLayer> sample_hidden(const DynamicsConfig& mc, const ColMat& x,
                                       HiddenSampler sampler, double scale, const ColMat* target,
                                       std::mt19937_64& rng, ColMat* last_hidden) {
  std::vector<HiddenLayer> layers;
  ColMat h = sampled::mlp_input(mc, x);
  for (Index width : mc.hidden) {
    layers.push_back(sampled::sample_layer(h, width, sampler, mc.activation, scale, target, rng));
    if (layers.size() == mc.hidden.size() && !last_hidden) break;
    ColMat value;
    sampled::activate(mc.activation, sampled::pre_activation(layers.back(), h), value, nullptr);
    h.swap(value);
  }
  if (last_hidden) last_hidden->swap(h);
  return layers;
}

// The last layer's system: the baseline's outputs, an HNN's field rows (Hadamard form for one
// hidden layer on unembedded inputs, else formed through every layer).
std::unique_ptr<sampled::LinearSystem> last_layer_system(const DynamicsConfig& mc,
                                                         const std::vector<HiddenLayer>& layers,
                                                         const ColMat& last_hidden, const ColMat& x,
                                                         const ColMat& dxdt) {
  if (mc.model == ModelKind::kBaseline) {
    return std::make_unique<sampled::DenseSystem>(last_hidden, dxdt);
  }
  if (layers.size() > 1 || mc.angles > 0) {
    return std::make_unique<sampled::DenseSystem>(sampled::field_matrix(mc, layers, x),
                                                  ColMat(dxdt.reshaped()));
  }
  const HiddenLayer& layer = layers.front();
  const Index w = layer.w.cols();
  ColMat slope = sampled::pre_activation(layer, sampled::mlp_input(mc, x));
  sampled::activate(mc.activation, slope, slope, &slope);  // in place: the slope alone
  const auto terms = sampled::field_terms(mc);
  ColMat v(mc.dim, Index(terms.size()) * w);
  for (std::size_t s = 0; s < terms.size(); ++s) {
    for (Index i = 0; i < mc.dim; ++i) {
      const sampled::FieldTerm t = terms[s][std::size_t(i)];
      const double scale = mc.input_scale.empty() ? 1.0 : mc.input_scale[std::size_t(t.source)];
      v.row(i).segment(Index(s) * w, w) = (t.sign / scale) * layer.w.row(t.source);
    }
  }
  return std::make_unique<sampled::HadamardSystem>(std::move(slope), std::move(v), dxdt);
}

// What one fit_once samples from and for. keep_last: the last hidden layer's outputs are
// needed (the baseline's matrix, A-SWIM's target).
struct FitRequest {
  const DynamicsConfig& mc;
  const ColMat &x, &dxdt;
  const SampledFitConfig& config;
  HiddenSampler sampler;
  const ColMat* target;
  bool keep_last;
};

// The hidden layers sampled at one SWIM scale, validated when the cutoff is auto or the scale is
// being chosen: the cutoff chosen, its curve, the held-out error and the whole problem's triangle
// the validation left (one fold), which the fit at the chosen cutoff starts from.
struct Trial {
  Fitted fit;
  std::optional<double> rcond;
  std::vector<RcondTrial> rcond_curve;
  sampled::ReducedProblem whole;
  double error = 0;
};

Trial sample_trial(const FitRequest& q, double scale, bool score, std::mt19937_64& rng,
                   SampledFitReport& report) {
  Trial t;
  auto start = Clock::now();
  t.fit.layers = sample_hidden(q.mc, q.x, q.sampler, scale, q.target, rng,
                               q.keep_last ? &t.fit.last_hidden : nullptr);
  report.sample_seconds += seconds_from(start);
  t.rcond = q.config.rcond;
  const bool rcond_auto = reads_rcond(q.config.solver) && !q.config.rcond;
  if (!rcond_auto && !score) return t;
  start = Clock::now();
  const auto on = [&](const std::vector<Index>& rows) {
    const ColMat hidden =
        q.mc.model == ModelKind::kBaseline ? ColMat(t.fit.last_hidden(rows, Eigen::all)) : ColMat();
    return last_layer_system(q.mc, t.fit.layers, hidden, q.x(rows, Eigen::all),
                             q.dxdt(rows, Eigen::all));
  };
  const std::vector<sampled::PointSplit> folds = sampled::validation_folds(q.x.rows());
  if (reads_rcond(q.config.solver)) {
    const std::vector<double> ladder =
        rcond_auto ? sampled::rcond_ladder() : std::vector<double>{*q.config.rcond};
    t.rcond = sampled::choose_rcond(on, folds, q.config, ladder, t.rcond_curve, &t.whole);
    t.error = std::ranges::min_element(t.rcond_curve, {}, &RcondTrial::error)->error;
  } else {
    t.error = sampled::held_out_error(on, folds, q.config);
  }
  report.validation_seconds += seconds_from(start);
  return t;
}

// The hidden layers at the configured SWIM scale, or with --swim-scale auto at the scale the walk
// keeps (scale_choice.h); every scale draws the same pairs, so only the scale differs between
// them, and rng ends where the kept one's draws left it. At most two trials are held at once.
Trial sampled_layers(const FitRequest& q, std::mt19937_64& rng, SampledFitReport& report) {
  const bool reads = reads_swim_scale(q.sampler, q.mc.activation);
  if (!reads || q.config.swim_scale) {
    const double scale = q.config.swim_scale.value_or(kPeerSwimScale);
    report.swim_scale = reads ? scale : 0;
    return sample_trial(q, scale, false, rng, report);
  }
  Trial last, best;
  std::mt19937_64 draws = rng, after = rng;
  const auto error_at = [&](double scale) {
    draws = rng;
    last = Trial{};  // freed before the next is built: a baseline's holds N x width outputs
    last = sample_trial(q, scale, true, draws, report);
    return last.error;
  };
  const auto keep_last = [&] {
    best = std::move(last);
    after = draws;
  };
  report.swim_scale = sampled::walk_scales(error_at, keep_last, report.scale_validation);
  rng = after;
  return best;
}

Fitted fit_once(const FitRequest& q, std::mt19937_64& rng, SampledFitReport& report) {
  Trial trial = sampled_layers(q, rng, report);
  report.rcond = trial.rcond.value_or(0);
  if (reads_rcond(q.config.solver) && !q.config.rcond) report.rcond_validation = trial.rcond_curve;
  SampledFitConfig solve = q.config;
  solve.rcond = trial.rcond;
  Fitted& fit = trial.fit;
  const auto start = Clock::now();
  const auto system = last_layer_system(q.mc, fit.layers, fit.last_hidden, q.x, q.dxdt);
  report.assemble_seconds += seconds_from(start);
  report.rows = std::size_t(system->equations() * system->rhs_columns());
  report.columns = std::size_t(system->unknowns() * system->rhs_columns());
  const LastLayerShape expected = last_layer_shape(q.mc, q.x.rows());
  if (system->unknowns() != expected.unknowns || system->equations() != expected.equations) {
    throw std::logic_error(fmt::format(
        "sampled fit: the last layer's system is {} x {}, not the {} x {} checked beforehand",
        system->equations(), system->unknowns(), expected.equations, expected.unknowns));
  }
  const sampled::LeastSquaresResult solved =
      sampled::solve_least_squares(*system, solve, &trial.whole);
  report.assemble_seconds += solved.gram_seconds;
  report.gram_seconds += solved.gram_seconds;
  report.solve_seconds += solved.solve_seconds;
  report.iterations = solved.iterations;
  report.regularization = solved.regularization;
  report.residual_rms = solved.residual_rms;
  report.matrix_bytes = std::max(report.matrix_bytes, system->bytes() + solved.bytes);
  fit.c = solved.c;
  return std::move(fit);
}

// The fitted MLP's outputs at the data (N x outputs): A-SWIM's approximate target.
ColMat fitted_outputs(const Fitted& fit) {
  const Index w = fit.last_hidden.cols();
  if (fit.c.cols() > 1) return fit.last_hidden * fit.c;  // the baseline: dx/dt
  return fit.last_hidden * fit.c.col(0).reshaped(w, fit.c.rows() / w);
}

template <typename T>
void write_weights(DynamicsModel<T>& model, const Fitted& fit) {
  const auto hidden = Index(fit.layers.size());
  const Index w = fit.layers.back().w.cols();
  const ColMat last = fit.c.cols() > 1 ? fit.c : ColMat(fit.c.col(0).reshaped(w, fit.c.rows() / w));
  model.visit_parameters([&](const std::string& name, ad::Var<T>& p) {
    for (Index l = 0; l <= hidden; ++l) {
      const std::string prefix = fmt::format("mlp.layers.{}.", l);
      if (name == prefix + "weight") {
        p.mutable_value() = (l < hidden ? fit.layers[std::size_t(l)].w : last).template cast<T>();
      } else if (name == prefix + "bias" && l < hidden) {
        p.mutable_value() = fit.layers[std::size_t(l)].b.template cast<T>();
      }
    }
  });
}

}  // namespace

template <typename T>
SampledFitReport fit_sampled(DynamicsModel<T>& model, const Matrix<double>& x,
                             const Matrix<double>& dxdt, const SampledFitConfig& config) {
  const DynamicsConfig& mc = model.config();
  check_inputs(mc, x, dxdt);
  check_width(mc, x.rows());
  SampledFitReport report;
  report.solver = std::string(name_of(kLeastSquaresSolverNames, config.solver));
  const ColMat xc = x, dc = dxdt;
  std::mt19937_64 rng(config.seed);
  const bool adaptive = config.sampler == HiddenSampler::kAswim;
  const bool baseline = mc.model == ModelKind::kBaseline;
  DynamicsConfig first = mc;
  if (adaptive) {
    for (Index& w : first.hidden)
      w = std::max<Index>(1, Index(std::lround(double(w) * config.aswim_first_fraction)));
  }
  const HiddenSampler first_sampler = adaptive ? HiddenSampler::kUswim : config.sampler;
  Fitted fit =
      fit_once({first, xc, dc, config, first_sampler, nullptr, baseline || adaptive}, rng, report);
  if (adaptive) {
    const ColMat approximate = fitted_outputs(fit);
    fit =
        fit_once({mc, xc, dc, config, HiddenSampler::kAswim, &approximate, baseline}, rng, report);
  }
  write_weights(model, fit);
  return report;
}

template SampledFitReport fit_sampled<double>(DynamicsModel<double>&, const Matrix<double>&,
                                              const Matrix<double>&, const SampledFitConfig&);
template SampledFitReport fit_sampled<float>(DynamicsModel<float>&, const Matrix<double>&,
                                             const Matrix<double>&, const SampledFitConfig&);

}  // namespace hnn::nn
