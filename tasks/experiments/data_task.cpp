// The `data` task: a user's own trajectories, measured or simulated (CSV, .npy, .npz or the
// Schmidt & Lipson text format), learned in standardised units and reported in the file's.
// Without a known H it is judged by rolling out from each held-out stretch's first state; with
// one (--hamiltonian) also by the energy MSE of the other tasks.

#include <algorithm>

#include "physics/expression_system.h"
#include "physics/integrator.h"
#include "tasks/data/units.h"
#include "tasks/evaluate/field_evaluation.h"
#include "tasks/evaluate/hamiltonian_error.h"
#include "tasks/evaluate/held_out.h"
#include "tasks/experiments/data_config.h"
#include "tasks/experiments/registry.h"
#include "tasks/field/field_model_run.h"
#include "tasks/report/json_values.h"
#include "tasks/report/rollout_csv.h"

namespace hnn::tasks {

namespace {

using nlohmann::json;

// The H of --hamiltonian over the state's column names.
std::unique_ptr<physics::ExpressionSystem> make_truth(const std::string& expression,
                                                      const MeasuredData& m) {
  if (expression.empty()) return nullptr;
  const auto n = std::ptrdiff_t(m.coordinates);
  std::vector<std::string> q(m.state_names.begin(), m.state_names.begin() + n),
      p(m.state_names.begin() + n, m.state_names.end());
  try {
    return std::make_unique<physics::ExpressionSystem>(expression, q, p);
  } catch (const std::invalid_argument& e) {
    throw Error(fmt::format("--hamiltonian: {} (the state's names: {})", e.what(),
                            fmt::join(m.state_names, ", ")));
  }
}

// A model's field and H in the model's units, seen in the file's.
LearnedField in_file_units(const LearnedField& model, const Units& u) {
  LearnedField file{.field = [model, u](double t, const Batch& x, Batch& dxdt) {
    Batch dzdt;
    model.field(t / u.time, u.to_model(x), dzdt);
    dxdt = u.rate_to_file(dzdt);
  }};
  if (model.hamiltonian) {
    file.hamiltonian = [model, u](const Batch& x) -> Eigen::VectorXd {
      return model.hamiltonian(u.to_model(x)) * u.energy_to_file();
    };
  }
  return file;
}

double median(std::vector<double> v) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

// n rows evenly spread over x.
Batch spread_rows(const Batch& x, int n) {
  n = int(std::min<Eigen::Index>(n, x.rows()));
  Batch out(n, x.cols());
  for (int i = 0; i < n; ++i) out.row(i) = x.row(Eigen::Index(i) * x.rows() / n);
  return out;
}

// What a data run is built from, before the model: the file's trajectories, the units.
struct Prepared {
  DataConfig config{};
  MeasuredData measured{};
  Units units{};
  std::unique_ptr<physics::ExpressionSystem> truth{};
};

Prepared prepare(const RunSettings& s) {
  HNN_TASKS_CHECK(!s.data_file.empty(),
                  "the data task needs a file: hnn train data --data FILE (CSV, .npy, .npz or "
                  "Schmidt & Lipson text)");
  Prepared p{.config = data_config(s.task_settings)};
  p.measured = load_measured_data(s.data_file, p.config.measured);
  HNN_TASKS_CHECK(p.measured.data.train_x.rows() >= 2 && p.measured.data.test_x.rows() >= 1,
                  "{}: {} training and {} test rows: too few to train and test", p.measured.source,
                  p.measured.data.train_x.rows(), p.measured.data.test_x.rows());
  p.units = p.config.standardize
                ? fit_units(p.measured.data, p.measured.coordinates, p.measured.state_names)
                : identity_units(p.measured.data.train_x.cols());
  p.truth = make_truth(p.config.hamiltonian, p.measured);
  if (p.measured.scattered) check_scattered_settings(s.task_settings, s.loss, p.measured.source);
  return p;
}

// The same losses in the model's standardised units (x - mean) / scale, t / time: those of
// loss_curve.csv and the progress line, under their names with "_standardised".
json standardised_losses(const LearnedField& model, const Dataset& z) {
  const nn::MeanStderr train = loss_stats(model.field, z.train_x, z.train_dxdt);
  const nn::MeanStderr test = loss_stats(model.field, z.test_x, z.test_dxdt);
  return {{"train_loss_standardised", number(train.mean)},
          {"train_loss_standardised_se", number(train.std_error)},
          {"test_loss_standardised", number(test.mean)},
          {"test_loss_standardised_se", number(test.std_error)}};
}

// metrics.json's "units": the standardisation, and which keys and files are in which units.
json units_statement(const Units& u) {
  json j = u.to_json();
  j["standardised"] = {"train_loss_standardised", "train_loss_standardised_se",
                       "test_loss_standardised",  "test_loss_standardised_se",
                       "loss_curve.csv",          "the progress line of hnn train"};
  j["file"] =
      "every other loss, error, time and energy (train_loss, test_loss, energy_mse, ...): the data "
      "file's own units";
  return j;
}

class DataRun : public FieldModelRun {
 public:
  DataRun(RunSettings settings, Prepared p)
      : FieldModelRun(std::move(settings), p.units.to_model(p.measured.data)), p_(std::move(p)) {
    if (!s_.loss.rollout) return;  // on dx/dt targets: no stretches to convert
    const SplitStretches stretches{in_model_units(p_.measured.train_stretches),
                                   in_model_units(p_.measured.held_out)};
    training_ = FieldTraining(s_.loss, &stretches, s_.train, "data", p_.units.time);
  }

