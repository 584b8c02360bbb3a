// The run of a field task: train a dynamics model on the task's dataset (with FieldObjective on
// dx/dt targets, or through an integrator with RolloutObjective), evaluate it against the true
// system, save and load it, roll it out.

#include "tasks/field/field_task.h"

#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>

#include "physics/integrator.h"
#include "tasks/evaluate/field_evaluation.h"
#include "tasks/evaluate/held_out.h"
#include "tasks/field/field_model_run.h"
#include "tasks/options/model_settings.h"
#include "tasks/report/json_values.h"
#include "tasks/report/rollout_csv.h"

namespace hnn::tasks {

namespace {

using nlohmann::json;

ModelInput model_input(const FieldTask& task, const RunSettings& s) {
  nn::ConstraintSpec constraints =
      nn::is_constrained(s.model) ? task.constraints() : nn::ConstraintSpec{};
  constraints.learned_masses = learned_masses(s.task_settings, s.model, task.name());
  return {.angles = task.angle_coordinates(),
          .input_scale = task.input_scale(),
          .given_velocities = given_velocities(s.task_settings, s.model, s.fit.samples(),
                                               velocity_state(task), task.name()),
          .constraints = std::move(constraints)};
}

class FieldRun : public FieldModelRun {
 public:
  FieldRun(const FieldTask& task, RunSettings settings)
      : FieldModelRun(settings, task.build_dataset(settings), model_input(task, settings)),
        task_(task),
        own_truth_(task.truth_for(s_)) {
    const RolloutLossConfig& loss = s_.loss;
    check_rollouts();
    stretches_ = task_.stretches(s_, data_);
    training_ = FieldTraining(loss, stretches_ ? &*stretches_ : nullptr, s_.train, task_.name());
  }

  nlohmann::json evaluate(const RunFolder* folder) const override {
    if (task_.scattered()) {
      json m = evaluate_field_points(&truth(), dynamics(), data_).metrics;
      m["training"] = training_.loss().to_json();
      return m;
    }
    const RolloutConfig config = evaluation_rollouts();
    FieldEvaluation e =
        task_.has_truth()
            ? evaluate_field_model(truth(), dynamics(), data_, rollout_states(config.trajectories),
                                   config)
            : evaluate_field_model(
                  dynamics(), data_,
                  follow_measured(measured_paths(config), learned_field(dynamics()), config));
    if (config.trajectories < asked_rollouts_) {
      e.metrics["rollouts_note"] =
          fmt::format("{} rollouts, not {}: the data have {} distinct initial states",
                      config.trajectories, asked_rollouts_, config.trajectories);
    }
    task_.add_metrics(e.rollouts, e.metrics);
    if (folder)
      folder->write_text("rollout.csv", tasks::rollout_csv(e.rollouts, nn::to_string(s_.model)));
    json m = e.metrics;
    m["training"] = training_.loss().to_json();
    if (training_.loss().rollout && task_.has_truth())
      m["truth_rollout_loss"] = number(training_.truth_loss(truth()));
    if (stretches_ && !stretches_->test.empty()) {
      m.update(held_out_stretch_metrics(dynamics(), *stretches_,
                                        {.per_body = task_.coordinates_per_body(),
                                         .stepping = training_.stepping(),
                                         .truth = task_.has_truth() ? &truth() : nullptr}));
    }
    return m;
  }

  // Given states the truth cannot start from are refused one line each, naming the state (1 for
  // the first) and why; with --project they are moved onto the constraints first.
  Batch given_states(Batch x, bool project, std::vector<std::string>& notes) const override {
    if (project) {
      auto [moved, largest] = task_.project_states(x);
      notes.push_back(
          fmt::format("moved {} given state{} onto {}'s constraints, the furthest by "
                      "{:.3g}",
                      x.rows(), x.rows() == 1 ? "" : "s", task_.name(), largest));
      return std::move(moved);
    }
    for (Eigen::Index row = 0; row < x.rows(); ++row) {
      const std::string problem = task_.state_problem(x, row);
      HNN_TASKS_CHECK(problem.empty(),
                      "given state {} is off {}'s constraints: {}; --project moves given states "
                      "onto them",
                      row + 1, task_.name(), problem);
    }
    return x;
  }

