// docs/inputs.md, "Command-line options": every bad value gets one line on stderr,
// "hnn: error: <what>", exit status 1, and no run folder.

#include <gtest/gtest.h>

#include <map>
#include <set>

#include "reliability_util.h"
#include "tasks/experiments/registry.h"
#include "tasks/options/train_options.h"
#include "tasks/run.h"

namespace hnn::reliability {
namespace {

std::vector<BadOption> bad_train_options() {
  const std::string positive = "expected an integer >= 1, got ";
  const std::string finite = "expected a finite number > 0, got ";
  return {
      {{"train", "spring", "--steps", "0"}, "--steps: " + positive + "'0'"},
      {{"train", "spring", "--steps", "-3"}, "--steps: " + positive + "'-3'"},
      {{"train", "spring", "--steps", "1.5"}, "--steps: " + positive + "'1.5'"},
      {{"train", "spring", "--steps", "99999999999"}, "--steps: " + positive + "'99999999999'"},
      {{"train", "spring", "--steps", "ten"}, "--steps: " + positive + "'ten'"},
      {{"train", "spring", "--batch", "-1"}, "--batch: expected an integer >= 0, got '-1'"},
      {{"train", "spring", "--batch", "751", "--hidden", "8"},
       "--batch 751 is larger than the training set (750 rows)"},
      {{"train", "spring", "--model", "transformer"},
       "--model: transformer not in {hnn,baseline,dhnn,lnn,chnn,clnn,hnn-mass}"},
      {{"train", "pixel-pendulum", "--model", "dhnn"},
       "task 'pixel-pendulum' does not train a dhnn model (its models: hnn, baseline)"},
      {{"train", "spring", "--dtype", "half"}, "--dtype: half not in {float,double}"},
      {{"train", "spring", "--seed", "abc"},
       "--seed: expected an integer from 0 to 18446744073709551615, got 'abc'"},
      {{"train", "spring", "--seed", "-1"},
       "--seed: expected an integer from 0 to 18446744073709551615, got '-1'"},
      {{"train", "spring", "--seed", "18446744073709551616"},
       "--seed: expected an integer from 0 to 18446744073709551615, got '18446744073709551616'"},
      {{"train", "spring", "--threads", "0"},
       "--threads: expected an integer from 1 to 256, got '0'"},
      {{"train", "spring", "--lr", "0"}, "--lr: " + finite + "'0'"},
      {{"train", "spring", "--lr", "-1e-3"}, "--lr: " + finite + "'-1e-3'"},
      {{"train", "spring", "--lr", "nan"}, "--lr: " + finite + "'nan'"},
      {{"train", "spring", "--lr", "inf"}, "--lr: " + finite + "'inf'"},
      {{"train", "spring", "--hidden", "0"},
       "--hidden: expected an integer from 1 to 8192, got '0'"},
      {{"train", "spring", "--hidden", "200", "50000"},
       "--hidden: expected an integer from 1 to 8192, got '50000'"},
      {{"train", "spring", "--threads", "257"},
       "--threads: expected an integer from 1 to 256, got '257'"},
      {{"train", "spring", "--checkpoint-every", "0"}, "--checkpoint-every: " + positive + "'0'"},
      {{"train", "spring", "--checkpoint-every", "x"}, "--checkpoint-every: " + positive + "'x'"},
      {{"train", "spring", "--data", "x.txt"},
       "task 'spring' does not read a data file (--data applies to measured-data tasks such as "
       "real-pendulum)"},
      {{"train", "spring", "--settings", "{\"trials\": 20}"},
       "task 'spring' has no setting 'trials' (known: loss, horizon, integrator, dt, norm, "
       "minibatches, baseline_output, masses, fit, sampler, swim_scale, rcond, solver, "
       "regularization, "
       "solver_tolerance, "
       "solver_iterations, sample_dt, "
       "t_end, rollouts, rollout_t_end)"},
      {{"train", "two-body", "--settings", "{\"rollouts\": 0}"},
       "two-body: rollouts must be an integer from 1 to 1000, got 0"},
      {{"train", "spring", "--settings", "{\"rollout_t_end\": -2}"},
       "spring: rollout_t_end must be a finite number > 0, got -2"},
      {{"train", "pixel-pendulum", "--settings", "[20]"},
       "--settings must be a JSON object like '{\"trials\": 20}', got '[20]'"},
      {{"train", "pixel-pendulum", "--settings", "{\"trials\": 1}"},
       "pixel-pendulum: trials must be at least 2, got 1"},
      {{"train", "pixel-pendulum", "--settings", "{\"trails\": 20}"},
       "pixel-pendulum has no setting 'trails' (known: ae_hidden, atol, dynamics_weight_decay, "
       "frames_per_trial, hnn_weight, rollout_frames, rollout_trials, rtol, test_fraction, "
       "trials)"},
      {{"train", "pixel-pendulum", "--settings", "{\"steps\": 20}"},
       "pixel-pendulum: 'steps' is a training setting: give it as an option (--steps, --batch, "
       "--lr, --hidden), not a task setting"},
      {{"train", "spring", "--optimizer", "sgd"}, "--optimizer: sgd not in {adam,adamw}"},
      {{"train", "pixel-pendulum", "--optimizer", "adamw"},
       "pixel-pendulum: --optimizer adamw does not apply: its autoencoder and latent HNN train "
       "with Adam's L2 weight decay on the autoencoder only (task settings weight_decay, "
       "dynamics_weight_decay)"},
      {{"train", "spring", "--fit", "sampled", "--optimizer", "adam"},
       "--optimizer does not apply to --fit sampled: it takes no training steps (the hidden "
       "layers are sampled, the last layer solved); --fit sampled+adam fine-tunes with Adam from "
       "there"},
      {{"train", "spring", "--bogus"}, "The following argument was not expected: --bogus"},
      {{"train"}, "train needs a TASK (or --resume DIR)"},
  };
}

TEST(CliOptions, BadTrainOptionsGetOneLineAndNoRunFolder) {
  expect_refused_with_no_run_folder(bad_train_options());
}

TEST(CliOptions, UnknownTaskListsTheKnownOnes) {
  const TempDir dir;
  const Result r = run_hnn({"train", "double-spring", "--out", (dir / "run").string()}, dir.path());
  EXPECT_EQ(r.code, 1);
  EXPECT_EQ(lines(r.err).size(), 1u);
  EXPECT_TRUE(
      r.err.starts_with("hnn: error: unknown task 'double-spring' (known: spring, "
                        "pendulum, real-pendulum, two-body, three-body"))
      << r.err;
  EXPECT_FALSE(fs::exists(dir / "run"));
}

TEST(CliOptions, BadCommandsAndOtherSubcommandsGetOneLine) {
  const TempDir dir;
  const std::string missing = (dir / "missing").string();
  write_text(dir / "file", "x");
  const std::vector<BadOption> cases = {
      {{}, "A subcommand is required"},
      {{"fly"}, "A subcommand is required"},
      {{"evaluate", missing}, "run: Directory does not exist: " + missing},
      {{"rollout", missing}, "run: Directory does not exist: " + missing},
      {{"rollout", dir.path().string(), "--dt", "0"},
       "--dt: expected a finite number > 0, got '0'"},
      {{"rollout", dir.path().string(), "--points", "1"},
       "--points: expected an integer from 2 to 1000000, got '1'"},
      {{"rollout", dir.path().string(), "--trajectories", "0"},
       "--trajectories: expected an integer from 1 to 100000, got '0'"},
      {{"rollout", dir.path().string(), "--dt", "-1"},
       "--dt: expected a finite number > 0, got '-1'"},
      {{"rollout", dir.path().string(), "--dt", "nan"},
       "--dt: expected a finite number > 0, got 'nan'"},
      {{"rollout", dir.path().string(), "--rtol", "0"},
       "--rtol: expected a finite number > 0, got '0'"},
      {{"rollout", dir.path().string(), "--t-end", "inf"},
       "--t-end: expected a finite number > 0, got 'inf'"},
      {{"rollout", dir.path().string(), "--points", "1000001"},
       "--points: expected an integer from 2 to 1000000, got '1000001'"},
      {{"rollout", dir.path().string(), "--trajectories", "100001"},
       "--trajectories: expected an integer from 1 to 100000, got '100001'"},
      {{"evaluate", dir.path().string(), "--data", missing},
       "--data: File does not exist: " + missing},
      {{"reproduce", "--seeds", "0"}, "--seeds: expected an integer >= 1, got '0'"},
      {{"reproduce", "--jobs", "100"}, "--jobs: expected an integer from 1 to 64, got '100'"},
      {{"reproduce", "--steps", "0"}, "--steps: expected an integer >= 1, got '0'"},
      {{"reproduce", "--dtype", "half"}, "--dtype: half not in {float,double}"},
      {{"reproduce", "--no-reversibility=x", "--out", (dir / "results").string()},
       "Could not convert: --no-reversibility = x"},
      {{"reproduce", "--tasks", "spring,nope", "--out", (dir / "results").string()},
       "unknown task 'nope' (known: spring, pendulum, real-pendulum, two-body, three-body, "
       "pixel-pendulum, damped-spring, double-pendulum, real-double-pendulum, henon-heiles, "
       "pendulum-scattered, double-pendulum-scattered, chain-pendulum-2, chain-pendulum-3, "
       "chain-pendulum-4, chain-pendulum-5, coupled-pendulums, magnet-pendulum, gyroscope, rotor, "
       "data)"},
      {{"reproduce", "--tasks", "data", "--out", (dir / "results").string()},
       "reproduce runs the paper's tasks (spring, pendulum, real-pendulum, two-body, three-body, "
       "pixel-pendulum); 'data' is not one of them: train it with hnn train data"},
      {{"bump", dir.path().string(), "--before", "0"},
       "--before: expected a finite number > 0, got '0'"},
      {{"bump", dir.path().string(), "--dt", "nan"},
       "--dt: expected a finite number > 0, got 'nan'"},
      {{"bump", dir.path().string(), "--trajectory", "-2"},
       "--trajectory: Value -2 not in range -1 to 1000000"},
      {{"animate", dir.path().string(), dir.path().string(), "--trajectories", "17"},
       "--trajectories: Value 17 not in range 1 to 16"},
      {{"animate", dir.path().string(), dir.path().string(), "--stride", "0"},
       "--stride: Value 0 not in range 1 to 1000"},
      {{"reversibility"}, "reversibility: give run folders or --report RESULTS"},
      {{"reversibility", dir.path().string(), "--t-end", "0"},
       "--t-end: expected a finite number > 0, got '0'"},
      {{"reversibility", dir.path().string(), "--dt", "nan"},
       "--dt: expected a finite number > 0, got 'nan'"},
      {{"reversibility", dir.path().string(), "--trajectories", "0"},
       "--trajectories: Value 0 not in range 1 to 1000"},
      {{"reversibility", missing}, "runs: Directory does not exist: " + missing},
      {{"bump", missing}, "run: Directory does not exist: " + missing},
      {{"animate", missing, dir.path().string()}, "baseline: Directory does not exist: " + missing},
      {{"train", "spring", "--out", (dir / "file").string()},
       "--out '" + (dir / "file").string() + "' is a file, not a folder"},
  };
  for (const BadOption& bad : cases) {
    std::string what;
    for (const std::string& a : bad.args) what += a + " ";
    expect_one_line_error(run_hnn(bad.args, dir.path()), bad.message, what);
  }
}

TEST(CliOptions, HelpStillExitsZero) {
  const TempDir dir;
  const Result r = run_hnn({"train", "--help"}, dir.path());
  EXPECT_EQ(r.code, 0);
  EXPECT_NE(r.out.find("--resume"), std::string::npos);
  EXPECT_NE(r.out.find("--checkpoint-every"), std::string::npos);
}

// A run that ends no better than it started (here: a learning rate of 1e3) exits 0, as it
// finished, but says so on the terminal and in metrics.json.
TEST(CliOptions, ARunThatEndsNoBetterThanItStartedIsWarnedAbout) {
  const TempDir dir;
  const Result r = run_hnn({"train", "spring", "--lr", "1e3", "--steps", "30", "--hidden", "8",
                            "--quiet", "--out", (dir / "run").string()},
                           dir.path());
  ASSERT_EQ(r.code, 0) << r.err;
  const nlohmann::json warnings = read_json(dir / "run" / "metrics.json")["warnings"];
  ASSERT_FALSE(warnings.empty());
  for (const auto& warning : warnings) {
    EXPECT_NE(r.err.find("hnn: warning: " + warning.get<std::string>() + "\n"), std::string::npos)
        << r.err;
  }
}

// ---- the table of `hnn train`'s options (tasks/options/train_options.h) makes each of its forms
// -------

using nlohmann::json;
using tasks::TrainOption;

// "--model"; "task" for the positional TASK.
std::string cli_name(const TrainOption& option) {
  const std::string name(option.name);
  return option.kind == tasks::ValueKind::kTask ? name : "--" + name;
}

TEST(TrainOptionsTable, EveryRowIsAnOptionOfHnnTrainUnderItsHeadingWithItsDefault) {
  const TempDir dir;
  const Result r = run_hnn({"train", "--help"}, dir.path());
  ASSERT_EQ(r.code, 0);
  // Each option's line (two spaces in; deeper lines carry on a help text) under its heading.
  std::map<std::string, std::pair<std::string, std::string>> listed;  // name -> heading, line
  std::string heading;
  for (const std::string& line : lines(r.out)) {
    if (!line.empty() && line[0] != ' ') heading = line.substr(0, line.find_last_of(':'));
    if (line.size() < 3 || !line.starts_with("  ") || line[2] == ' ') continue;
    listed[line.substr(2, line.find(' ', 2) - 2)] = {heading, line};
  }
  listed.erase("-h,--help");
  EXPECT_EQ(listed.size(), tasks::train_options().size()) << r.out;
  for (const TrainOption& option : tasks::train_options()) {
    const std::string name = cli_name(option);
    ASSERT_TRUE(listed.count(name)) << name << " is not in hnn train --help:\n" << r.out;
    const auto& [under, line] = listed.at(name);
    const std::string group(option.group);
    EXPECT_EQ(under, option.kind == tasks::ValueKind::kTask ? "Positionals"
                     : group.empty()                        ? "Options"
                                                            : group)
        << name;
    if (!option.default_shown.empty()) {
      EXPECT_NE(line.find("(default: " + std::string(option.default_shown) + ")"),
                std::string::npos)
          << line;
    }
    if (option.default_by_task) {
      EXPECT_NE(line.find("(default: each task's own: "), std::string::npos) << line;
    }
  }
}

TEST(TrainOptionsTable, TheDefaultsShownAreRunOptionsOwn) {
  const std::unique_ptr<tasks::Task> task = tasks::make_task("spring");
  const json defaults = tasks::resolve(*task, {.task = "spring"}).to_json();
  for (const TrainOption& option : tasks::train_options()) {
    if (option.default_shown.empty()) continue;
    const std::string text(option.default_shown);
    tasks::RunOptions o{.task = "spring"};
    tasks::apply(option, option.kind == tasks::ValueKind::kChoice ? json(text) : json::parse(text),
                 o);
    EXPECT_EQ(tasks::resolve(*task, o).to_json(), defaults) << option.name;
  }
}

TEST(TrainOptionsTable, TheSweepKeysAreItsRowsInRankOrderAndTheOthersAreRefusedWithTheReason) {
  const TempDir dir;
  // A value of every sweep key: a data run that trains through an integrator.
  const json values = json::parse(R"({
      "task": "data", "model": "baseline", "seed": 3, "dtype": "float", "preset": "lean",
      "hidden": [8], "steps": 5, "batch": 0, "lr": 0.01, "lr-schedule": "cosine",
      "optimizer": "adamw",
      "data": "x.csv", "settings": {"threshold": 0.2}, "checkpoint-every": 2, "coords": "q",
      "momenta": "p", "velocities": "v", "derivatives": "dq,dp", "time": "t",
      "trajectory": "traj", "split": "time", "test-fraction": 0.3, "hamiltonian": "q^2",
      "loss": "rollout", "horizon": 2, "integrator": "leapfrog", "dt": 0.05, "norm": "l1",
      "minibatches": "epochs",
      "fit": "sampled+adam", "sampler": "aswim", "swim-scale": 0.2, "rcond": 1e-10, "solver": "qr",
      "regularization": 1e-9, "solver-tolerance": 1e-10, "solver-iterations": 50,
      "baseline-output": "field", "masses": "known"})");
  json spec = json::object();
  std::vector<const TrainOption*> keys;
  for (const TrainOption& option : tasks::train_options()) {
    const std::string name(option.name);
    if (!option.sweep_owned.empty()) {
      write_text(dir / "owned.json", json({{"task", {"spring"}}, {name, {1}}}).dump());
      const Result r = run_hnn(
          {"sweep", (dir / "owned.json").string(), "--out", (dir / "owned").string(), "--list"},
          dir.path());
      EXPECT_EQ(r.code, 1) << name;
      EXPECT_NE(r.err.find("key '" + name + "': " + std::string(option.sweep_owned)),
                std::string::npos)
          << r.err;
      continue;
    }
    ASSERT_TRUE(values.contains(name)) << "give the sweep key " << name << " a value here";
    spec[name] = json::array({values.at(name)});  // not {x}: clang reads that as a copy
    keys.push_back(&option);
  }
  EXPECT_EQ(keys.size(), values.size());
  std::sort(keys.begin(), keys.end(), [](const TrainOption* a, const TrainOption* b) {
    return a->sweep_rank < b->sweep_rank;
  });
  // No solver reads every solver key (the others are refused, tasks/options/fit_options.h): lsqr
  // lists a run with every key but --rcond, qr one with --rcond but not lsqr's own.
  const auto listed_in_rank_order = [&](json run, const std::vector<std::string>& dropped) {
    for (const std::string& name : dropped) run.erase(name);
    write_text(dir / "all.json", run.dump());
    const Result r =
        run_hnn({"sweep", (dir / "all.json").string(), "--out", (dir / "all").string(), "--list"},
                dir.path());
    ASSERT_EQ(r.code, 0) << r.err;
    std::size_t at = r.out.find("hnn train data ");
    ASSERT_NE(at, std::string::npos) << r.out;
    for (const TrainOption* key : keys) {
      if (key->kind == tasks::ValueKind::kTask || !run.contains(key->name)) continue;
      const std::size_t next = r.out.find(" --" + std::string(key->name) + " ", at);
      EXPECT_NE(next, std::string::npos) << key->name << " missing or out of order: " << r.out;
      at = next == std::string::npos ? at : next;
    }
  };
  spec["solver"] = {"lsqr"};
  listed_in_rank_order(spec, {"rcond"});
  spec["solver"] = {"qr"};
  listed_in_rank_order(spec, {"regularization", "solver-tolerance", "solver-iterations"});
  std::set<int> ranks;
  for (const TrainOption* key : keys) ranks.insert(key->sweep_rank);
  EXPECT_EQ(ranks.size(), keys.size());
  EXPECT_EQ(*ranks.begin(), 0);
  EXPECT_EQ(*ranks.rbegin(), int(keys.size()) - 1);
}

TEST(TrainOptionsTable, TheJsonFormReadsBackAsItWasWrittenAndOldRunsGetTheRecordedDefaults) {
  const std::unique_ptr<tasks::Task> task = tasks::make_task("spring");
  const tasks::RunOptions o{.task = "spring",
                            .model = nn::ModelKind::kBaseline,
                            .seed = 9,
                            .dtype = tasks::Dtype::kFloat,
                            .preset = tasks::Preset::kLean,
                            .threads = 3,
                            .steps = 7,
                            .batch_size = 5,
                            .hidden = std::vector<int>{8, 4},
                            .learning_rate = 0.02,
                            .weight_decay = 1e-4,
                            .lr_schedule = tasks::LrSchedule::kCosine,
                            .optimizer = tasks::OptimizerKind::kAdamW,
                            .task_settings = {{"loss", "rollout"}, {"horizon", 2}}};
  const json j = tasks::resolve(*task, o).to_json();
  // Its keys: the table's recorded options, and the weight decay (each task's, no option's).
  std::set<std::string> recorded = {"weight_decay"};
  for (const TrainOption& option : tasks::train_options())
    if (!option.key.empty() && option.lands != tasks::Lands::kTaskSetting)
      recorded.insert(std::string(option.key));
  std::set<std::string> written;
  for (const auto& [key, value] : j.items()) written.insert(key);
  EXPECT_EQ(written, recorded);
  EXPECT_EQ(tasks::resolve(*task, tasks::options_from_json(j, "test")).to_json(), j);
  // A run from before a key existed reads that key's recorded default.
  json old = j;
  for (const TrainOption& option : tasks::train_options())
    if (!option.recorded_default.empty()) old.erase(std::string(option.key));
  const json back = tasks::resolve(*task, tasks::options_from_json(old, "old")).to_json();
  for (const TrainOption& option : tasks::train_options()) {
    if (option.recorded_default.empty()) continue;
    EXPECT_EQ(back[std::string(option.key)], json::parse(option.recorded_default)) << option.name;
  }
}

// A sampled fit's settings are task settings: recorded as given, read back to the same fit; an
// Adam run's settings do not change (no key of the fit).
TEST(TrainOptionsTable, ASampledFitsSettingsReadBackAsWrittenAndAdamRunsKeepTheirs) {
  const std::unique_ptr<tasks::Task> task = tasks::make_task("spring");
  const json given = {{"fit", "sampled"},
                      {"sampler", "aswim"},
                      {"swim_scale", 0.2},
                      {"rcond", 1e-10},
                      {"solver", "qr"},
                      {"regularization", 1e-9},
                      {"solver_tolerance", 1e-10},
                      {"solver_iterations", 50}};
  const tasks::RunSettings s = tasks::resolve(
      *task, {.task = "spring", .hidden = std::vector<int>{30}, .task_settings = given});
  const json j = s.to_json();
  EXPECT_EQ(j.at("task_settings"), given);
  EXPECT_EQ(j.at("steps"), 0);  // a sampled fit takes none
  const tasks::RunSettings back = tasks::resolve(*task, tasks::options_from_json(j, "test"));
  EXPECT_EQ(back.to_json(), j);
  EXPECT_EQ(back.fit.method, tasks::FitMethod::kSampled);
  EXPECT_EQ(back.fit.sampled.sampler, nn::HiddenSampler::kAswim);
  EXPECT_EQ(back.fit.sampled.solver, nn::LeastSquaresSolver::kQr);
  EXPECT_EQ(back.fit.sampled.rcond, 1e-10);
  EXPECT_EQ(back.fit.sampled.swim_scale, 0.2);
  EXPECT_EQ(back.fit.sampled.regularization, 1e-9);
  EXPECT_EQ(back.fit.sampled.tolerance, 1e-10);
  EXPECT_EQ(back.fit.sampled.max_iterations, 50);
  const json adam = tasks::resolve(*task, {.task = "spring"}).to_json();
  EXPECT_EQ(adam.at("task_settings"), json::object());
  EXPECT_EQ(adam.at("steps"), task->train_config().steps);
}

}  // namespace
}  // namespace hnn::reliability
