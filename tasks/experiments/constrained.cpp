// The constrained systems of Finzi, Wang & Wilson 2020 (physics/constrained/), one task each, at
// their protocol (their pl_trainer.py): 800 training trajectories, each cut to one random chunk
// of 5 outputs; the model's field integrated by RK4 over the chunk with an L1 loss; 3 x 256
// networks, lr 3e-3 with a cosine schedule, batch 200, 2000 epochs (8,000 steps); 100 test
// rollouts of one trajectory length (100 outputs) from chunk starts, scored by their metric in
// Cartesian (x, v) with its floor and the failed rollouts counted.
//
// The baseline learns the Cartesian state z = (x, v). On the chains the HNN learns the angle twin
// (theta, p), the LNN and the mass HNN (their HNN) (theta, omega) (physics/constrained/
// chain_angles.h); on the other systems the LNN and the mass HNN learn their body coordinates
// with their rates (q, dq/dt) (body_coordinates.h: spherical or Euler angles, a free body's
// centre), as the peer's HNN does. Every rollout is mapped to Cartesian (x, v) before the metric,
// so every model is scored alike.

#include <fmt/format.h>

#include <cmath>

#include "autodiff/parallel.h"
#include "nn/constrained/constraints.h"
#include "physics/constrained/body_coordinates.h"
#include "physics/constrained/chain_angles.h"
#include "physics/constrained/metric.h"
#include "physics/constrained/systems.h"
#include "tasks/experiments/registry.h"
#include "tasks/field/field_task.h"
#include "tasks/report/json_values.h"

namespace hnn::tasks {

namespace {

namespace pc = physics::constrained;
using nlohmann::json;

constexpr int kChunkOutputs = 5;              // the peer's chunk_len
constexpr int kTrainTrajectories = 800;       // the peer's n_train
constexpr int kValidationTrajectories = 100;  // the peer's n_val: the test split of the loss curve
constexpr int kPeerBatch = 200, kPeerEpochs = 2000;
constexpr int kMaxChunkedTrajectories = 100'000;
// The floor's perturbation draws: one fixed generator, so that every model of a run's seed is
// measured against the same floor (the starts depend on the seed).
constexpr std::uint64_t kConstrainedFloorSeed = 0x5eed;

// The truths (a run's data, its evaluation's truth and its floor) at the default tolerances, their
// rows (each integrated on its own steps) shared among the engine's threads. A gyroscope's data
// took 14 s on one thread.
const pc::TruthOptions kOnEngineThreads{
    .parallel = [](int parts, const std::function<void(int)>& part) {
      ad::parallel_for(parts, part);
    }};

// The state a model learns: the system's own, or the chain's angles with canonical momenta
// (HNN), or the chain's angles or a body's coordinates with their rates (LNN, mass HNN).
enum class Coordinates { kCartesian, kAngles, kAngleVelocities };

Coordinates model_coordinates(nn::ModelKind model) {
  if (model == nn::ModelKind::kHnn) return Coordinates::kAngles;
  if (nn::needs_velocities(model)) return Coordinates::kAngleVelocities;
  return Coordinates::kCartesian;
}

struct ConstrainedEntry {
  const char* task;
  const char* system;  // physics/constrained/systems.h
  int links;           // 0: not a chain (body coordinates, no canonical twin)
  const char* summary;
};

int trajectory_count(const json& s, const char* key, int fallback, const std::string& task) {
  if (!s.contains(key)) return fallback;
  HNN_TASKS_CHECK(s[key].is_number_integer() && s[key].get<long>() >= 1 &&
                      s[key].get<long>() <= kMaxChunkedTrajectories,
                  "{}: {} must be an integer in 1..{}, got {}", task, key, kMaxChunkedTrajectories,
                  s[key].dump());
  return s[key].get<int>();
}

// The system as the CHNN and CLNN see it (nn/constrained/constraints.h): its points, masses
// and constraints, one to one; the potential is what they learn.
nn::ConstraintSpec model_constraints(const pc::ConstrainedSpec& spec) {
  const auto values = [](const Eigen::VectorXd& v) {
    return std::vector<double>(v.data(), v.data() + v.size());
  };
  nn::ConstraintSpec c{.points = spec.points,
                       .dim = spec.dim,
                       .mass = spec.mass,
                       .links = {},
                       .anchors = {},
                       .pins = {}};
  for (const pc::DistanceConstraint& d : spec.distances) c.links.push_back({d.i, d.j, d.length});
  for (const pc::AnchorConstraint& a : spec.anchors) {
    c.anchors.push_back({a.i, values(a.anchor), a.length});
  }
  for (const pc::PinConstraint& p : spec.pins)
    c.pins.push_back({values(p.weights), values(p.point)});
  return c;
}

class ConstrainedTask : public FieldTask {
 public:
  ConstrainedTask(const ConstrainedEntry& entry, Coordinates coordinates)
      : entry_(entry),
        coordinates_(coordinates),
        cartesian_(pc::make_constrained_system(entry.system)) {
    if (entry.links > 0) {
      angles_ = std::make_unique<pc::ChainPendulumAngles>(entry.links);
      velocities_ = std::make_unique<pc::ChainPendulumVelocities>(entry.links);
    } else {
      body_ = std::make_unique<pc::BodyCoordinates>(cartesian_);
    }
    // The registered task (Cartesian) opens the other models' runs through its twins.
    if (coordinates == Coordinates::kCartesian) {
      if (entry.links > 0)
        angle_twin_ = std::make_unique<ConstrainedTask>(entry, Coordinates::kAngles);
      velocity_twin_ = std::make_unique<ConstrainedTask>(entry, Coordinates::kAngleVelocities);
    }
  }