  // The progress line shows the training loss in the model's units: it says so.
  TrainResult train(const LoopOptions& loop) override {
    LoopOptions labelled = loop;
    if (p_.config.standardize) labelled.label += " (standardised units)";
    return FieldModelRun::train(labelled);
  }

  json evaluate(const RunFolder* folder) const override {
    const LearnedField model = learned_field(dynamics());
    const LearnedField file = in_file_units(model, p_.units);
    const Dataset& d = p_.measured.data;
    const nn::MeanStderr train = loss_stats(file.field, d.train_x, d.train_dxdt);
    const nn::MeanStderr test = loss_stats(file.field, d.test_x, d.test_dxdt);
    json m = {{"train_loss", number(train.mean)},
              {"train_loss_se", number(train.std_error)},
              {"test_loss", number(test.mean)},
              {"test_loss_se", number(test.std_error)},
              {"train_r2", number(r_squared(train.mean, d.train_dxdt))},
              {"test_r2", number(r_squared(test.mean, d.test_dxdt))},
              {"n_train", d.train_x.rows()},
              {"n_test", d.test_x.rows()}};
    m.update(standardised_losses(model, data_));
    if (dynamics().config().field == nn::FieldType::kBoth) {
      m["dissipation_share"] = number(dissipation_share(
          dynamics(), data_.test_x, [&](const Batch& f) { return p_.units.rate_to_file(f); }));
    }
    if (p_.truth) m.update(hamiltonian_error_metrics(*p_.truth, file, d.test_x));
    const bool scattered = p_.measured.scattered;
    HeldOutEvaluation held;
    if (scattered) m["rollouts_skipped"] = kRolloutsSkipped;
    if (!scattered) {
      held = evaluate_held_out(model, p_.units, p_.measured.held_out, p_.measured.coordinates,
                               data_.train_x,
                               {.threshold = p_.config.threshold, .truth = p_.truth.get()});
      m.update(held.metrics);
      m.update(energy_metrics(file));
    }
    m["training"] = s_.loss.to_json();
    m["units"] = units_statement(p_.units);
    m["state_names"] = p_.measured.state_names;
    m["data"] = describe(p_.measured);
    if (folder) {
      if (!scattered) {
        folder->write_text("rollout.csv",
                           held_out_csv(held, p_.measured.state_names, nn::to_string(s_.model)));
      }
      // Said once the run has gone through: an error before it stays the one line on stderr.
      fmt::print(stderr, "hnn: data: {}\n", derivatives_source(p_.measured));
    }
    return m;
  }

  // `hnn rollout`, in the file's units: from each initial state (given, or the first state of
  // a held-out stretch, whose data come too) the true system when --hamiltonian gave one, over
  // the whole span, and the model. Without one the truth is the data alone, and a note says
  // so when the span goes past them.
  RolloutOutput rollout(const RolloutRequest& r) const override {
    const std::vector<double> t =
        physics::linspace(0.0, r.t_end ? *r.t_end : rollout_span() * p_.units.time, r.points);
    const auto integrator =
        physics::make_integrator(r.integrator, {.dt = r.dt, .rtol = r.rtol, .atol = r.rtol * 1e-3});
    RolloutCsv csv(p_.measured.state_names, {.times = 12});
    RolloutOutput out;
    // Scattered states have no held-out stretches: their test states start the paths.
    const Batch& tests = p_.measured.data.test_x;
    const Batch starts =
        r.initial_states.rows() > 0 ? r.initial_states
        : p_.measured.scattered
            ? spread_rows(tests, trajectories_to_write(r, int(tests.rows()), "test states"))
            : Batch();
    const bool given = starts.rows() > 0;
    const auto& held = p_.measured.held_out;
    out.trajectories = given ? int(starts.rows())
                             : trajectories_to_write(r, int(held.size()), "held-out stretches");
    double data_end = INFINITY;
    for (int i = 0; i < out.trajectories; ++i) {
      const auto k = std::size_t(i);
      const Batch x0 = given ? Batch(starts.row(i)) : Batch(held[k].x.topRows(1));
      if (!given) {
        csv.add(kDataSource, k, held[k].t.array() - held[k].t(0), held[k].x, energy(held[k].x));
        data_end = std::min(data_end, held[k].t(held[k].t.size() - 1) - held[k].t(0));
      }
      if (p_.truth) {
        const Batch x = integrator->integrate(p_.truth->field(), x0, t).path(0);
        csv.add(kTrueSource, k, t, x, energy(x));
      }
      add_model_path(csv, k, x0, r, t);
    }
    out.csv = csv.str();
    if (!p_.truth && (given || t.back() > data_end))
      out.notes.push_back(no_truth(given, data_end, t.back()));
    return out;
  }

