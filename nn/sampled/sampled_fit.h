#pragma once
// Fitting a dynamics model without backpropagation (Rahma, Datar & Dietrich 2024, "Training
// Hamiltonian neural networks without backpropagation", arXiv 2411.17511): every hidden layer
// is sampled from the data (ELM: at random; SWIM: each neuron from a pair of data points), and
// the last layer is the solution of a linear least-squares problem. This works because an HNN's
// field (dH/dp, -dH/dq), a baseline's dx/dt and a D-HNN's two potentials are all linear in the
// last layer's weights. An LNN's accelerations are not, so it is refused.

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "nn/activation.h"
#include "nn/dynamics.h"
#include "nn/enum_names.h"

namespace hnn::nn {

/// How hidden weights are drawn.
enum class HiddenSampler {
  kElm,    // random weights and biases (extreme learning machine)
  kUswim,  // SWIM: each neuron from a pair of data points drawn uniformly
  kAswim,  // SWIM with pairs weighted by how fast an approximate target (a U-SWIM fit) changes
};
inline constexpr NameTable<HiddenSampler, 3> kHiddenSamplerNames{{
    {HiddenSampler::kElm, "elm"},
    {HiddenSampler::kUswim, "uswim"},
    {HiddenSampler::kAswim, "aswim"},
}};

/// How the last layer's least-squares problem is solved (docs/sampled.md has the measurements).
enum class LeastSquaresSolver {
  kLsqr,      // LSQR on A, right-preconditioned by the Cholesky factor of the regularised Gram,
              // started from the normal equations' solution
  kCholesky,  // the regularised normal equations (A^T A + lambda I) c = A^T b, by Cholesky
  kQr,        // LAPACK's dgelsd (SVD-based, like np.linalg.lstsq) on A, or for one hidden layer
              // on its reduction by a QR of D (docs/sampled.md)
  kRidge,     // qr's reduction, then Tikhonov on its triangle R: the QR of [R; mu I] by dtpqrt,
              // mu = rcond times R's largest singular value, and one triangular solve
  kSketch,    // ridge's problem by LSQR on [A; mu I], right-preconditioned by ridge's triangle of a
              // sparse sketch of A (sketch.h): the sketch's QR instead of D's
};
inline constexpr NameTable<LeastSquaresSolver, 5> kLeastSquaresSolverNames{{
    {LeastSquaresSolver::kLsqr, "lsqr"},
    {LeastSquaresSolver::kCholesky, "cholesky"},
    {LeastSquaresSolver::kQr, "qr"},
    {LeastSquaresSolver::kRidge, "ridge"},
    {LeastSquaresSolver::kSketch, "sketch"},
}};

/// Whether a solver reads SampledFitConfig::rcond (the others read regularization, and lsqr
/// tolerance and max_iterations).
constexpr bool reads_rcond(LeastSquaresSolver solver) {
  return solver != LeastSquaresSolver::kLsqr && solver != LeastSquaresSolver::kCholesky;
}
/// Whether a solver iterates (reads SampledFitConfig::tolerance and max_iterations).
constexpr bool iterates(LeastSquaresSolver solver) {
  return solver == LeastSquaresSolver::kLsqr || solver == LeastSquaresSolver::kSketch;
}

/// The peer's SWIM scale, atanh(1/2) = ln(3) / 2: a tanh neuron passes through -1/2 and +1/2 at
/// its two data points (swimnetworks' Dense).
inline constexpr double kPeerSwimScale = 0.54930614433405484570;

/// Settings of a sampled fit. The defaults reproduce the peer's accuracy or better
/// (docs/sampled.md).
struct SampledFitConfig {
  HiddenSampler sampler = HiddenSampler::kUswim;
  /// SWIM: a neuron's pre-activation runs from -swim_scale to +swim_scale between its two data
  /// points (the peer's kPeerSwimScale); smaller, smoother neurons. Empty (auto, the default):
  /// chosen by validation like rcond, walking kPeerSwimScale * 2^k from k = 0 while the held-out
  /// error falls kScaleGain-fold a step (scale_choice.h). ELM does not read it.
  std::optional<double> swim_scale{};
  /// kQr, kRidge: singular values below rcond times the largest do not shape the solution (the
  /// peer's np.linalg.lstsq rcond; kQr drops them, kRidge damps them). Empty (auto, the default):
  /// chosen by validation on held-out tenths of the points, then the fit runs again on all of them
  /// at that cutoff (rcond_choice.h).
  std::optional<double> rcond{};
  std::uint64_t seed = 0;
  /// kQr by default: it keeps the peer's accuracy; so does kRidge in a twentieth of the solve's
  /// time on exact derivatives, but it chose other cutoffs on noisy data (docs/sampled.md).
  LeastSquaresSolver solver = LeastSquaresSolver::kQr;
  /// lambda, added to the diagonal of A^T A after its columns are scaled to unit norm, for
  /// kCholesky and kLsqr's preconditioner. When the Cholesky factorisation fails, lambda is
  /// raised tenfold until it succeeds (at most to 1e-6, or to lambda itself when larger; beyond,
  /// the system is called singular).
  double regularization = 1e-13;
  /// kLsqr and kSketch stop when the preconditioned normal-equation residual |(A M)^T r| falls
  /// below tolerance * |A M| |r|.
  double tolerance = 1e-14;
  /// kLsqr's and kSketch's iteration cap.
  int max_iterations = 200;
  /// kAswim: the first (U-SWIM) fit, whose outputs weight the pairs of the second, has this
  /// fraction of each hidden layer's width (at least 1 neuron). The peer fits it at full width
  /// (1); a fifth weights the pairs as well and costs a small part of the second fit
  /// (docs/sampled.md: the same error on Henon-Heiles and the double pendulum at half the time).
  double aswim_first_fraction = 0.2;
};

/// One cutoff of --rcond auto's ladder: the relative field error on the held-out points of the
/// fit on the others, and how many singular values it kept.
struct RcondTrial {
  double rcond = 0;
  double error = 0;
  int rank = 0;
};

/// Whether a fit reads SampledFitConfig::swim_scale: SWIM with tanh or sigmoid (the other
/// activations place a neuron's data points at 0 and 1 of their own curve).
constexpr bool reads_swim_scale(HiddenSampler sampler, Activation activation) {
  return sampler != HiddenSampler::kElm &&
         (activation == Activation::kTanh || activation == Activation::kSigmoid);
}

/// One scale of --swim-scale auto's walk: the held-out relative field error of the fit at it
/// (at its best cutoff, when rcond is auto too).
struct ScaleTrial {
  double scale = 0;
  double error = 0;
};

/// What a fit did, for metrics.json and the closing figures.
struct SampledFitReport {
  std::string solver;            // the least-squares method that ran
  double sample_seconds = 0;     // drawing the hidden layers
  double assemble_seconds = 0;   // forming the matrices the solver reads
  double solve_seconds = 0;      // the solve itself
  double gram_seconds = 0;       // of assemble_seconds: A^T A (one syrk), or forming A for qr
  double regularization = 0;     // the lambda the Cholesky factorisation took (kLsqr, kCholesky)
  std::size_t rows = 0;          // equations of the least-squares problem
  std::size_t columns = 0;       // unknowns (last-layer weights)
  std::size_t matrix_bytes = 0;  // the largest matrices held at once
  double residual_rms = 0;       // root mean square of the system's residual on the fit data
  int iterations = 0;            // of an iterative solver; 0 for a direct one
  double rcond = 0;              // kQr, kRidge: the cutoff used (auto: the one chosen)
  std::vector<RcondTrial> rcond_validation;  // auto: every cutoff tried (the last fit's)
  double swim_scale = 0;                     // SWIM: the scale used (auto: the one chosen)
  std::vector<ScaleTrial> scale_validation;  // auto: every scale tried (the last fit's)
  double validation_seconds = 0;  // auto: choosing the cutoff and scale (not in the others)
};

/// Samples every hidden layer of `model` and solves its last layer so that model.field(x)
/// approximates dxdt in the least-squares sense; the fit runs in double whatever T is. x and
/// dxdt are N x dim, in the model's state coordinates. Throws std::invalid_argument, with one
/// line naming what is wrong, for an LNN, a width the data cannot support, non-finite x or dxdt,
/// or a singular system.
template <typename T>
SampledFitReport fit_sampled(DynamicsModel<T>& model, const Matrix<double>& x,
                             const Matrix<double>& dxdt, const SampledFitConfig& config);

}  // namespace hnn::nn
