#include "nn/constrained/masses.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <Eigen/Cholesky>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
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

namespace {

// dPhi/dx of the position constraints at x (1 x N d): a link's or an anchor's row e^T at its
// points (|e|^2 / 2 = l^2 / 2, e = x_i - x_j or x_i - a), a pin's d rows its weights per axis.
Eigen::MatrixXd constraint_jacobian(const ConstraintSpec& spec, const Eigen::RowVectorXd& x) {
  const Index d = spec.dim;
  Eigen::MatrixXd g = Eigen::MatrixXd::Zero(spec.constraints(), spec.positions());
  Index row = 0;
  for (const Link& l : spec.links) {
    const Eigen::RowVectorXd e = x.segment(l.i * d, d) - x.segment(l.j * d, d);
    g.block(row, l.i * d, 1, d) = e;
    g.block(row++, l.j * d, 1, d) = -e;
  }
  for (const Anchor& a : spec.anchors) {
    g.block(row++, a.i * d, 1, d) =
        x.segment(a.i * d, d) - Eigen::Map<const Eigen::RowVectorXd>(a.point.data(), d);
  }
  for (const Pin& p : spec.pins) {
    for (Index k = 0; k < d; ++k, ++row)
      for (Index j = 0; j < spec.points; ++j) g(row, j * d + k) = p.weights[std::size_t(j)];
  }
  return g;
}

}  // namespace

double tangent_mass_error(const ConstraintSpec& spec, const Eigen::MatrixXd& mass,
                          const Eigen::MatrixXd& truth, const Eigen::MatrixXd& positions) {
  const Index n = spec.positions();
  if (mass.rows() != n || mass.cols() != n || truth.rows() != n || truth.cols() != n ||
      positions.cols() != n)
    throw std::invalid_argument(fmt::format(
        "tangent_mass_error: masses {}x{} and {}x{}, positions {} wide, for {} coordinates",
        mass.rows(), mass.cols(), truth.rows(), truth.cols(), positions.cols(), n));
  std::vector<Eigen::MatrixXd> l, t;  // reduced mass matrices at each row
  double cross = 0, square = 0;
  for (Index r = 0; r < positions.rows(); ++r) {
    const Eigen::JacobiSVD<Eigen::MatrixXd> svd(constraint_jacobian(spec, positions.row(r)),
                                                Eigen::ComputeFullV);
    const Eigen::MatrixXd tangent = svd.matrixV().rightCols(n - svd.rank());
    l.push_back(tangent.transpose() * mass * tangent);
    t.push_back(tangent.transpose() * truth * tangent);
    cross += l.back().cwiseProduct(t.back()).sum();
    square += l.back().squaredNorm();
  }
  const double scale = cross / square;
  double off = 0, size = 0;
  for (std::size_t r = 0; r < l.size(); ++r) {
    off += (scale * l[r] - t[r]).squaredNorm();
    size += t[r].squaredNorm();
  }
  return std::sqrt(off / size);
}

}  // namespace hnn::nn