  std::string name() const override { return entry_.task; }
  std::string summary() const override { return entry_.summary; }
  TrainConfig train_config() const override {
    return {.steps = kPeerEpochs * kTrainTrajectories / kPeerBatch,
            .batch_size = kPeerBatch,
            .learning_rate = 3e-3,
            .weight_decay = 1e-4,
            .lr_schedule = LrSchedule::kCosine,
            .optimizer = OptimizerKind::kAdamW,
            .hidden = {256, 256, 256}};
  }
  RolloutLossConfig default_loss() const override {
    return {.rollout = true,
            .horizon = kChunkOutputs - 1,
            .integrator = RolloutIntegrator::kRk4,
            .norm = RolloutNorm::kL1,
            .minibatches = RowSampler::Draw::kEpochs};  // their DataLoader(shuffle=True)
  }
  // Their pl_trainer trains and evaluates in float32 (datasets.py casts the trajectories with
  // .float()); float runs the 2-chain's default run in 304 s on 2 threads against 807 s in double,
  // at the same error (docs/constrained.md).
  Dtype default_dtype() const override { return Dtype::kFloat; }
  std::string table_note() const override {
    return fmt::format(
        "{}: cartesian_error is Finzi et al.'s geometric-mean relative error in Cartesian (x, v) "
        "over 100 test rollouts of 100 outputs, beside its floor and the failed rollouts.",
        entry_.task);
  }
  std::vector<nn::ModelKind> models() const override {
    using nn::ModelKind;
    if (entry_.links == 0) {
      return {ModelKind::kBaseline, ModelKind::kMassHnn, ModelKind::kLnn, ModelKind::kChnn,
              ModelKind::kClnn};
    }
    return {ModelKind::kBaseline, ModelKind::kHnn,  ModelKind::kMassHnn,
            ModelKind::kLnn,      ModelKind::kChnn, ModelKind::kClnn};
  }
  nn::ConstraintSpec constraints() const override { return model_constraints(cartesian_.spec()); }
  std::string refusal_reason(nn::ModelKind model) const override {
    if (model_coordinates(model) != Coordinates::kAngles || entry_.links > 0) return "";
    return fmt::format(
        ": an {} learns canonical momenta in angle coordinates, which hnn has for the chain "
        "pendulums only (physics/constrained/chain_angles.h), not for the {}; the peer's HNN "
        "(--model hnn-mass) and the LNN learn it in body coordinates (q, dq/dt)",
        nn::to_string(model), entry_.system);
  }
  std::vector<std::string> own_setting_names() const override {
    return {"trajectories", "validation"};
  }
  Eigen::Index angle_coordinates() const override {
    if (coordinates_ == Coordinates::kCartesian) return 0;
    return entry_.links > 0 ? entry_.links : body_->angles();
  }

  std::unique_ptr<TaskRun> open(const RunSettings& settings) const override {
    const Coordinates c = model_coordinates(settings.model);
    if (c == coordinates_) return FieldTask::open(settings);
    const ConstrainedTask& twin = c == Coordinates::kAngles ? *angle_twin_ : *velocity_twin_;
    return twin.FieldTask::open(settings);
  }

  const physics::System& truth() const override {
    if (coordinates_ == Coordinates::kAngles) return *angles_;
    if (coordinates_ == Coordinates::kAngleVelocities) {
      if (body_) return *body_;
      return *velocities_;
    }
    return cartesian_;
  }

