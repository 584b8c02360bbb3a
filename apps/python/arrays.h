#pragma once
// NumPy arrays in and out of the package: states [batch, dim] checked once (dimensions, width,
// dtype, emptiness, NaN or infinity) with one line naming the argument, and results returned as
// new arrays. A C-contiguous array of the computation's dtype is read in place (StatesIn); any
// other numeric dtype and layout (Fortran order, slices) is converted once, as NumPy-based
// libraries do.

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <atomic>
#include <stdexcept>
#include <string_view>
#include <vector>

#include "autodiff/var.h"
#include "physics/integrator.h"

namespace hnn::python {

namespace py = pybind11;

/// Bad input from Python: hnn.Error, a ValueError (module.cpp registers it).
class InputError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

template <typename T>
using Matrix = ad::Matrix<T>;

/// `obj` as a [rows, cols] matrix of T, a copy; throws InputError naming `what` unless it is a
/// 2-D numeric array with `cols` columns, at least one row, and only finite values.
template <typename T>
Matrix<T> states(const py::handle& obj, std::string_view what, Eigen::Index cols);

/// States checked as states() checks them, for the functions that only read them: a
/// C-contiguous, aligned array of T in native byte order is read in place through view() (its
/// rows are laid out as Matrix<T>'s, row-major), and kept alive meanwhile; any other is
/// converted once, by states().
template <typename T>
class StatesIn {
 public:
  StatesIn(const py::handle& obj, std::string_view what, Eigen::Index cols);
  /// The states, over NumPy's buffer or the copy; valid while *this lives.
  ad::MatrixView<T> view() const;
  Eigen::Index rows() const { return rows_; }

 private:
  py::object array_;         // the caller's array, kept alive while read in place
  const T* data_ = nullptr;  // its buffer when read in place (view() may run without the GIL)
  Matrix<T> copy_;           // the converted states otherwise
  Eigen::Index rows_, cols_;
};

/// How many state arrays states() has copied since the module was loaded: tests/python read it
/// (hnn._hnn._state_copies) to check that an array read in place is not copied.
extern std::atomic<long> state_copies;

/// `obj` as a 3-D array [times, batch, dim] (as simulate and rollout return), one matrix
/// [times, dim] per trajectory; throws InputError naming `what` like states().
std::vector<physics::Batch> trajectories(const py::handle& obj, std::string_view what,
                                         Eigen::Index times, Eigen::Index dim);
/// `obj` as a 1-D array of finite times, at least one; throws InputError naming `what`.
std::vector<double> times(const py::handle& obj, std::string_view what);

/// A new NumPy array holding `m` (its shape, its scalar type).
template <typename T>
py::array to_array(const Matrix<T>& m);
/// A new 1-D NumPy array.
py::array to_array(const Eigen::VectorXd& v);
template <typename T>
py::array to_array(const Matrix<T>& m, std::vector<py::ssize_t> shape);
/// A trajectory's states as one array [times, batch, dim].
py::array to_array(const physics::Trajectory& path);

}  // namespace hnn::python