  std::vector<std::string> state_names() const override { return p_.measured.state_names; }

  // In the file's units, for any model with an H (a dhnn too, which model_in_data_units refuses).
  Eigen::VectorXd learned_h(const Batch& x) const override {
    const LearnedField file = in_file_units(learned_field(dynamics()), p_.units);
    return file.hamiltonian ? file.hamiltonian(x) : TaskRun::learned_h(x);
  }

  Eigen::VectorXd true_energy(const Batch& x) const override { return energy(x); }

  // The units folded into the weights: the first layer takes x instead of z = (x - mean) / scale
  // and the last gives H in the file's units (an HNN) or dx/dt (a baseline). Exact: an affine map
  // into a linear layer is a linear layer.
  std::unique_ptr<nn::DynamicsModel<double>> model_in_data_units() const override {
    HNN_TASKS_CHECK(dynamics().config().field != nn::FieldType::kBoth,
                    "a dhnn trained on standardised data has no single D in the file's units "
                    "(its dissipation scales per column); only an hnn or a baseline converts");
    std::unique_ptr<nn::DynamicsModel<double>> m = nn::cast_model<double>(dynamics());
    const Units& u = p_.units;
    const std::size_t layers = m->config().hidden.size() + 1;
    const Eigen::RowVectorXd output_scale =
        nn::learns_scalars(m->config().model)
            ? Eigen::RowVectorXd::Constant(m->mlp().config().widths.back(), u.energy_to_file())
            : Eigen::RowVectorXd(u.scale / u.time);
    nn::Matrix<double> first_weight;
    m->visit_parameters([&](const std::string& name, ad::Var<double>& p) {
      nn::Matrix<double>& v = p.mutable_value();
      if (name == "mlp.layers.0.weight") {
        first_weight = v;  // the bias below needs it unscaled
        v = u.scale.cwiseInverse().asDiagonal() * v;
      }
      if (name == "mlp.layers.0.bias") v -= u.mean.cwiseQuotient(u.scale) * first_weight;
      const std::string last = fmt::format("mlp.layers.{}.", layers - 1);
      if (name.starts_with(last)) v = v * output_scale.asDiagonal();
    });
    return m;
  }

  // Test states spread over the held-out rows, in the model's units.
  Batch rollout_states(int count) const override { return spread_rows(data_.test_x, count); }

  // The held-out stretches' median duration, in the model's time unit.
  double rollout_span() const override {
    HNN_TASKS_CHECK(!p_.measured.scattered,
                    "{}: scattered states (no time column) have no time span to roll out over: "
                    "give one with --t-end",
                    p_.measured.source);
    return held_out_duration() / p_.units.time;
  }

 private:
  // The note of a run without an H whose rollouts leave the data (or start from given states).
  static std::string no_truth(bool given, double data_end, double t_end) {
    if (given) {
      return "data: the truth is unavailable from your states: the run has no H (train with "
             "--hamiltonian EXPR to integrate one)";
    }
    return fmt::format(
        "data: the truth is unavailable past the data: the shortest held-out "
        "stretch ends at t = {:g} and the paths run to t = {:g}; train with "
        "--hamiltonian EXPR to integrate a known H",
        data_end, t_end);
  }

  // The model's path from the state x0 (one row, file units) at the file's times t:
  // integrated in the model's units (as evaluate_held_out does, so that tolerances mean the
  // same at any data scale; `r`'s dt is in the file's time unit) and shown in the file's.
  void add_model_path(RolloutCsv& csv, std::size_t traj, const Batch& x0, const RolloutRequest& r,
                      const std::vector<double>& t) const {
    const Units& u = p_.units;
    const auto integrator = physics::make_integrator(
        r.integrator, {.dt = r.dt / u.time, .rtol = r.rtol, .atol = r.rtol * 1e-3});
    std::vector<double> t_model(t.size());
    std::transform(t.begin(), t.end(), t_model.begin(), [&](double v) { return v / u.time; });
    const LearnedField model = learned_field(dynamics());
    const Batch z = integrator->integrate(model.field, u.to_model(x0), t_model).path(0);
    const Batch x = u.to_file(z);
    csv.add(nn::to_string(s_.model), traj, t, x, energy(x),
            model.hamiltonian ? Eigen::VectorXd(model.hamiltonian(z) * u.energy_to_file())
                              : Eigen::VectorXd());
  }