  Dataset build_dataset(const RunSettings& settings) const override {
    const int train =
        trajectory_count(settings.task_settings, "trajectories", kTrainTrajectories, name());
    const int test =
        trajectory_count(settings.task_settings, "validation", kValidationTrajectories, name());
    std::mt19937_64 rng(settings.seed);
    const auto chunks = [&](int count) {
      return chunk_rows(pc::sample_chunks(cartesian_, count, kChunkOutputs, rng, kOnEngineThreads));
    };
    const Batch train_x = chunks(train);
    const Batch test_x = chunks(test);
    Batch train_dxdt, test_dxdt;
    truth().vector_field(train_x, train_dxdt);
    truth().vector_field(test_x, test_dxdt);
    return {train_x, train_dxdt, test_x, test_dxdt};
  }

  std::optional<SplitStretches> stretches(const RunSettings&, const Dataset& data) const override {
    const double span = (kChunkOutputs - 1) * cartesian_.spec().dt;
    return SplitStretches{regular_stretches(data.train_x, kChunkOutputs, span),
                          regular_stretches(data.test_x, kChunkOutputs, span)};
  }

  // The peer's test starts: the first states of random chunks of sampled trajectories.
  Batch rollout_states(const Dataset&, int count, std::mt19937_64& rng) const override {
    pc::ChunkSample sample =
        pc::sample_chunks(cartesian_, count, kChunkOutputs, rng, kOnEngineThreads);
    sample.states.resize(1);
    return in_coordinates(std::move(sample.states)).front();
  }

  // One trajectory length: the peer's output times (0, dt, ... below the horizon), the model
  // integrated by dopri5 at the peer's tolerance 1e-7. No perturbed truth in the model's
  // coordinates: add_metrics measures the peer's floor in Cartesian ones.
  RolloutConfig rollout_config() const override {
    const int points = int(cartesian_.output_times().size());
    return {.t_end = cartesian_.spec().dt * (points - 1),
            .points = points,
            .rtol = 1e-7,
            .atol = 1e-9,
            .perturbation = 0};
  }

  // The peer's metric in Cartesian (x, v) against a tight truth, the same for every model; its
  // floor where the span is the peer's (floor_score integrates over the system's output times).
  void add_metrics(const Rollouts& r, json& metrics) const override {
    std::vector<Batch> predicted = per_time(r.pred);
    for (Batch& b : predicted) b = to_cartesian(b);
    const Batch z0 = to_cartesian(per_time(r.truth).front());
    const std::vector<Batch> truth =
        pc::simulate_constrained(cartesian_, z0, r.t, kOnEngineThreads).states;
    const double dt = r.t[1] - r.t[0];
    const pc::RolloutScore score =
        pc::score_rollouts(predicted, truth, dt, dt * double(r.t.size()));
    metrics["cartesian_error"] = number(score.geometric_mean);
    metrics["cartesian_error_failed"] = score.failed;
    metrics["cartesian_error_rollouts"] = int(z0.rows());
    if (r.t.size() == cartesian_.output_times().size()) {
      std::mt19937_64 rng(kConstrainedFloorSeed);
      metrics["cartesian_error_floor"] = number(
          pc::floor_score(cartesian_, z0, truth, rng, kOnEngineThreads).score.geometric_mean);
    } else {
      metrics["cartesian_error_note"] = "no floor: the rollouts' span is not the peer's";
    }
    metrics["coordinates"] = coordinates_ == Coordinates::kCartesian ? "cartesian"
                             : coordinates_ == Coordinates::kAngles  ? "angles (theta, p)"
                             : body_                                 ? "body coordinates (q, dq/dt)"
                                                                     : "angles (theta, omega)";
  }

  // A given Cartesian state must keep the rods' lengths, the pins, and their rates at 0: off
  // them, the projected truth would move a system with other rods. Angle coordinates keep them
  // by construction.
  std::string state_problem(const Batch& x, Eigen::Index row) const override {
    if (coordinates_ != Coordinates::kCartesian) return "";
    return cartesian_.state_problem(&x(row, 0));
  }

  std::pair<Batch, double> project_states(const Batch& x) const override {
    HNN_TASKS_CHECK(coordinates_ == Coordinates::kCartesian,
                    "--project moves Cartesian states onto {}'s constraints; this run's states "
                    "are angles, which keep them by construction",
                    name());
    Batch moved = cartesian_.project(x);
    return {moved, (moved - x).rowwise().norm().maxCoeff()};
  }

