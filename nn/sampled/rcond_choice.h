#pragma once
// --rcond auto (docs/sampled.md, "Noisy data: --rcond auto"): the least-squares cutoff chosen by
// validation. A contiguous tenth of the points is held out; the reduced problem of the other nine
// tenths is decomposed once by an SVD (qr), and each cutoff of a ladder (1e-14 ... 1e-1, a decade
// apart) gives its solution as a cheap product with the SVD's factors, judged by its field error
// on the held-out points; more tenths in turn while fewer than kHeldOutPoints were held out. ridge
// solves the fold's triangle once per cutoff instead, from the smallest, and stops where the
// held-out error passes a hundred times the best (on exact derivatives after a few cutoffs: an
// SVD of a 5000-wide triangle costs more than twenty such solves). Exact
// derivatives want the smallest cutoff (the peer's 1e-13); noisy ones a large one, or the fit
// interpolates the noise and its rollouts run away.

#include <functional>
#include <memory>
#include <vector>

#include "nn/sampled/least_squares.h"
#include "nn/sampled/sampled_fit.h"
#include "nn/sampled/systems.h"

namespace hnn::nn::sampled {

/// The cutoffs tried, smallest first.
std::vector<double> rcond_ladder();

/// The training and held-out points of one fold.
struct PointSplit {
  std::vector<Eigen::Index> train, held_out;
};
/// How many points the validation holds out, at least (or all of them, fold after fold).
inline constexpr Eigen::Index kHeldOutPoints = 1000;

/// The folds --rcond auto validates on: contiguous tenths of the points in the data's order (so
/// that trajectories stored point after point are held out whole rather than interpolated from
/// their neighbours), each held out in turn, as many as hold out kHeldOutPoints (all ten for a
/// few hundred points, one for ten thousand), spread over the data. Throws std::invalid_argument
/// for fewer than 2 points.
std::vector<PointSplit> validation_folds(Eigen::Index points);

/// Builds the last layer's system on the given points (indices into the fit's data).
using SystemOn = std::function<std::unique_ptr<LinearSystem>(const std::vector<Eigen::Index>&)>;

/// The cutoff of `ladder` (rcond_ladder(), or one given cutoff to score) whose fits by
/// config.solver (qr or ridge) on each fold's training points have the smallest relative field
/// error over the held-out points of every fold (ties to the smaller cutoff), and every cutoff's
/// error in `curve` (ridge: those its walk reached). With one fold and `whole`, also the whole
/// problem's triangle: the fold's training triangle merged with its held-out points' (one dtpqrt),
/// which saves the fit at the chosen cutoff a reduction of all the points (qr_apply's 11 s of the
/// Henon-Heiles protocol's fit).
double choose_rcond(const SystemOn& system_on, const std::vector<PointSplit>& folds,
                    const SampledFitConfig& config, const std::vector<double>& ladder,
                    std::vector<RcondTrial>& curve, ReducedProblem* whole = nullptr);

/// The relative field error over the held-out points of every fold of fits by config.solver on
/// each fold's training points: how --swim-scale auto scores a scale for the solvers without a
/// cutoff (lsqr, cholesky).
double held_out_error(const SystemOn& system_on, const std::vector<PointSplit>& folds,
                      const SampledFitConfig& config);

}  // namespace hnn::nn::sampled