  double held_out_duration() const {
    std::vector<double> spans;
    for (const HeldOut& h : p_.measured.held_out) spans.push_back(h.t(h.t.size() - 1) - h.t(0));
    return median(spans);
  }

  // With a known H, the energy MSE of the other tasks: the true and the learned field from test
  // states over the held-out duration (or energy_t_end).
  json energy_metrics(const LearnedField& file) const {
    if (!p_.truth) {
      return {{"energy_mse", nullptr},
              {"energy_mse_se", nullptr},
              {"energy_relative_mse", nullptr},
              {"energy_relative_mse_se", nullptr},
              {"energy_note", "no known Hamiltonian: give one with --hamiltonian EXPR"},
              {"relative_error_floor_note",
               "no known Hamiltonian to perturb (--hamiltonian EXPR gives "
               "truth_rollout_relative_error_floor)"}};
    }
    const double t_end = p_.config.t_end > 0 ? p_.config.t_end : held_out_duration();
    const Batch x0 = spread_rows(p_.measured.data.test_x, p_.config.rollouts);
    // The floor's perturbation is 1e-4 in the model's (standardised) units.
    const RolloutConfig config{
        .trajectories = int(x0.rows()),
        .t_end = t_end,
        .perturbation_scale = {p_.units.scale.data(),
                               p_.units.scale.data() + p_.units.scale.size()},
        .seed = s_.seed + 2};
    const Rollouts r = make_rollouts(*p_.truth, file, x0, config);
    json m = rollout_metrics(r, p_.config.threshold);
    // The held-out stretches' valid prediction time and state error keep their names; these
    // are the rollouts against the known H.
    json out = {{"energy_mse", m["energy_mse"]},
                {"energy_mse_se", m["energy_mse_se"]},
                {"energy_mse_count", m["energy_mse_count"]},
                {"energy_relative_mse", m["energy_relative_mse"]},
                {"energy_relative_mse_se", m["energy_relative_mse_se"]},
                {"n_rollouts", m["n_rollouts"]},
                {"rollouts", m["rollouts"]},
                {"rollout_failures", r.failures},
                {"energy_t_end", t_end},
                {"hamiltonian", p_.config.hamiltonian}};
    for (const char* key :
         {"state_mse", "relative_error_geomean", "relative_error_floor", "valid_prediction_time"}) {
      for (const char* suffix : {"", "_se", "_count"})
        out[std::string("truth_rollout_") + key + suffix] = m[std::string(key) + suffix];
    }
    if (x0.rows() < p_.config.rollouts) {
      out["rollouts_note"] = fmt::format("{} rollouts, not {}: the test set has {} states",
                                         x0.rows(), p_.config.rollouts, x0.rows());
    }
    return out;
  }

  // The known H along x (the energy column), or none.
  Eigen::VectorXd energy(const Batch& x) const {
    return p_.truth ? Eigen::VectorXd(p_.truth->energy_batch(x)) : Eigen::VectorXd();
  }

  // Stretches in the model's units (time from the file's origin, in the model's unit).
  std::vector<Stretch> in_model_units(const std::vector<HeldOut>& parts) const {
    std::vector<Stretch> out;
    for (const HeldOut& h : parts) out.push_back({h.t / p_.units.time, p_.units.to_model(h.x)});
    return out;
  }

  Prepared p_;
};

class DataTask : public Task {
 public:
  std::string name() const override { return "data"; }
  std::string summary() const override {
    return "your own trajectories: --data FILE (CSV, .npy, .npz, Schmidt & Lipson text)";
  }
  TrainConfig train_config() const override { return {}; }
  bool reads_data_file() const override { return true; }
  void check_task_settings(const json& settings) const override {
    for (const auto& [key, value] : settings.items()) {
      HNN_TASKS_CHECK(std::find(data_setting_names().begin(), data_setting_names().end(), key) !=
                          data_setting_names().end(),
                      "the data task has no setting '{}' (known: {})", key,
                      fmt::join(data_setting_names(), ", "));
    }
    data_config(settings);
  }
  std::unique_ptr<TaskRun> open(const RunSettings& settings) const override {
    return std::make_unique<DataRun>(settings, prepare(settings));
  }
};

}  // namespace

std::unique_ptr<Task> make_data_task() { return std::make_unique<DataTask>(); }

}  // namespace hnn::tasks
