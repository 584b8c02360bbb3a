#include "nn/constrained/masses.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <Eigen/Cholesky>
#include <algorithm>
#include <stdexcept>
#include <utility>

namespace hnn::nn {

namespace {

using Eigen::Index;

struct Body {
  Index centre;                // the point coupled to all the others (the only one of a point mass)
  std::vector<Index> members;  // every point of the body, the centre included, ascending
};

[[noreturn]] void fail(const std::string& what) {
  throw std::invalid_argument("learned masses: " + what);
}

bool coupled(const Eigen::MatrixXd& m, Index i, Index j) { return i != j && m(i, j) != 0; }

// The points reachable from `start` through non-zero off-diagonal entries of m.
std::vector<Index> component(const Eigen::MatrixXd& m, Index start, std::vector<bool>& seen) {
  std::vector<Index> members{start}, stack{start};
  seen[std::size_t(start)] = true;
  while (!stack.empty()) {
    const Index i = stack.back();
    stack.pop_back();
    for (Index j = 0; j < m.rows(); ++j) {
      if (!coupled(m, i, j) || seen[std::size_t(j)]) continue;
      seen[std::size_t(j)] = true;
      members.push_back(j);
      stack.push_back(j);
    }
  }
  std::sort(members.begin(), members.end());
  return members;
}

// A body's centre is coupled to every other point of it, and those to nothing else.
Body body(const Eigen::MatrixXd& m, std::vector<Index> members) {
  for (Index centre : members) {
    bool star = true;
    for (Index i : members)
      for (Index j : members)
        if (i != centre && j != centre && coupled(m, i, j)) star = false;
    for (Index j : members) star = star && (j == centre || coupled(m, centre, j));
    if (star) return {centre, std::move(members)};
  }
  fail(
      fmt::format("points {} to {} are coupled in the mass matrix but are not a rigid body (one "
                  "centre coupled to each other point, those to nothing else)",
                  members.front(), members.back()));
}

std::vector<Body> bodies(const ConstraintSpec& spec) {
  std::vector<Body> out;
  std::vector<bool> seen(std::size_t(spec.points), false);
  for (Index i = 0; i < spec.points; ++i)
    if (!seen[std::size_t(i)]) out.push_back(body(spec.mass, component(spec.mass, i, seen)));
  return out;
}

Eigen::MatrixXd unit(Index n, Index i) {
  Eigen::MatrixXd b = Eigen::MatrixXd::Zero(n, n);
  b(i, i) = 1;
  return b;
}

// One basis matrix, and where its coefficient shows in M^-1: c = M^-1(at, at) - M^-1(less, less)
// (an axis point's diagonal holds 1 / m + 1 / I_j; less = -1: nothing to take away).
struct Term {
  Eigen::MatrixXd basis;
  Index at, less;
};

std::vector<Term> terms(const ConstraintSpec& spec) {
  std::vector<Term> out;
  for (const Body& b : bodies(spec)) {
    if (b.members.size() == 1) {
      out.push_back({unit(spec.points, b.centre), b.centre, -1});
      continue;
    }
    Eigen::MatrixXd all = Eigen::MatrixXd::Zero(spec.points, spec.points);
    for (Index i : b.members)
      for (Index j : b.members) all(i, j) = 1;
    out.push_back({all, b.centre, -1});
    for (Index j : b.members)
      if (j != b.centre) out.push_back({unit(spec.points, j), j, b.centre});
  }
  return out;
}

// The basis and its coefficients, checked: sum_k c_k B_k = M^-1 with every c_k > 0.
struct Decomposition {
  std::vector<Eigen::MatrixXd> basis;
  Eigen::VectorXd coefficients;
};

Decomposition decompose(const ConstraintSpec& spec) {
  std::vector<Term> all = terms(spec);
  const Eigen::MatrixXd inverse =
      spec.mass.llt().solve(Eigen::MatrixXd::Identity(spec.points, spec.points));
  Decomposition out{{}, Eigen::VectorXd(Index(all.size()))};
  Eigen::VectorXd& c = out.coefficients;
  Eigen::MatrixXd sum = Eigen::MatrixXd::Zero(spec.points, spec.points);
  for (Index k = 0; k < c.size(); ++k) {
    Term& t = all[std::size_t(k)];
    c[k] = inverse(t.at, t.at) - (t.less < 0 ? 0.0 : inverse(t.less, t.less));
    sum += c[k] * t.basis;
    out.basis.push_back(std::move(t.basis));
  }
  const double miss = (sum - inverse).cwiseAbs().maxCoeff();
  if (miss > 1e-9 * inverse.cwiseAbs().maxCoeff() || (c.array() <= 0).any()) {
    fail(
        fmt::format("the mass matrix's inverse is not a positive sum of its bodies' basis "
                    "(off by {:.3g}; coefficients {})",
                    miss, fmt::join(c.data(), c.data() + c.size(), ", ")));
  }
  return out;
}

}  // namespace

std::vector<Eigen::MatrixXd> inverse_mass_basis(const ConstraintSpec& spec) {
  return decompose(spec).basis;
}

Eigen::VectorXd inverse_mass_coefficients(const ConstraintSpec& spec) {
  return decompose(spec).coefficients;
}

}  // namespace hnn::nn
