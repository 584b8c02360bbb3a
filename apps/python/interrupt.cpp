#include "apps/python/interrupt.h"

#include <pybind11/pybind11.h>

namespace hnn::python {

namespace {

// A signal handler reaches only globals: the one training from Python at a time (the GIL lets
// one thread start training; the loop is not re-entered while it runs).
tasks::StopSignal g_stop;

extern "C" void on_interrupt(int) { g_stop.requested = true; }

}  // namespace

Interrupt::Interrupt() {
  g_stop.requested = false;
  struct sigaction action = {};
  action.sa_handler = on_interrupt;
  sigemptyset(&action.sa_mask);
  sigaction(SIGINT, &action, &previous_);
}

Interrupt::~Interrupt() { sigaction(SIGINT, &previous_, nullptr); }

tasks::StopSignal* Interrupt::signal() { return &g_stop; }

void Interrupt::raise_keyboard_interrupt() {
  PyErr_SetNone(PyExc_KeyboardInterrupt);
  throw pybind11::error_already_set();
}

}  // namespace hnn::python
