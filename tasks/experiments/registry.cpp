#include "tasks/experiments/registry.h"

#include <functional>
#include <utility>

namespace hnn::tasks {

namespace {

using Factory = std::function<std::unique_ptr<Task>()>;

std::vector<std::pair<std::string, Factory>> make_registry() {
  std::vector<std::pair<std::string, Factory>> tasks = {
      {"spring", make_spring_task},
      {"pendulum", make_pendulum_task},
      {"real-pendulum", make_real_pendulum_task},
      {"two-body", make_two_body_task},
      {"three-body", make_three_body_task},
      {"pixel-pendulum", make_pixel_pendulum_task},
      {"damped-spring", make_damped_spring_task},
      {"double-pendulum", make_double_pendulum_task},
      {"real-double-pendulum", make_real_double_pendulum_task},
      {"henon-heiles", make_henon_heiles_task},
      {"pendulum-scattered", make_pendulum_scattered_task},
      {"double-pendulum-scattered", make_double_pendulum_scattered_task}};
  for (const std::string& name : constrained_task_names())
    tasks.emplace_back(name, [name] { return make_constrained_task(name); });
  tasks.emplace_back("data", make_data_task);
  return tasks;
}

const std::vector<std::pair<std::string, Factory>>& registry() {
  static const std::vector<std::pair<std::string, Factory>> tasks = make_registry();
  return tasks;
}

}  // namespace

std::vector<std::string> task_names() {
  std::vector<std::string> names;
  for (const auto& [name, factory] : registry()) names.push_back(name);
  return names;
}

std::vector<std::string> paper_task_names() {
  return {"spring", "pendulum", "real-pendulum", "two-body", "three-body", "pixel-pendulum"};
}

std::unique_ptr<Task> make_task(const std::string& name) {
  for (const auto& [known, factory] : registry())
    if (known == name) return factory();
  std::string known;
  for (const std::string& n : task_names()) known += (known.empty() ? "" : ", ") + n;
  throw Error(fmt::format("unknown task '{}' (known: {})", name, known));
}

std::unique_ptr<FieldTask> make_field_task(const std::string& name) {
  std::unique_ptr<Task> task = make_task(name);
  HNN_TASKS_CHECK(dynamic_cast<FieldTask*>(task.get()) != nullptr,
                  "task '{}' does not learn a field from states", name);
  return std::unique_ptr<FieldTask>(static_cast<FieldTask*>(task.release()));
}

Dataset build_dataset(const std::string& task, std::uint64_t seed) {
  return make_field_task(task)->build_dataset(seed);
}

}  // namespace hnn::tasks
