#pragma once
// The experiments by name: every task hnn runs, one file each in this folder, and the lookups
// that the programs, the run end to end (tasks/run.h) and the studies make by name.

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "tasks/data/dataset.h"
#include "tasks/field/field_task.h"
#include "tasks/task.h"

namespace hnn::tasks {

/// The tasks by name: spring, pendulum, real-pendulum, two-body, three-body, pixel-pendulum (the
/// paper's), damped-spring (the dissipative-HNN paper's), double-pendulum (the LNN paper's),
/// real-double-pendulum (measured), henon-heiles, pendulum-scattered and
/// double-pendulum-scattered (the sampled-HNN paper's protocols: scattered states), the
/// constrained systems (constrained_task_names) and data (a user's own file). Throws Error naming
/// the known tasks for any other name.
std::unique_ptr<Task> make_task(const std::string& name);
std::vector<std::string> task_names();
/// The paper's six: what `hnn reproduce` runs by default.
std::vector<std::string> paper_task_names();

/// make_task(name) as a FieldTask; throws Error when the task learns something else.
std::unique_ptr<FieldTask> make_field_task(const std::string& name);
/// The dataset of a field task with its default settings and the given seed (tests, tools).
Dataset build_dataset(const std::string& task, std::uint64_t seed);

// The experiments' factories, one file each, listed by the registry (registry.cpp).
std::unique_ptr<Task> make_spring_task();                     // spring.cpp
std::unique_ptr<Task> make_pendulum_task();                   // pendulum.cpp
std::unique_ptr<Task> make_real_pendulum_task();              // real_pendulum.cpp
std::unique_ptr<Task> make_two_body_task();                   // nbody.cpp
std::unique_ptr<Task> make_three_body_task();                 // nbody.cpp
std::unique_ptr<Task> make_pixel_pendulum_task();             // pixel_pendulum.cpp
std::unique_ptr<Task> make_damped_spring_task();              // damped_spring.cpp
std::unique_ptr<Task> make_double_pendulum_task();            // double_pendulum.cpp
std::unique_ptr<Task> make_real_double_pendulum_task();       // real_double_pendulum.cpp
std::unique_ptr<Task> make_henon_heiles_task();               // scattered.cpp
std::unique_ptr<Task> make_pendulum_scattered_task();         // scattered.cpp
std::unique_ptr<Task> make_double_pendulum_scattered_task();  // scattered.cpp
std::unique_ptr<Task> make_data_task();                       // data_task.cpp
// constrained.cpp: Finzi et al.'s constrained systems, one task each (chain-pendulum-2..5,
// coupled-pendulums, magnet-pendulum, gyroscope, rotor).
std::vector<std::string> constrained_task_names();
std::unique_ptr<Task> make_constrained_task(const std::string& name);

}  // namespace hnn::tasks
