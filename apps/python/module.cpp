// The compiled module _hnn of the package hnn (apps/python/hnn/__init__.py): models, systems,
// runs, and the library's errors as Python exceptions.

#include <pybind11/pybind11.h>

#include "apps/python/arrays.h"
#include "apps/python/model.h"
#include "apps/python/runs.h"
#include "apps/python/systems.h"
#include "autodiff/check.h"
#include "autodiff/parallel.h"
#include "nn/parameter_file.h"
#include "physics/types.h"
#include "tasks/error.h"
#include "tasks/train/stop.h"

namespace py = pybind11;

PYBIND11_MODULE(_hnn, m) {
  m.doc() = "hnn's library from Python: models, systems and runs (docs/python.md)";
  // hnn.Error: the library's one-line messages on bad input (a ValueError); a diverged
  // training run is a RuntimeError.
  static py::exception<hnn::python::InputError> error(m, "Error", PyExc_ValueError);
  error.attr("__doc__") =
      "Bad input to hnn (an array, an option, a file): one line saying what "
      "and where. A ValueError.";
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const hnn::tasks::TrainingDiverged& e) {
      PyErr_SetString(PyExc_RuntimeError, e.what());
    } catch (const hnn::tasks::Error& e) {
      error(e.what());
    } catch (const hnn::ad::Error& e) {
      error(e.what());
    } catch (const hnn::nn::ParameterFileError& e) {
      error(e.what());
    } catch (const hnn::physics::DataError& e) {
      error(e.what());
    } catch (const std::invalid_argument& e) {  // InputError and the libraries' checks
      error(e.what());
    }
  });
  m.def("set_threads", &hnn::ad::set_num_threads, py::arg("n"),
        "Threads of the engine's fused kernels (the hnn program's --threads)");
  m.def("threads", &hnn::ad::num_threads);
  m.def(
      "_state_copies", [] { return hnn::python::state_copies.load(); },
      "How many state arrays were copied (converted) so far; for tests");
  hnn::python::bind_model(m);
  hnn::python::bind_systems(m);
  hnn::python::bind_runs(m);
  hnn::python::bind_autodiff(m);
}
