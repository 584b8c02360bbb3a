// hnn compare's named studies (studies.h).

#include "apps/hnn/compare/studies.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <stdexcept>

#include "tasks/data/data_files.h"

namespace hnn::app {

Group crossed(std::vector<std::string> tasks, std::vector<std::string> models,
              std::vector<std::string> losses) {
  Group g;
  g.tasks = std::move(tasks);
  g.models = std::move(models);
  g.losses = std::move(losses);
  return g;
}

namespace {

// The default study: the tasks where each family matters, each at its peer's protocol
// (docs/compare.md). Names this hnn lacks become skipped rows saying so, not errors.
std::vector<Group> default_study() {
  // SRNN's three-body: the HNN paper's system sampled at dt = 1 (its 100 + 32 trajectories of 10
  // points), trained through leapfrog on windows of 5 points, batch 32 (docs/families.md).
  Group three_body = crossed({"three-body"}, {"baseline", "hnn"}, {"derivative", "rollout"});
  three_body.keys["settings"] = {{"setup", "srnn"}};
  three_body.rollout_keys = {
      {"integrator", "leapfrog"}, {"horizon", 4}, {"batch", 32}, {"steps", 5000}};
  three_body.headline = "stretch_position_error";
  three_body.metrics = {"truth_leapfrog_position_error", "valid_prediction_time"};
  // Where the rollout loss wins: the spring sampled every time unit, noisy (docs/families.md).
  Group coarse_spring = crossed({"spring"}, {"baseline", "hnn"}, {"derivative", "rollout"});
  coarse_spring.keys["settings"] = {{"sample_dt", 1.0}, {"t_end", 6}};
  coarse_spring.rollout_keys = {{"integrator", "leapfrog"}, {"horizon", 1}};
  coarse_spring.headline = "stretch_state_mse";
  coarse_spring.metrics = {"truth_leapfrog_state_mse"};
  // The D-HNN paper's real pendulum (their analysis notebook): the Lipson file through the data
  // task, 80/20 in time, width 256, batch 128, 5000 steps at 5e-3; the energy MSE of
  // H = 2.4 (1 - cos q) + p^2 along the held-out trajectory rolled out from its first state.
  Group dhnn_real = crossed({"data"}, {"baseline", "hnn", "dhnn"}, {"derivative"});
  dhnn_real.keys = {{"data", tasks::default_data_path("lipson/real_pend_h_1.txt")},
                    {"hidden", {256, 256}},
                    {"batch", 128},
                    {"steps", 5000},
                    {"lr", 5e-3},
                    {"hamiltonian", "2.4*(1 - cos(o)) + v^2"},
                    {"settings", {{"energy_t_end", 20}, {"rollouts", 15}}}};
  dhnn_real.headline = "held_out_energy_mse";
  dhnn_real.metrics = {"valid_prediction_time"};
  return {crossed({"real-pendulum", "damped-spring"}, {"baseline", "hnn", "dhnn"}, {"derivative"}),
          dhnn_real, crossed({"double-pendulum"}, {"baseline", "hnn", "lnn"}, {"derivative"}),
          three_body, coarse_spring};
}

// Finzi et al.'s constrained systems at their protocol, each task's default (8,000 steps through
// RK4 over 5-output chunks, L1): the chains in angles for the HNN, their HNN (hnn-mass) and the
// LNN, in Cartesian coordinates for the baseline, CHNN and CLNN; the other systems in their body
// coordinates for their HNN (the free HNN there is a row saying why it is skipped), Cartesian for
// the baseline and CHNN. Each run trains a 3 x 256 network for 8,000 steps through RK4 and solves
// the constraints' multipliers (or a mass matrix) at every stage, so this is a study of its own,
// not the default's (docs/tasks.md, "Constrained systems").
std::vector<Group> constrained_study() {
  Group chains = crossed({"chain-pendulum-2", "chain-pendulum-3", "chain-pendulum-5"},
                         {"baseline", "hnn", "hnn-mass", "lnn", "chnn", "clnn"}, {"rollout"});
  chains.metrics = {"cartesian_error_floor", "cartesian_error_failed"};
  Group bodies = crossed({"gyroscope", "rotor", "magnet-pendulum", "coupled-pendulums"},
                         {"baseline", "hnn", "hnn-mass", "chnn"}, {"rollout"});
  bodies.metrics = chains.metrics;
  // Their data efficiency: 10 training trajectories instead of 800, so their batch of
  // min(200, trajectories) is all 10 chunks and their 2000 epochs are 2000 steps.
  Group few = crossed({"chain-pendulum-2"}, {"hnn", "hnn-mass", "chnn"}, {"rollout"});
  few.keys = {{"settings", {{"trajectories", 10}}}, {"batch", 10}, {"steps", 2000}};
  few.metrics = chains.metrics;
  return {chains, bodies, few};
}

}  // namespace

std::vector<std::string> study_names() { return {"default", "constrained"}; }

std::vector<Group> named_study(const std::string& name) {
  if (name == "default") return default_study();
  if (name == "constrained") return constrained_study();
  throw std::invalid_argument(fmt::format("compare: --study: unknown study '{}' (known: {})", name,
                                          fmt::join(study_names(), ", ")));
}

}  // namespace hnn::app
