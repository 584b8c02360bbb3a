#pragma once
// hnn.train's compiled half: `hnn train`'s run from Python options, through the same option
// table (tasks/options/train_options.h) and run (tasks/run.h run_training).

#include <pybind11/pybind11.h>

namespace hnn::python {

void bind_runs(pybind11::module_& m);

}  // namespace hnn::python
