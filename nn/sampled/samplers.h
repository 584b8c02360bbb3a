#pragma once
// The hidden-layer samplers of the peer (AlphaGergedan/swimnetworks, Dense): ELM draws weights
// at random; SWIM builds each neuron from a pair of data points, so that the activation's steep
// part lies between them (docs/sampled.md).

#include <optional>
#include <random>

#include "nn/activation.h"
#include "nn/sampled/features.h"
#include "nn/sampled/sampled_fit.h"

namespace hnn::nn::sampled {

/// A layer of `width` neurons on the inputs u (N x in). ELM: weights N(0, 1), biases uniform
/// between the smallest and largest entry of u (the peer's domain limits). SWIM: pairs
/// (from, to) of distinct points, each neuron's pre-activation -scale at u_from and +scale at
/// u_to (tanh; sigmoid the same points of its curve, the relu family 0 and 1), drawn uniformly (no
/// target) or with probability max_k |y_to,k - y_from,k| / |u_to - u_from| (a target y, N x q:
/// A-SWIM's approximate values); all pairs distinct. Throws std::invalid_argument when the data
/// cannot give `width` distinct pairs of distinct points.
HiddenLayer sample_layer(const ColMat& u, Eigen::Index width, HiddenSampler sampler,
                         Activation activation, double scale, const ColMat* target,
                         std::mt19937_64& rng);

}  // namespace hnn::nn::sampled
