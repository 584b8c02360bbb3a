// hnn.autodiff: derivatives of the library's own functions at a batch of states, to any order: a
// model's learned scalar (an HNN's H, an LNN's L) and its field's Jacobian by the engine
// (autodiff/functional.h row_jacobian); a system's H by physics/autodiff/hamiltonian_derivatives.h
// (the engine on the systems' H written with its ops, GiNaC on an expression's).

#include <fmt/format.h>

#include "apps/python/arrays.h"
#include "apps/python/model.h"
#include "autodiff/functional.h"
#include "autodiff/tape.h"
#include "nn/hnn.h"
#include "nn/lnn.h"
#include "physics/autodiff/hamiltonian_derivatives.h"

namespace hnn::python {

namespace {

constexpr int kMaxOrder = 6;  // dim^order entries a state: 6 keeps a 6-D state under 50,000

// The model's learned scalar on the tape: an HNN's H (column 0 of its MLP), an LNN's L.
template <typename T>
ad::Var<T> learned_scalar(const nn::DynamicsModel<T>& m, const ad::Var<T>& x) {
  if (const auto* hnn = dynamic_cast<const nn::Hnn<T>*>(&m);
      hnn != nullptr && m.config().field != nn::FieldType::kConservative)
    return hnn->energy(x);
  if (const auto* lnn = dynamic_cast<const nn::Lnn<T>*>(&m)) return lnn->lagrangian(x);
  throw InputError(fmt::format("autodiff: a {} model learns no scalar H or L", m.name()));
}

// Row-wise derivatives of y (R x m) in x, `order` times: R x (m dim^order), each new index last.
template <typename T>
Matrix<T> row_derivatives(ad::Var<T> y, const ad::Var<T>& x, int order) {
  for (int k = 0; k < order; ++k)
    y = ad::row_jacobian(y, x, {.create_graph = k + 1 < order, .allow_unused = true});
  return y.value();
}

void check_order(int order) {
  if (order < 0 || order > kMaxOrder)
    throw InputError(fmt::format("autodiff: order must be 0 to {}, got {}", kMaxOrder, order));
}

std::vector<py::ssize_t> shape(Eigen::Index rows, std::initializer_list<Eigen::Index> outputs,
                               Eigen::Index dim, int order) {
  std::vector<py::ssize_t> s{rows};
  for (Eigen::Index o : outputs) s.push_back(o);
  for (int k = 0; k < order; ++k) s.push_back(dim);
  return s;
}

}  // namespace

py::array Model::derivative(const py::handle& x, int order) const {
  check_order(order);
  return visit([&]<typename T>(const nn::DynamicsModel<T>& m) {
    const StatesIn<T> states(x, "x", m.dim());
    Matrix<T> d;
    {
      py::gil_scoped_release free;
      ad::TapeScope scope;
      const ad::Var<T> xv = ad::Var<T>::variable(states.view());
      d = row_derivatives(learned_scalar(m, xv), xv, order);
    }
    return to_array(d, shape(states.rows(), {}, m.dim(), order));
  });
}

py::array Model::field_jacobian(const py::handle& x) const {
  return visit([&]<typename T>(const nn::DynamicsModel<T>& m) {
    const StatesIn<T> states(x, "x", m.dim());
    Matrix<T> j;
    {
      py::gil_scoped_release free;
      ad::TapeScope scope;
      const ad::Var<T> xv = ad::Var<T>::variable(states.view());
      j = row_derivatives(m.time_derivative(xv), xv, 1);
    }
    return to_array(j, shape(states.rows(), {m.dim()}, m.dim(), 1));
  });
}

void bind_autodiff(py::module_& m) {
  m.def("_system_derivative", [](const physics::System& s, const py::handle& x, int order) {
    check_order(order);
    const StatesIn<double> states(x, "x", s.dim());
    physics::Batch d;
    {
      py::gil_scoped_release free;
      d = physics::hamiltonian_derivatives(s, states.view(), order);
    }
    return to_array(d, shape(states.rows(), {}, s.dim(), order));
  });
}

}  // namespace hnn::python
