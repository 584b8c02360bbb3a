#pragma once
// Internal to tasks/: the experiments' factories, one file each, listed by the registry
// (task.cpp).

#include <memory>

#include "tasks/task.h"

namespace hnn::tasks {

std::unique_ptr<Task> make_spring_task();                // spring.cpp
std::unique_ptr<Task> make_pendulum_task();              // pendulum.cpp
std::unique_ptr<Task> make_real_pendulum_task();         // real_pendulum.cpp
std::unique_ptr<Task> make_two_body_task();              // nbody.cpp
std::unique_ptr<Task> make_three_body_task();            // nbody.cpp
std::unique_ptr<Task> make_pixel_pendulum_task();        // pixel_pendulum.cpp
std::unique_ptr<Task> make_damped_spring_task();         // damped_spring.cpp
std::unique_ptr<Task> make_double_pendulum_task();       // double_pendulum.cpp
std::unique_ptr<Task> make_real_double_pendulum_task();  // real_double_pendulum.cpp
std::unique_ptr<Task> make_data_task();                  // data_task.cpp

}  // namespace hnn::tasks
