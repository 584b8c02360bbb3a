#include "apps/python/arrays.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <cmath>
#include <cstdint>
#include <string>

namespace hnn::python {

namespace {

std::string shape_text(const py::array& a) {
  std::vector<py::ssize_t> shape(a.shape(), a.shape() + a.ndim());
  return fmt::format("({}{})", fmt::join(shape, ", "), shape.size() == 1 ? "," : "");  // NumPy's
}

// `obj` as an array of numbers (bool, strings and objects refused), not yet converted.
py::array numeric(const py::handle& obj, std::string_view what) {
  py::array a = py::array::ensure(obj);
  if (!a) {
    throw InputError(fmt::format("{}: expected an array of numbers, got a {}", what,
                                 std::string(py::str(obj.get_type().attr("__name__")))));
  }
  const char kind = a.dtype().kind();
  if (kind != 'i' && kind != 'u' && kind != 'f') {
    throw InputError(fmt::format("{}: expected an array of numbers, got dtype {}", what,
                                 std::string(py::str(a.dtype()))));
  }
  return a;
}

template <typename T>
void check_finite(const T* data, Eigen::Index rows, Eigen::Index cols, std::string_view what) {
  for (Eigen::Index i = 0; i < rows * cols; ++i) {
    if (!std::isfinite(data[i])) {
      throw InputError(
          fmt::format("{}: NaN or infinity at row {}, column {}", what, i / cols, i % cols));
    }
  }
}

// `a` (2-D, of dtype S) copied into `out` as T, reading its strides: one copy whatever the
// layout (Fortran order, slices). False when `a` is not of S or its strides are not whole,
// non-negative steps of S (then states() lets NumPy convert it first).
template <typename S, typename T>
bool copy_strided(const py::array& a, Matrix<T>& out) {
  constexpr auto size = py::ssize_t(sizeof(S));
  if (!py::isinstance<py::array_t<S>>(a)) return false;
  if (a.strides(0) < 0 || a.strides(1) < 0 || a.strides(0) % size || a.strides(1) % size)
    return false;
  using Source = Eigen::Matrix<S, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  using Steps = Eigen::Stride<Eigen::Dynamic, Eigen::Dynamic>;
  const Eigen::Map<const Source, Eigen::Unaligned, Steps> in(
      static_cast<const S*>(a.data()), a.shape(0), a.shape(1),
      Steps(a.strides(0) / size, a.strides(1) / size));
  out = in.template cast<T>();
  return true;
}

// `obj` as a numeric 2-D array of `cols` columns and at least one row, not yet converted.
py::array state_array(const py::handle& obj, std::string_view what, Eigen::Index cols) {
  py::array a = numeric(obj, what);
  if (a.ndim() != 2) {
    throw InputError(fmt::format("{}: expected a 2-D array [batch, {}], got shape {}", what, cols,
                                 shape_text(a)));
  }
  if (a.shape(1) != cols) {
    throw InputError(
        fmt::format("{}: expected {} columns (q then p), got shape {}", what, cols, shape_text(a)));
  }
  if (a.shape(0) == 0) throw InputError(fmt::format("{}: the array is empty (no rows)", what));
  return a;
}

// Whether `a` can be read in place as a Matrix<T>: of T exactly (native byte order), aligned,
// C-contiguous (each row's values side by side, row after row: Matrix<T> is row-major).
template <typename T>
bool readable_in_place(const py::array& a) {
  return py::isinstance<py::array_t<T>>(a) && (a.flags() & py::array::c_style) != 0 &&
         (a.flags() & py::detail::npy_api::NPY_ARRAY_ALIGNED_) != 0;
}

}  // namespace

std::atomic<long> state_copies{0};

template <typename T>
Matrix<T> states(const py::handle& obj, std::string_view what, Eigen::Index cols) {
  const py::array a = state_array(obj, what, cols);
  // Copied once into the row-major matrix the library's functions take, converted on the way
  // from the common dtypes in any layout.
  ++state_copies;
  Matrix<T> out;
  if (!(copy_strided<double>(a, out) || copy_strided<float>(a, out) ||
        copy_strided<std::int64_t>(a, out) || copy_strided<std::int32_t>(a, out))) {
    const auto c = py::array_t<T, py::array::c_style | py::array::forcecast>::ensure(a);
    out = Eigen::Map<const Matrix<T>>(c.data(), a.shape(0), cols);
  }
  check_finite(out.data(), out.rows(), cols, what);
  return out;
}

template <typename T>
StatesIn<T>::StatesIn(const py::handle& obj, std::string_view what, Eigen::Index cols)
    : cols_(cols) {
  py::array a = state_array(obj, what, cols);
  rows_ = a.shape(0);
  if (readable_in_place<T>(a)) {
    check_finite(static_cast<const T*>(a.data()), rows_, cols, what);
    data_ = static_cast<const T*>(a.data());
    array_ = std::move(a);
  } else {
    copy_ = states<T>(a, what, cols);
  }
}

template <typename T>
ad::MatrixView<T> StatesIn<T>::view() const {
  if (data_ == nullptr) return copy_;
  return Eigen::Map<const Matrix<T>>(data_, rows_, cols_);
}

std::vector<physics::Batch> trajectories(const py::handle& obj, std::string_view what,
                                         Eigen::Index times, Eigen::Index dim) {
  const py::array a = numeric(obj, what);
  if (a.ndim() != 3 || a.shape(0) != times || a.shape(2) != dim) {
    throw InputError(fmt::format("{}: expected a 3-D array [{} times, batch, {}], got shape {}",
                                 what, times, dim, shape_text(a)));
  }
  if (a.shape(1) == 0)
    throw InputError(fmt::format("{}: the array is empty (no trajectories)", what));
  const auto c = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(a);
  const Eigen::Index batch = a.shape(1);
  std::vector<physics::Batch> paths(std::size_t(batch), physics::Batch(times, dim));
  for (Eigen::Index k = 0; k < times; ++k) {
    for (Eigen::Index b = 0; b < batch; ++b) {
      auto row = paths[std::size_t(b)].row(k);
      row = Eigen::Map<const Eigen::RowVectorXd>(c.data() + (k * batch + b) * dim, dim);
      if (!row.allFinite())
        throw InputError(
            fmt::format("{}: NaN or infinity at time {} of trajectory {}", what, k, b));
    }
  }
  return paths;
}

std::vector<double> times(const py::handle& obj, std::string_view what) {
  const py::array a = numeric(obj, what);
  if (a.ndim() != 1)
    throw InputError(
        fmt::format("{}: expected a 1-D array of times, got shape {}", what, shape_text(a)));
  if (a.shape(0) == 0) throw InputError(fmt::format("{}: the array is empty (no times)", what));
  const auto c = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(a);
  check_finite(c.data(), a.shape(0), 1, what);
  return {c.data(), c.data() + a.shape(0)};
}

template <typename T>
py::array to_array(const Matrix<T>& m, std::vector<py::ssize_t> shape) {
  py::array_t<T> out(shape);
  std::copy(m.data(), m.data() + m.size(), out.mutable_data());
  return out;
}

template <typename T>
py::array to_array(const Matrix<T>& m) {
  return to_array(m, {m.rows(), m.cols()});
}

py::array to_array(const Eigen::VectorXd& v) {
  py::array_t<double> out(v.size());
  std::copy(v.data(), v.data() + v.size(), out.mutable_data());
  return out;
}

py::array to_array(const physics::Trajectory& path) {
  const Eigen::Index times = Eigen::Index(path.states.size());
  const Eigen::Index rows = path.states.front().rows(), cols = path.states.front().cols();
  py::array_t<double> out({py::ssize_t(times), py::ssize_t(rows), py::ssize_t(cols)});
  for (Eigen::Index k = 0; k < times; ++k)
    std::copy(path.states[k].data(), path.states[k].data() + rows * cols,
              out.mutable_data() + k * rows * cols);
  return out;
}

template class StatesIn<float>;
template class StatesIn<double>;
template Matrix<float> states(const py::handle&, std::string_view, Eigen::Index);
template Matrix<double> states(const py::handle&, std::string_view, Eigen::Index);
template py::array to_array(const Matrix<float>&);
template py::array to_array(const Matrix<double>&);
template py::array to_array(const Matrix<float>&, std::vector<py::ssize_t>);
template py::array to_array(const Matrix<double>&, std::vector<py::ssize_t>);

}  // namespace hnn::python