  // With a true system, it and the model from each initial state over the whole span; without
  // one, the measured paths from the test states, or the model alone from given states.
  RolloutOutput rollout(const RolloutRequest& r) const override {
    const auto integrator =
        physics::make_integrator(r.integrator, {.dt = r.dt, .rtol = r.rtol, .atol = r.rtol * 1e-3});
    const std::vector<double> t =
        physics::linspace(0.0, r.t_end.value_or(rollout_span()), r.points);
    const bool given = r.initial_states.rows() > 0;
    if (!task_.has_truth() && !given) return measured_rollout(r, *integrator, t);
    if (!task_.has_truth()) {
      return {.csv = model_paths_csv(r.initial_states, *integrator, t),
              .trajectories = int(r.initial_states.rows()),
              .notes = {fmt::format("{}: the truth is unavailable from your states: the task "
                                    "knows no H, its truth is measured data",
                                    task_.name())}};
    }
    Batch x0 = r.initial_states;
    if (!given) {
      x0 = rollout_states(r.trajectories.value_or(RolloutRequest::kDefaultTrajectories));
      x0.conservativeResize(trajectories_to_write(r, int(x0.rows()), "distinct test states"),
                            Eigen::NoChange);
    }
    return {
        .csv = rollout_paths_csv(truth(), dynamics(), nn::to_string(s_.model), x0, *integrator, t),
        .trajectories = int(x0.rows())};
  }

  // The evaluation's states: a generator independent of the training data's draws. Without a
  // truth, the first states of the measured paths.
  physics::Batch rollout_states(int count) const override {
    if (!task_.has_truth()) {
      const std::vector<Eigen::MatrixXd> paths =
          task_.measured_paths(s_, count, task_.rollout_config(s_.task_settings));
      Batch x0(Eigen::Index(paths.size()), data_.test_x.cols());
      for (std::size_t i = 0; i < paths.size(); ++i) x0.row(Eigen::Index(i)) = paths[i].row(0);
      return x0;
    }
    std::mt19937_64 rng(s_.seed + 1);
    physics::Batch x0 = task_.rollout_states(data_, count, rng);
    x0.conservativeResize(std::min<Eigen::Index>(x0.rows(), count), Eigen::NoChange);
    return x0;
  }

  double rollout_span() const override { return task_.rollout_config(s_.task_settings).t_end; }

  Eigen::VectorXd true_energy(const Batch& x) const override {
    return task_.has_truth() ? Eigen::VectorXd(task_.truth().energy_batch(x)) : Eigen::VectorXd();
  }

 private:
  // The run's rollouts: the task's with its settings, as many as the data can start (checked
  // against an explicit "rollouts" in the constructor), the floor's draws from the run's seed.
  RolloutConfig evaluation_rollouts() const {
    RolloutConfig config = task_.rollout_config(s_.task_settings);
    config.trajectories = std::min(config.trajectories, available_rollouts_);
    config.seed = s_.seed + 2;
    return config;
  }

  std::vector<Eigen::MatrixXd> measured_paths(const RolloutConfig& config) const {
    return task_.measured_paths(s_, config.trajectories, config);
  }

  // How many rollouts the run's data can start, found before a run folder exists: a "rollouts"
  // setting above it is an error naming both; the default is cut to it (and metrics say so).
  void check_rollouts() {
    const RolloutConfig config = task_.rollout_config(s_.task_settings);
    asked_rollouts_ = config.trajectories;
    available_rollouts_ = int(rollout_states(config.trajectories).rows());
    HNN_TASKS_CHECK(available_rollouts_ > 0, "{}: no state to start a rollout from", task_.name());
    HNN_TASKS_CHECK(
        !s_.task_settings.contains("rollouts") || available_rollouts_ >= config.trajectories,
        "{}: rollouts {} is more than the {} distinct initial states its data have", task_.name(),
        config.trajectories, available_rollouts_);
  }

  // `hnn rollout` without a truth: the measured paths ("data", missing samples left out) and
  // the model's from their first states with the requested integrator at times t. The data
  // stop where they end: a note says so when t goes further.
  RolloutOutput measured_rollout(const RolloutRequest& r, const physics::Integrator& integrator,
                                 const std::vector<double>& t) const {
    RolloutConfig config = task_.rollout_config(s_.task_settings);
    config.trajectories = trajectories_to_write(r, available_rollouts_, "measured test paths");
    const std::vector<Eigen::MatrixXd> paths = measured_paths(config);
    RolloutCsv csv(state_names(), {}, /*skip_incomplete=*/true);
    const std::vector<double> data_t = physics::linspace(0.0, config.t_end, config.points);
    for (std::size_t i = 0; i < paths.size(); ++i) {
      csv.add(kDataSource, i, data_t, paths[i]);
      add_model_path(csv, i, Batch(paths[i].topRows(1)), integrator, t);
    }
    RolloutOutput out{.csv = csv.str(), .trajectories = int(paths.size())};
    if (t.back() > config.t_end) {
      out.notes.push_back(
          fmt::format("{}: the truth is unavailable past the data: the measured "
                      "paths end at t = {:g} and the model's run to t = {:g}",
                      task_.name(), config.t_end, t.back()));
    }
    return out;
  }

