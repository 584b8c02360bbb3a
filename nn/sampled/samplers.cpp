#include "nn/sampled/samplers.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <vector>

namespace hnn::nn::sampled {

using Eigen::Index;

namespace {

// Pairs closer than this carry no direction (the peer's dist_min, which it clips to; we drop
// such pairs instead, so duplicated points never make a neuron of infinite slope).
constexpr double kDistMin = 1e-10;

HiddenLayer sample_elm(const ColMat& u, Index width, std::mt19937_64& rng) {
  HiddenLayer layer{ColMat(u.cols(), width), Eigen::RowVectorXd(width)};
  std::normal_distribution<double> normal(0.0, 1.0);
  for (Index j = 0; j < width; ++j) {
    for (Index i = 0; i < u.cols(); ++i) layer.w(i, j) = normal(rng);
  }
  std::uniform_real_distribution<double> bias(u.minCoeff(), u.maxCoeff());
  for (Index j = 0; j < width; ++j) layer.b(j) = bias(rng);
  return layer;
}

// Draws `width` distinct candidates with probability proportional to p: draws with replacement
// and redraws duplicates (the peer's resample_duplicates), rebuilding the distribution without
// the chosen ones whenever too many draws repeat.
std::vector<Index> draw_distinct(std::vector<double> p, Index width, std::mt19937_64& rng) {
  std::vector<Index> chosen;
  std::vector<char> taken(p.size(), 0);
  std::vector<double> cdf(p.size());
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  while (Index(chosen.size()) < width) {
    std::partial_sum(p.begin(), p.end(), cdf.begin());
    Index misses = 0;
    while (Index(chosen.size()) < width && misses <= width) {
      const double r = unit(rng) * cdf.back();
      auto k = Index(std::upper_bound(cdf.begin(), cdf.end(), r) - cdf.begin());
      k = std::min<Index>(k, Index(p.size()) - 1);
      if (taken[std::size_t(k)] || p[std::size_t(k)] == 0) {
        ++misses;
        continue;
      }
      taken[std::size_t(k)] = 1;
      chosen.push_back(k);
    }
    for (Index k : chosen) p[std::size_t(k)] = 0;
  }
  return chosen;
}

}  // namespace

HiddenLayer sample_layer(const ColMat& u, Index width, HiddenSampler sampler, Activation activation,
                         double scale, const ColMat* target, std::mt19937_64& rng) {
  if (sampler == HiddenSampler::kElm) return sample_elm(u, width, rng);
  const Index n = u.rows();
  if (n < 3) {
    throw std::invalid_argument(
        fmt::format("sampled fit: SWIM needs at least 3 data points, got {}", n));
  }
  // Candidate pairs as the peer draws them: from uniform, to = from + delta, delta in [1, n - 2].
  const Index candidates = n * std::max<Index>(1, (width + n - 1) / n);
  std::uniform_int_distribution<Index> pick_from(0, n - 1), pick_delta(1, n - 2);
  std::vector<Index> from(static_cast<std::size_t>(candidates)), to(from.size());
  std::vector<double> dist(from.size()), p(from.size());
  for (std::size_t k = 0; k < from.size(); ++k) {
    from[k] = pick_from(rng);
    to[k] = (from[k] + pick_delta(rng)) % n;
    dist[k] = (u.row(to[k]) - u.row(from[k])).norm();
    // Uniform: every pair of distinct points alike; A-SWIM: the target's steepest change.
    double weight = 1;
    if (target) {
      weight = (target->row(to[k]) - target->row(from[k])).cwiseAbs().maxCoeff() / dist[k];
    }
    p[k] = dist[k] < kDistMin ? 0 : weight;
  }
  double total = std::accumulate(p.begin(), p.end(), 0.0);
  if (target && total < kDistMin) {  // a flat target: the peer falls back to uniform
    for (std::size_t k = 0; k < p.size(); ++k) p[k] = dist[k] < kDistMin ? 0 : 1;
  }
  const auto usable = Index(std::count_if(p.begin(), p.end(), [](double v) { return v > 0; }));
  if (usable < width) {
    throw std::invalid_argument(fmt::format(
        "sampled fit: width {} is more than the {} distinct point pairs SWIM drew from {} data "
        "points; lower the width or give more data",
        width, usable, n));
  }
  // tanh maps u_from to -scale and u_to to +scale (the peer's atanh(1/2)); sigmoid the same points
  // of its own curve; the relu family maps them to 0 and 1.
  double gain = 1, shift = 0;
  if (activation == Activation::kTanh) gain = 2 * scale, shift = -scale;
  if (activation == Activation::kSigmoid) gain = 4 * scale, shift = -2 * scale;
  HiddenLayer layer{ColMat(u.cols(), width), Eigen::RowVectorXd(width)};
  const std::vector<Index> chosen = draw_distinct(std::move(p), width, rng);
  for (Index j = 0; j < width; ++j) {
    const auto k = std::size_t(chosen[std::size_t(j)]);
    layer.w.col(j) = gain * (u.row(to[k]) - u.row(from[k])).transpose() / (dist[k] * dist[k]);
    layer.b(j) = -u.row(from[k]).dot(layer.w.col(j)) + shift;
  }
  return layer;
}

}  // namespace hnn::nn::sampled
