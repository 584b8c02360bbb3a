// The commands that read a trained run and write beside it (run.h): `hnn rollout`, from the
// run's test states or given ones (checked against the system, or moved onto its constraints),
// and `hnn reversibility`. Training and evaluating a run are in run.cpp.
#include <fmt/format.h>

#include "tasks/data/initial_states.h"
#include "tasks/run.h"

namespace hnn::tasks {

namespace fs = std::filesystem;
using nlohmann::json;

RolloutWritten write_rollout(const fs::path& run_dir, const RolloutCommand& command) {
  const LoadedRun loaded = load_run(run_dir, command.data_file);
  RolloutRequest request = command.request;
  const std::vector<std::string> names = loaded.run->state_names();
  if (!command.states.empty()) request.initial_states = states_from_values(command.states, names);
  if (!command.states_file.empty())
    request.initial_states = states_from_file(command.states_file, names);
  std::vector<std::string> notes;
  if (request.initial_states.rows() > 0) {
    request.initial_states =
        loaded.run->given_states(std::move(request.initial_states), command.project, notes);
  } else {
    HNN_TASKS_CHECK(!command.project,
                    "--project moves given states (--state, --states) onto the constraints; the "
                    "run's own test states are on them");
  }
  RolloutOutput output = loaded.run->rollout(request);
  notes.insert(notes.end(), output.notes.begin(), output.notes.end());
  const fs::path path = command.out.empty()
                            ? run_dir / fmt::format("rollout_{}.csv", request.integrator)
                            : command.out;
  RunFolder(path.parent_path().empty() ? "." : path.parent_path())
      .write_text(path.filename().string(), output.csv);
  return {.path = path, .trajectories = output.trajectories, .notes = std::move(notes)};
}

json reversibility(const fs::path& run_dir, const ReversibilityOptions& options,
                   const std::string& data_file) {
  const LoadedRun loaded = load_run(run_dir, data_file);
  ReversibilityOptions o = options;
  if (o.t_end <= 0) o.t_end = loaded.run->rollout_span();
  json result =
      measure_reversibility(loaded.run->dynamics(), loaded.run->rollout_states(o.trajectories), o);
  result.update({{"task", loaded.settings.task},
                 {"model", nn::to_string(loaded.settings.model)},
                 {"space", loaded.run->space()}});
  RunFolder(run_dir).write_text("reversibility.json", result.dump(2) + "\n");
  return result;
}

}  // namespace hnn::tasks
