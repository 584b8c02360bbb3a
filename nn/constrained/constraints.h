#pragma once
// The description of a constrained mechanical system in Cartesian coordinates, as the CHNN and
// CLNN models (nn/constrained/constrained_model.h) take it: N point masses in d dimensions, a
// constant mass matrix over the points acting on each axis alike, and holonomic distance
// constraints between two points (rods) or between a point and a fixed point (pivots). nn does not
// include physics/: tasks/ converts a physics system's description into this one.

#include <Eigen/Core>
#include <vector>

#include "autodiff/var.h"

namespace hnn::nn {

/// |x_i - x_j| = length.
struct Link {
  Eigen::Index i = 0, j = 0;
  double length = 1;
};

/// |x_i - point| = length, point fixed in space (d coordinates).
struct Anchor {
  Eigen::Index i = 0;
  std::vector<double> point;
  double length = 1;
};

/// sum_j weights[j] x_j = point: d constraints, one per axis. A point of a rigid body (affine
/// weights over the system's points) held at a fixed point in space, a ball joint (the gyroscope's
/// and the rotor's pivots).
struct Pin {
  std::vector<double> weights;  // one per point
  std::vector<double> point;    // d coordinates
};

/// A state z = (x, v) of such a system is a row of 2 N d numbers: the positions x, point by point
/// (point i's axis k at column i d + k), then the velocities v = dx/dt in the same order.
struct ConstraintSpec {
  Eigen::Index points = 0;  // N; 0 means no constrained system (the other model kinds)
  Eigen::Index dim = 0;     // d, the dimension of space
  /// N x N, symmetric positive definite (non-diagonal for rigid bodies built of points): the
  /// kinetic energy is 1/2 sum_k v[:, k]^T M v[:, k] over the axes k.
  Eigen::MatrixXd mass;
  /// Whether a model learns the masses (nn/constrained/masses.h: `mass` then gives only the
  /// bodies, point masses and rigid bodies, whose masses and moments are learned), as Finzi et
  /// al.'s models do, or takes `mass` as known.
  bool learned_masses = false;
  std::vector<Link> links;
  std::vector<Anchor> anchors;
  std::vector<Pin> pins;

  bool empty() const { return points == 0; }
  /// The constraints' blocks, each a d-vector e linear in x: links, anchors, then pins.
  Eigen::Index blocks() const { return Eigen::Index(links.size() + anchors.size() + pins.size()); }
  /// The number of scalar constraints C: one per link and per anchor (|e|^2 = l^2), d per pin
  /// (e = 0), in that order (the order of the multipliers).
  Eigen::Index constraints() const {
    return Eigen::Index(links.size() + anchors.size()) + dim * Eigen::Index(pins.size());
  }
  /// N d, the size of x (and of v).
  Eigen::Index positions() const { return points * dim; }
};

/// Throws std::invalid_argument naming the first thing wrong: N or d < 1, a mass matrix that is not
/// N x N, finite, symmetric and positive definite, a point index out of range, a link from a point
/// to itself or given twice, an anchor point of the wrong size, a length not finite and > 0, a pin
/// whose weights are not N finite numbers, not all zero, or whose point is not d finite numbers.
void validate(const ConstraintSpec& spec);

}  // namespace hnn::nn
