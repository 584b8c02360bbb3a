#include "tasks/pixel/config.h"

#include <cmath>

#include "tasks/error.h"

namespace hnn::tasks::pixel {

nlohmann::json PixelConfig::to_json() const {
  return {{"trials", trials},
          {"frames_per_trial", frames_per_trial},
          {"test_fraction", test_fraction},
          {"ae_hidden", ae_hidden},
          {"hidden", hidden},
          {"steps", steps},
          {"batch_size", batch_size},
          {"learning_rate", learning_rate},
          {"weight_decay", weight_decay},
          {"dynamics_weight_decay", dynamics_weight_decay},
          {"hnn_weight", hnn_weight},
          {"rollout_frames", rollout_frames},
          {"rollout_trials", rollout_trials},
          {"rtol", rtol},
          {"atol", atol}};
}

PixelConfig PixelConfig::from_json(const nlohmann::json& j) {
  PixelConfig c;
  c.trials = j.at("trials");
  c.frames_per_trial = j.at("frames_per_trial");
  c.test_fraction = j.at("test_fraction");
  c.ae_hidden = j.at("ae_hidden");
  c.hidden = j.at("hidden").get<std::vector<int>>();
  c.steps = j.at("steps");
  c.batch_size = j.at("batch_size");
  c.learning_rate = j.at("learning_rate");
  c.weight_decay = j.at("weight_decay");
  c.dynamics_weight_decay = j.value("dynamics_weight_decay", c.weight_decay);
  c.hnn_weight = j.at("hnn_weight");
  c.rollout_frames = j.at("rollout_frames");
  c.rollout_trials = j.at("rollout_trials");
  c.rtol = j.at("rtol");
  c.atol = j.at("atol");
  return c;
}

void validate(const PixelConfig& c) {
  HNN_TASKS_CHECK(c.trials >= 2, "pixel-pendulum: trials must be at least 2, got {}", c.trials);
  HNN_TASKS_CHECK(c.frames_per_trial >= 4,
                  "pixel-pendulum: frames per trial must be at least 4 (3 go to the offsets), "
                  "got {}",
                  c.frames_per_trial);
  HNN_TASKS_CHECK(c.test_fraction > 0 && c.test_fraction < 1,
                  "pixel-pendulum: the test fraction must be in (0, 1), got {}", c.test_fraction);
  HNN_TASKS_CHECK(c.ae_hidden >= 1, "pixel-pendulum: autoencoder width must be positive");
  HNN_TASKS_CHECK(!c.hidden.empty(), "pixel-pendulum: the latent MLP needs a hidden layer");
  for (int w : c.hidden) HNN_TASKS_CHECK(w > 0, "pixel-pendulum: hidden widths must be positive");
  HNN_TASKS_CHECK(c.steps > 0, "pixel-pendulum: steps must be positive, got {}", c.steps);
  HNN_TASKS_CHECK(c.batch_size >= 0, "pixel-pendulum: batch must be >= 0, got {}", c.batch_size);
  HNN_TASKS_CHECK(c.learning_rate > 0 && std::isfinite(c.learning_rate),
                  "pixel-pendulum: the learning rate must be positive");
  HNN_TASKS_CHECK(c.weight_decay >= 0 && c.dynamics_weight_decay >= 0,
                  "pixel-pendulum: weight decays must be >= 0");
  HNN_TASKS_CHECK(c.rollout_frames >= 1, "pixel-pendulum: rollout frames must be positive");
  HNN_TASKS_CHECK(c.rollout_trials >= 0, "pixel-pendulum: rollout trials must be >= 0");
  HNN_TASKS_CHECK(c.rtol > 0 && c.atol > 0, "pixel-pendulum: tolerances must be positive");
}

}  // namespace hnn::tasks::pixel
