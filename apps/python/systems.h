#pragma once
// hnn.systems' compiled half (hnn/systems.py makes the systems).

#include <pybind11/pybind11.h>

namespace hnn::python {

void bind_systems(pybind11::module_& m);

}  // namespace hnn::python
