// Generalised coordinates of the constrained systems that are not chains (body_coordinates.h).
#include "physics/constrained/body_coordinates.h"

#include <fmt/format.h>

#include <Eigen/Dense>
#include <array>
#include <cmath>
#include <stdexcept>

namespace hnn::physics::constrained {
namespace {

// A value along a path s -> q + s u as its Taylor coefficients to second order,
// v + d s + dd s^2: the positions' value, velocity J u and half their second derivative in one
// pass (a second-order Jet in the manner of Ceres' first-order ones).
struct Jet {
  double v = 0.0, d = 0.0, dd = 0.0;
};

Jet operator+(Jet a, Jet b) { return {a.v + b.v, a.d + b.d, a.dd + b.dd}; }
Jet operator-(Jet a, Jet b) { return {a.v - b.v, a.d - b.d, a.dd - b.dd}; }
Jet operator*(Jet a, Jet b) {
  return {a.v * b.v, a.v * b.d + a.d * b.v, a.v * b.dd + a.d * b.d + a.dd * b.v};
}
Jet operator*(double c, Jet a) { return {c * a.v, c * a.d, c * a.dd}; }
Jet sine(Jet a) {
  const double s = std::sin(a.v), c = std::cos(a.v);
  return {s, c * a.d, c * a.dd - s * a.d * a.d / 2};
}
Jet cosine(Jet a) {
  const double s = std::sin(a.v), c = std::cos(a.v);
  return {c, -s * a.d, -s * a.dd - c * a.d * a.d / 2};
}

using Jets = std::vector<Jet>;
using Frame = std::array<std::array<Jet, 3>, 3>;  // a rotation matrix, [row][column]

Jets along(const Eigen::VectorXd& q, const Eigen::VectorXd& u) {
  Jets out(std::size_t(q.size()));
  for (Eigen::Index i = 0; i < q.size(); ++i) out[std::size_t(i)] = {q[i], u[i], 0.0};
  return out;
}

PositionJet unpack(const Jets& x) {
  PositionJet out{Eigen::VectorXd(x.size()), Eigen::VectorXd(x.size()), Eigen::VectorXd(x.size())};
  for (std::size_t i = 0; i < x.size(); ++i) {
    out.x0[Eigen::Index(i)] = x[i].v;
    out.x1[Eigen::Index(i)] = x[i].d;
    out.x2[Eigen::Index(i)] = x[i].dd;
  }
  return out;
}

// The peer's spherical angles (systems.h, spherical_point): per anchored point, azimuth phi and
// polar theta, x = pivot + l (-cos theta, sin phi sin theta, cos phi sin theta).
BodyMap spherical_map(const ConstrainedSpec& spec) {
  const std::vector<AnchorConstraint> anchors = spec.anchors;
  const int bobs = static_cast<int>(anchors.size());
  BodyMap map{.dof = 2 * bobs, .angles = 2 * bobs, .positions = {}, .coordinates = {}};
  map.positions = [anchors](const Eigen::VectorXd& q, const Eigen::VectorXd& u) {
    const Jets a = along(q, u);
    Jets x(3 * anchors.size());
    for (std::size_t b = 0; b < anchors.size(); ++b) {
      const Jet phi = a[2 * b], theta = a[2 * b + 1];
      const double l = anchors[b].length;
      const Eigen::VectorXd& pivot = anchors[b].anchor;
      const std::size_t i = 3 * std::size_t(anchors[b].i);
      x[i] = Jet{pivot[0]} - l * cosine(theta);
      x[i + 1] = Jet{pivot[1]} + l * (sine(phi) * sine(theta));
      x[i + 2] = Jet{pivot[2]} + l * (cosine(phi) * sine(theta));
    }
    return unpack(x);
  };
  map.coordinates = [anchors](const double* x) {
    Eigen::VectorXd q(2 * anchors.size());
    for (std::size_t b = 0; b < anchors.size(); ++b) {
      const double* p = x + 3 * anchors[b].i;
      const Eigen::VectorXd& pivot = anchors[b].anchor;
      const double rx = p[0] - pivot[0], ry = p[1] - pivot[1], rz = p[2] - pivot[2];
      q[Eigen::Index(2 * b)] = std::atan2(ry, rz);
      q[Eigen::Index(2 * b + 1)] = std::atan2(std::hypot(ry, rz), -rx);
    }
    return q;
  };
  return map;
}

// R = Rz(a) Rx(b) Rz(c), as euler_frame (rigid_bodies.h).
Frame euler_rotation(Jet a, Jet b, Jet c) {
  const Jet ca = cosine(a), sa = sine(a), cb = cosine(b), sb = sine(b), cc = cosine(c),
            sc = sine(c);
  const Jet zero{};
  const Frame rz_a{{{ca, zero - sa, zero}, {sa, ca, zero}, {zero, zero, Jet{1.0}}}};
  const Frame rx_b{{{Jet{1.0}, zero, zero}, {zero, cb, zero - sb}, {zero, sb, cb}}};
  const Frame rz_c{{{cc, zero - sc, zero}, {sc, cc, zero}, {zero, zero, Jet{1.0}}}};
  const auto product = [](const Frame& l, const Frame& r) {
    Frame out{};
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        for (int k = 0; k < 3; ++k) out[i][j] = out[i][j] + l[i][k] * r[k][j];
    return out;
  };
  return product(product(rz_a, rx_b), rz_c);
}

// A rigid body's 4 points (rigid_body_spec: the centre, then centre + R e_k): q = (ZXZ Euler
// angles, centre) for a free body; a pinned one's centre follows from its pin, q = the angles.
BodyMap rigid_map(const ConstrainedSpec& spec) {
  const bool pinned = !spec.pins.empty();
  // The pinned point's body offset w (sum_k w_k e_k) and its place in space: the centre is
  // point - R w.
  Eigen::Vector3d offset = Eigen::Vector3d::Zero(), pin = Eigen::Vector3d::Zero();
  if (pinned) {
    offset = spec.pins[0].weights.tail(3);
    pin = spec.pins[0].point;
  }
  BodyMap map{.dof = pinned ? 3 : 6, .angles = 3, .positions = {}, .coordinates = {}};
  map.positions = [pinned, offset, pin](const Eigen::VectorXd& q, const Eigen::VectorXd& u) {
    const Jets a = along(q, u);
    const Frame r = euler_rotation(a[0], a[1], a[2]);
    std::array<Jet, 3> centre;
    for (int k = 0; k < 3; ++k) {
      if (pinned) {
        centre[k] = Jet{pin[k]};
        for (int axis = 0; axis < 3; ++axis) centre[k] = centre[k] - offset[axis] * r[k][axis];
      } else {
        centre[k] = a[std::size_t(3 + k)];
      }
    }
    Jets x(12);
    for (int k = 0; k < 3; ++k) {
      x[std::size_t(k)] = centre[k];
      for (int axis = 0; axis < 3; ++axis)
        x[std::size_t(3 * (axis + 1) + k)] = centre[k] + r[k][axis];
    }
    return unpack(x);
  };
  map.coordinates = [pinned](const double* x) {
    Eigen::Matrix3d r;  // column k: tip k relative to the centre
    for (int axis = 0; axis < 3; ++axis)
      for (int k = 0; k < 3; ++k) r(k, axis) = x[3 * (axis + 1) + k] - x[k];
    Eigen::VectorXd q(pinned ? 3 : 6);
    q[0] = std::atan2(r(0, 2), -r(1, 2));
    q[1] = std::atan2(std::hypot(r(0, 2), r(1, 2)), r(2, 2));
    q[2] = std::atan2(r(2, 0), r(2, 1));
    if (!pinned) q.tail(3) = Eigen::Vector3d(x[0], x[1], x[2]);
    return q;
  };
  return map;
}

bool all_anchored(const ConstrainedSpec& spec) {
  if (spec.dim != 3 || !spec.distances.empty() || !spec.pins.empty()) return false;
  if (int(spec.anchors.size()) != spec.points) return false;
  for (int i = 0; i < spec.points; ++i)
    if (spec.anchors[std::size_t(i)].i != i) return false;
  return true;
}

bool one_rigid_body(const ConstrainedSpec& spec) {
  return spec.dim == 3 && spec.points == 4 && spec.distances.size() == 6 && spec.anchors.empty() &&
         spec.pins.size() <= 1;
}

}  // namespace

BodyMap body_map(const ConstrainedSystem& system) {
  const ConstrainedSpec& spec = system.spec();
  if (all_anchored(spec)) return spherical_map(spec);
  if (one_rigid_body(spec)) return rigid_map(spec);
  throw std::invalid_argument(fmt::format(
      "body_map: {} is neither bobs on tethers nor one rigid body, the systems that have body "
      "coordinates here (a chain's angles are in chain_angles.h)",
      spec.name));
}

BodyCoordinates::BodyCoordinates(ConstrainedSystem cartesian)
    : cartesian_(std::move(cartesian)), map_(body_map(cartesian_)) {}

Eigen::MatrixXd BodyCoordinates::jacobian(const Eigen::VectorXd& q) const {
  Eigen::MatrixXd j(cartesian_.configuration_dim(), map_.dof);
  for (int c = 0; c < map_.dof; ++c)
    j.col(c) = map_.positions(q, Eigen::VectorXd::Unit(map_.dof, c)).x1;
  return j;
}

Batch BodyCoordinates::to_cartesian(const BatchView& x, Batch* curvature) const {
  const int n = map_.dof, nd = cartesian_.configuration_dim();
  Batch z(x.rows(), 2 * nd);
  if (curvature) curvature->resize(x.rows(), nd);
  for (Eigen::Index r = 0; r < x.rows(); ++r) {
    const PositionJet p =
        map_.positions(x.row(r).head(n).transpose(), x.row(r).tail(n).transpose());
    z.row(r).head(nd) = p.x0.transpose();
    z.row(r).tail(nd) = p.x1.transpose();
    if (curvature) curvature->row(r) = 2.0 * p.x2.transpose();
  }
  return z;
}

Batch BodyCoordinates::from_cartesian(const Batch& z) const {
  const int n = map_.dof, nd = cartesian_.configuration_dim();
  if (z.cols() != 2 * nd)
    throw std::invalid_argument(fmt::format("{}: from_cartesian needs {} columns (x, v), got {}",
                                            name(), 2 * nd, z.cols()));
  Batch x(z.rows(), 2 * n);
  for (Eigen::Index r = 0; r < z.rows(); ++r) {
    const Eigen::VectorXd q = map_.coordinates(&z(r, 0));
    x.row(r).head(n) = q.transpose();
    x.row(r).tail(n) =
        jacobian(q).colPivHouseholderQr().solve(z.row(r).tail(nd).transpose()).transpose();
  }
  return x;
}

Eigen::VectorXd BodyCoordinates::hamiltonian_batch(const BatchView& x) const {
  return cartesian_.hamiltonian_batch(to_cartesian(x));
}

void BodyCoordinates::vector_field(const BatchView& x, Batch& dxdt) const {
  const int n = map_.dof;
  Batch curvature;  // f''[qdot, qdot] per row, from the same Jets as the positions
  const Batch z = to_cartesian(x, &curvature);
  const Batch a = cartesian_.acceleration(z);
  dxdt.resize(x.rows(), 2 * n);
  for (Eigen::Index r = 0; r < x.rows(); ++r) {
    // a = J qddot + f''[qdot, qdot].
    const Eigen::VectorXd rest = (a.row(r) - curvature.row(r)).transpose();
    dxdt.row(r).head(n) = x.row(r).tail(n);
    dxdt.row(r).tail(n) =
        jacobian(x.row(r).head(n).transpose()).colPivHouseholderQr().solve(rest).transpose();
  }
}

Batch BodyCoordinates::sample_initial_states(int n, std::mt19937_64& rng) const {
  return from_cartesian(cartesian_.sample_initial_states(n, rng));
}

}  // namespace hnn::physics::constrained