  std::string model_paths_csv(const Batch& x0, const physics::Integrator& integrator,
                              const std::vector<double>& t) const {
    RolloutCsv csv(state_names());
    for (Eigen::Index i = 0; i < x0.rows(); ++i)
      add_model_path(csv, std::size_t(i), Batch(x0.row(i)), integrator, t);
    return csv.str();
  }

  // The model's path from the state x0 (one row), with its learned H when it has one.
  void add_model_path(RolloutCsv& csv, std::size_t traj, const Batch& x0,
                      const physics::Integrator& integrator, const std::vector<double>& t) const {
    const LearnedField model = learned_field(dynamics());
    const Batch x = integrator.integrate(model.field, x0, t).path(0);
    csv.add(nn::to_string(s_.model), traj, t, x, {},
            model.hamiltonian ? model.hamiltonian(x) : Eigen::VectorXd());
  }

  // The run's truth: the task's own, or the one its settings make (FieldTask::truth_for).
  const physics::System& truth() const { return own_truth_ ? *own_truth_ : task_.truth(); }

  const FieldTask& task_;
  std::unique_ptr<physics::System> own_truth_;
  std::optional<SplitStretches> stretches_;
  int asked_rollouts_ = 0, available_rollouts_ = 0;
};

}  // namespace

void FieldTask::add_metrics(const Rollouts&, nlohmann::json&) const {}

std::string FieldTask::state_problem(const Batch&, Eigen::Index) const { return ""; }

std::pair<Batch, double> FieldTask::project_states(const Batch&) const {
  throw Error(
      fmt::format("--project moves given states onto a constrained system's "
                  "constraints; {}'s states have none",
                  name()));
}

std::vector<Stretch> regular_stretches(const Batch& x, int points, double t_end) {
  const std::vector<double> t = physics::linspace(0.0, t_end, points);
  const Eigen::VectorXd times = Eigen::Map<const Eigen::VectorXd>(t.data(), points);
  std::vector<Stretch> out;
  for (Eigen::Index start = 0; start + points <= x.rows(); start += points)
    out.push_back({times, x.middleRows(start, points)});
  return out;
}

OscillatorSettings oscillator_settings(const nlohmann::json& s, OscillatorSettings paper,
                                       const std::string& task) {
  OscillatorSettings o = paper;
  try {
    if (s.contains("t_end")) o.t_end = s["t_end"].get<double>();
    HNN_TASKS_CHECK(o.t_end > 0 && std::isfinite(o.t_end), "{}: t_end must be positive, got {}",
                    task, o.t_end);
    const double interval =
        s.contains("sample_dt") ? s["sample_dt"].get<double>() : paper.t_end / (paper.points - 1);
    HNN_TASKS_CHECK(interval > 0 && std::isfinite(interval),
                    "{}: sample_dt must be positive, got {}", task, interval);
    if (!s.contains("t_end") && !s.contains("sample_dt")) return paper;
    const double intervals = std::round(o.t_end / interval);
    HNN_TASKS_CHECK(intervals >= 1 && std::abs(o.t_end / interval - intervals) < 1e-6 * intervals,
                    "{}: sample_dt {} does not divide t_end {} into whole intervals", task,
                    interval, o.t_end);
    o.points = int(intervals) + 1;
  } catch (const nlohmann::json::exception& e) {
    throw Error(fmt::format("{}: bad settings {}: {}", task, s.dump(), e.what()));
  }
  return o;
}

std::optional<SplitStretches> FieldTask::stretches(const RunSettings&, const Dataset&) const {
  return std::nullopt;
}

void FieldTask::check_task_settings(const nlohmann::json& settings) const {
  const std::vector<std::string> own = own_setting_names(), rollouts = evaluation_setting_names();
  std::vector<std::string> known = rollout_setting_names();
  known.push_back(kBaselineOutputKey);
  known.push_back(kMassesKey);
  known.insert(known.end(), fit_setting_names().begin(), fit_setting_names().end());
  known.insert(known.end(), own.begin(), own.end());
  known.insert(known.end(), rollouts.begin(), rollouts.end());
  for (const auto& [key, value] : settings.items()) {
    HNN_TASKS_CHECK(std::find(known.begin(), known.end(), key) != known.end(),
                    "task '{}' has no setting '{}' (known: {})", name(), key,
                    fmt::join(known, ", "));
  }
  rollout_config(settings);
}

std::unique_ptr<TaskRun> FieldTask::open(const RunSettings& settings) const {
  return std::make_unique<FieldRun>(*this, settings);
}

Dataset FieldTask::build_dataset(std::uint64_t seed) const {
  return build_dataset(RunSettings{.task = name(), .seed = seed});
}

}  // namespace hnn::tasks
