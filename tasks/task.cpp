#include "tasks/task.h"

#include <cstdlib>
#include <filesystem>

#include "tasks/pixel_pendulum.h"
#include "tasks/task_library.h"
#include "tasks/trajectories.h"

namespace hnn::tasks {

void Task::set_data_file(const std::string&) {
  throw Error(fmt::format("task '{}' does not read a data file (--data applies to real-pendulum)",
                          name()));
}

std::vector<std::string> preset_names() { return {"paper", "lean"}; }

TrainConfig train_config(const Task& task, const std::string& preset) {
  TrainConfig config = task.train_config();
  if (preset == "lean") {
    config.hidden = task.lean_hidden();
  } else if (preset != "paper") {
    throw Error(fmt::format("unknown preset '{}' (known: paper, lean)", preset));
  }
  return config;
}

std::vector<std::string> task_names() {
  return {"spring", "pendulum", "real-pendulum", "two-body", "three-body", "pixel-pendulum"};
}

std::unique_ptr<Task> make_task(const std::string& name) {
  if (name == "spring") return make_spring_task();
  if (name == "pendulum") return make_pendulum_task();
  if (name == "real-pendulum") return make_real_pendulum_task();
  if (name == "two-body") return make_two_body_task();
  if (name == "three-body") return make_three_body_task();
  if (name == pixel::kTaskName) return pixel::make_pixel_pendulum_task();
  std::string known;
  for (const std::string& n : task_names()) known += (known.empty() ? "" : ", ") + n;
  throw Error(fmt::format("unknown task '{}' (known: {})", name, known));
}

std::string default_data_path(const std::string& relative) {
  namespace fs = std::filesystem;
  // HNN_DATA_DIR overrides; else the source tree's data/ (a build), else the installed copy.
  if (const char* dir = std::getenv("HNN_DATA_DIR")) return (fs::path(dir) / relative).string();
  const fs::path source = fs::path(HNN_SOURCE_DATA_DIR) / relative;
  if (fs::exists(source)) return source.string();
  return (fs::path(HNN_INSTALL_DATA_DIR) / relative).string();
}

Dataset oscillator_dataset(const physics::System& system, std::uint64_t seed,
                           const OscillatorSettings& settings) {
  std::mt19937_64 rng(seed);
  const Batch x0 = system.sample_initial_states(settings.trajectories, rng);
  TrajectorySamples s = sample_trajectories(system, x0, settings.t_end, settings.points, 1e-10);
  add_noise(s.x, settings.noise, rng);  // targets stay the derivatives at the clean states
  const Eigen::Index cut = Eigen::Index(settings.trajectories / 2) * settings.points;
  Dataset d;
  std::tie(d.train_x, d.test_x) = split_rows(s.x, cut);
  std::tie(d.train_dxdt, d.test_dxdt) = split_rows(s.dxdt, cut);
  return d;
}

}  // namespace hnn::tasks
