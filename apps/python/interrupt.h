#pragma once
// Ctrl-C during training from Python: while an Interrupt lives, SIGINT asks the training loop to
// stop after its current step (tasks/train/stop.h) instead of reaching Python's handler, which
// could not run while the GIL is released. Python's handler is restored when it ends.

#include <signal.h>

#include "tasks/train/stop.h"

namespace hnn::python {

class Interrupt {
 public:
  Interrupt();
  ~Interrupt();
  Interrupt(const Interrupt&) = delete;
  Interrupt& operator=(const Interrupt&) = delete;

  /// The signal the training loop polls (LoopOptions::stop, RunOptions::stop).
  tasks::StopSignal* signal();
  /// Raises KeyboardInterrupt in Python (the GIL held): training stopped on request.
  [[noreturn]] static void raise_keyboard_interrupt();

 private:
  struct sigaction previous_ {};
};

}  // namespace hnn::python