  // Cartesian (x, v) rows of states in this task's coordinates.
  Batch to_cartesian(const Batch& x) const {
    if (coordinates_ == Coordinates::kAngles) return angles_->to_cartesian(x);
    if (coordinates_ == Coordinates::kAngleVelocities)
      return body_ ? body_->to_cartesian(x) : velocities_->to_cartesian(x);
    return x;
  }

 private:
  // Cartesian states, one batch per time, in this task's coordinates: angles continuous along
  // time (a chunk crossing theta = pi carries no 2 pi jump).
  std::vector<Batch> in_coordinates(std::vector<Batch> states) const {
    if (coordinates_ == Coordinates::kCartesian) return states;
    if (body_) {
      for (Batch& b : states) b = body_->from_cartesian(b);
      pc::unwrap_angles(states, body_->angles());
      return states;
    }
    for (Batch& b : states) b = pc::chain_angles(entry_.links, b);
    pc::unwrap_angles(states, entry_.links);
    if (coordinates_ == Coordinates::kAngles)
      for (Batch& b : states) b = angles_->momenta_from_velocities(b);
    return states;
  }

  // A chunk sample as rows, chunk after chunk, each chunk's kChunkOutputs states in time order.
  Batch chunk_rows(const pc::ChunkSample& sample) const {
    const std::vector<Batch> states = in_coordinates(sample.states);
    const Eigen::Index n = states.front().rows();
    Batch rows(n * kChunkOutputs, states.front().cols());
    for (Eigen::Index i = 0; i < n; ++i)
      for (int k = 0; k < kChunkOutputs; ++k)
        rows.row(i * kChunkOutputs + k) = states[std::size_t(k)].row(i);
    return rows;
  }

  // Per-trajectory paths (times x dim) -> one batch per time (trajectories x dim).
  static std::vector<Batch> per_time(const std::vector<Eigen::MatrixXd>& paths) {
    std::vector<Batch> out(std::size_t(paths.front().rows()),
                           Batch(Eigen::Index(paths.size()), paths.front().cols()));
    for (std::size_t i = 0; i < paths.size(); ++i)
      for (std::size_t k = 0; k < out.size(); ++k)
        out[k].row(Eigen::Index(i)) = paths[i].row(Eigen::Index(k));
    return out;
  }

  ConstrainedEntry entry_;
  Coordinates coordinates_;
  pc::ConstrainedSystem cartesian_;
  std::unique_ptr<pc::ChainPendulumAngles> angles_;
  std::unique_ptr<pc::ChainPendulumVelocities> velocities_;
  std::unique_ptr<pc::BodyCoordinates> body_;  // the systems that are not chains
  std::unique_ptr<ConstrainedTask> angle_twin_, velocity_twin_;
};

constexpr ConstrainedEntry kConstrainedEntries[] = {
    {"chain-pendulum-2", "chain_pendulum_2", 2,
     "2-link chain pendulum in Cartesian coordinates (Finzi et al. 2020)"},
    {"chain-pendulum-3", "chain_pendulum_3", 3,
     "3-link chain pendulum in Cartesian coordinates (Finzi et al. 2020)"},
    {"chain-pendulum-4", "chain_pendulum_4", 4,
     "4-link chain pendulum in Cartesian coordinates (Finzi et al. 2020)"},
    {"chain-pendulum-5", "chain_pendulum_5", 5,
     "5-link chain pendulum in Cartesian coordinates (Finzi et al. 2020)"},
    {"coupled-pendulums", "coupled_pendulums_3", 0,
     "3 spherical pendulums joined by springs, Cartesian (Finzi et al. 2020)"},
    {"magnet-pendulum", "magnet_pendulum", 0,
     "spherical pendulum over two magnets, Cartesian (Finzi et al. 2020)"},
    {"gyroscope", "gyroscope", 0,
     "gyroscope as constrained point masses, Cartesian (Finzi et al. 2020)"},
    {"rotor", "rotor", 0, "free rotor as constrained point masses, Cartesian (Finzi et al. 2020)"},
};

}  // namespace

std::vector<std::string> constrained_task_names() {
  std::vector<std::string> names;
  for (const ConstrainedEntry& e : kConstrainedEntries) names.push_back(e.task);
  return names;
}

std::unique_ptr<Task> make_constrained_task(const std::string& name) {
  for (const ConstrainedEntry& e : kConstrainedEntries)
    if (name == e.task) return std::make_unique<ConstrainedTask>(e, Coordinates::kCartesian);
  throw Error(fmt::format("no constrained task '{}'", name));
}

}  // namespace hnn::tasks
