#include "nn/constrained/constraints.h"

#include <fmt/format.h>

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>

namespace hnn::nn {

namespace {

[[noreturn]] void fail(const std::string& what) {
  throw std::invalid_argument("constraints: " + what);
}

void check_mass(const ConstraintSpec& spec) {
  const Eigen::MatrixXd& m = spec.mass;
  if (m.rows() != spec.points || m.cols() != spec.points) {
    fail(fmt::format("the mass matrix is {}x{} but there are {} points", m.rows(), m.cols(),
                     spec.points));
  }
  if (!m.allFinite()) fail("the mass matrix has a non-finite entry");
  const double asymmetry = (m - m.transpose()).cwiseAbs().maxCoeff();
  if (asymmetry > 1e-12 * m.cwiseAbs().maxCoeff()) {
    fail(fmt::format("the mass matrix is not symmetric (|M - M^T| = {:.3g})", asymmetry));
  }
  if (Eigen::LLT<Eigen::MatrixXd>(m).info() != Eigen::Success) {
    fail("the mass matrix is not positive definite");
  }
}

void check_point(Eigen::Index i, const ConstraintSpec& spec, const std::string& where) {
  if (i < 0 || i >= spec.points) {
    fail(fmt::format("{} names point {}, outside [0, {})", where, i, spec.points));
  }
}

void check_length(double length, const std::string& where) {
  if (!(std::isfinite(length) && length > 0)) {
    fail(fmt::format("{} has length {}; a length must be finite and > 0", where, length));
  }
}

void check_links(const ConstraintSpec& spec) {
  std::vector<std::pair<Eigen::Index, Eigen::Index>> seen;
  for (std::size_t k = 0; k < spec.links.size(); ++k) {
    const Link& link = spec.links[k];
    const std::string where = fmt::format("link {} ({}-{})", k, link.i, link.j);
    check_point(link.i, spec, where);
    check_point(link.j, spec, where);
    if (link.i == link.j) fail(where + " joins a point to itself");
    check_length(link.length, where);
    const std::pair<Eigen::Index, Eigen::Index> key{std::min(link.i, link.j),
                                                    std::max(link.i, link.j)};
    if (std::find(seen.begin(), seen.end(), key) != seen.end()) {
      fail(where + " joins two points already joined (redundant constraints)");
    }
    seen.emplace_back(key);
  }
}

bool finite(const std::vector<double>& values) {
  return std::all_of(values.begin(), values.end(), [](double c) { return std::isfinite(c); });
}

void check_anchors(const ConstraintSpec& spec) {
  for (std::size_t k = 0; k < spec.anchors.size(); ++k) {
    const Anchor& anchor = spec.anchors[k];
    const std::string where = fmt::format("anchor {} (point {})", k, anchor.i);
    check_point(anchor.i, spec, where);
    if (Eigen::Index(anchor.point.size()) != spec.dim) {
      fail(fmt::format("{} has a fixed point of {} coordinates in {} dimensions", where,
                       anchor.point.size(), spec.dim));
    }
    if (!finite(anchor.point)) {
      fail(where + " has a non-finite fixed point");
    }
    check_length(anchor.length, where);
  }
}

void check_pins(const ConstraintSpec& spec) {
  for (std::size_t k = 0; k < spec.pins.size(); ++k) {
    const Pin& pin = spec.pins[k];
    const std::string where = fmt::format("pin {}", k);
    if (Eigen::Index(pin.weights.size()) != spec.points || !finite(pin.weights)) {
      fail(fmt::format("{} needs {} finite weights (one per point), got {}", where, spec.points,
                       pin.weights.size()));
    }
    if (std::all_of(pin.weights.begin(), pin.weights.end(), [](double w) { return w == 0; })) {
      fail(where + " has only zero weights");
    }
    if (Eigen::Index(pin.point.size()) != spec.dim || !finite(pin.point)) {
      fail(fmt::format("{} needs a fixed point of {} finite coordinates, got {}", where, spec.dim,
                       pin.point.size()));
    }
  }
}

}  // namespace

void validate(const ConstraintSpec& spec) {
  if (spec.points < 1 || spec.dim < 1) {
    fail(fmt::format("{} points in {} dimensions; both must be >= 1", spec.points, spec.dim));
  }
  check_mass(spec);
  check_links(spec);
  check_anchors(spec);
  check_pins(spec);
}

}  // namespace hnn::nn
