#pragma once
// Task 5, the pixel pendulum, among the tasks: its run gives its parts to the commands that only
// it has (the energy bump, Figure 4's comparison).

#include "tasks/pixel/figures.h"
#include "tasks/task.h"

namespace hnn::tasks {

inline constexpr const char* kPixelPendulum = "pixel-pendulum";

/// The config, frames, model and seed of a pixel-pendulum run (trained or loaded); throws Error
/// when `run` is of another task.
pixel::PixelParts pixel_parts(const TaskRun& run);

}  // namespace hnn::tasks
