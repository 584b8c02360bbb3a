// `hnn train --fit sampled` (issue 29): hidden layers sampled, the last layer solved, no
// backpropagation. A sampled run is an ordinary run folder: it evaluates, rolls out and exports;
// its metrics.json says how the fit went; what does not apply to it is refused in one line
// (the options themselves: cli_options_test.cpp).

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <array>

#include "nn/sampled/sampled_fit.h"
#include "reliability_util.h"
#include "tasks/options/fit_options.h"
#include "tasks/run.h"
#include "tasks/train/stop.h"

namespace hnn::reliability {
namespace {

using nlohmann::json;

// A small spring run: few evaluation rollouts keep it fast.
Result train_spring(const TempDir& dir, const std::string& name, std::vector<std::string> extra) {
  std::vector<std::string> args = {"train",      "spring",
                                   "--hidden",   "100",
                                   "--settings", R"({"rollouts": 3})",
                                   "--out",      (dir / name).string()};
  args.insert(args.end(), extra.begin(), extra.end());
  return run_hnn(args, dir.path());
}

// --fit sampled takes no steps: the options of Adam's steps are refused with it; its own options
// are refused without it (docs/inputs.md).
std::vector<BadOption> bad_fit_options() {
  const std::string no_steps =
      " does not apply to --fit sampled: it takes no training steps (the hidden layers are "
      "sampled, the last layer solved); --fit sampled+adam fine-tunes with Adam from there";
  std::vector<BadOption> bad;
  for (const std::vector<std::string>& option :
       std::vector<std::vector<std::string>>{{"--steps", "10"},
                                             {"--batch", "10"},
                                             {"--lr", "0.1"},
                                             {"--lr-schedule", "cosine"},
                                             {"--checkpoint-every", "5"}}) {
    bad.push_back(
        {{"train", "spring", "--fit", "sampled", option[0], option[1]}, option[0] + no_steps});
  }
  for (const std::vector<std::string>& option :
       std::vector<std::vector<std::string>>{{"--sampler", "elm"},
                                             {"--rcond", "1e-10"},
                                             {"--swim-scale", "0.1"},
                                             {"--solver", "qr"},
                                             {"--regularization", "1e-8"},
                                             {"--solver-tolerance", "1e-8"},
                                             {"--solver-iterations", "50"}}) {
    bad.push_back({{"train", "spring", option[0], option[1]},
                   "spring: " + option[0] +
                       " applies to a sampled fit only (add --fit sampled or --fit sampled+adam)"});
  }
  const std::vector<BadOption> others = {
      {{"train", "spring", "--fit", "sampled", "--loss", "rollout"},
       "spring: --loss rollout does not apply to --fit sampled (the last layer is solved on dx/dt "
       "targets; --fit sampled+adam fine-tunes through the integrator)"},
      {{"train", "double-pendulum", "--model", "lnn", "--fit", "sampled+adam"},
       "double-pendulum: --fit sampled+adam does not fit an lnn: its accelerations are not linear "
       "in its last layer (they invert the Hessian of L in dq/dt), so no least-squares solve "
       "gives it (models it fits: hnn, baseline, dhnn)"},
      {{"train", "spring", "--hidden", "5000"},
       "--hidden 5000 is wider than Adam trains (4096 at most); --fit sampled takes up to 8192"},
      {{"train", "spring", "--fit", "sampled", "--model", "baseline", "--hidden", "1000"},
       "spring: sampled fit: 1000 last-layer unknowns per output but only 750 equations from 750 "
       "points; lower the width or give more points"},
      {{"train", "spring", "--fit", "sgd"}, "--fit: sgd not in {adam,sampled,sampled+adam}"},
      {{"train", "spring", "--fit", "sampled", "--sampler", "gauss"},
       "--sampler: gauss not in {elm,uswim,aswim}"},
      {{"train", "spring", "--fit", "sampled", "--solver", "svd"},
       "--solver: svd not in {lsqr,cholesky,qr,ridge,sketch}"},
      {{"train", "spring", "--fit", "sampled", "--rcond", "1"},
       "--rcond: expected auto or a number in (0, 1), got '1'"},
      {{"train", "spring", "--fit", "sampled", "--rcond", "often"},
       "--rcond: expected auto or a number in (0, 1), got 'often'"},
      {{"train", "spring", "--fit", "sampled", "--settings", R"({"rcond": "often"})"},
       "spring: --rcond must be auto or a number in (0, 1), got \"often\""},
      {{"train", "spring", "--fit", "sampled", "--settings", R"({"rcond": 2})"},
       "spring: --rcond must be in (0, 1), got 2"},
      {{"train", "spring", "--fit", "sampled", "--swim-scale", "0"},
       "--swim-scale: expected auto or a finite number > 0, got '0'"},
      {{"train", "spring", "--fit", "sampled", "--settings", R"({"swim_scale": "steep"})"},
       "spring: --swim-scale must be auto or a finite number > 0, got \"steep\""},
      {{"train", "spring", "--fit", "sampled", "--sampler", "elm", "--swim-scale", "0.1"},
       "spring: --swim-scale does not apply to --sampler elm (it draws weights at random, not "
       "from pairs of points; uswim and aswim read it)"},
      {{"train", "spring", "--fit", "sampled", "--regularization", "0"},
       "--regularization: expected a finite number > 0, got '0'"},
      {{"train", "spring", "--fit", "sampled", "--solver-iterations", "0"},
       "--solver-iterations: Value 0 not in range 1 to 100000"},
  };
  bad.insert(bad.end(), others.begin(), others.end());
  // A solver option the solver does not read (tasks/options/fit_options.h); qr by default.
  for (const auto& [solver, option, value, readers] : std::vector<std::array<std::string, 4>>{
           {"lsqr", "--rcond", "1e-10", "qr, ridge and sketch"},
           {"cholesky", "--rcond", "1e-10", "qr, ridge and sketch"},
           {"qr", "--regularization", "1e-8", "lsqr and cholesky"},
           {"ridge", "--regularization", "1e-8", "lsqr and cholesky"},
           {"sketch", "--regularization", "1e-8", "lsqr and cholesky"},
           {"qr", "--solver-tolerance", "1e-8", "lsqr and sketch"},
           {"cholesky", "--solver-tolerance", "1e-8", "lsqr and sketch"},
           {"qr", "--solver-iterations", "50", "lsqr and sketch"},
           {"ridge", "--solver-iterations", "50", "lsqr and sketch"}}) {
    bad.push_back({{"train", "spring", "--fit", "sampled", "--solver", solver, option, value},
                   "spring: " + option + " does not apply to --solver " + solver + " (read by " +
                       readers + ")"});
  }
  bad.push_back(
      {{"train", "spring", "--fit", "sampled+adam", "--steps", "2", "--regularization", "0.01"},
       "spring: --regularization does not apply to --solver qr (read by lsqr and "
       "cholesky)"});
  return bad;
}

TEST(SampledFitCli, BadFitOptionsGetOneLineAndNoRunFolder) {
  expect_refused_with_no_run_folder(bad_fit_options());
}

TEST(SampledFitCli, ASampledSpringHnnIsAnOrdinaryRunFolderThatKeepsTheEnergyAdvantage) {
  const TempDir dir;
  // The spring's dx/dt are noisy: --rcond auto (the default) cuts off the singular values that
  // only fit the noise, and the learned H keeps closed level sets beyond the data (at the peer's
  // 1e-13 its rollouts run away, the baseline's further still).
  const std::vector<std::string> fit = {"--fit", "sampled", "--quiet"};
  const Result hnn = train_spring(dir, "hnn", fit);
  ASSERT_EQ(hnn.code, 0) << hnn.err;
  std::vector<std::string> as_baseline = fit;
  as_baseline.insert(as_baseline.end(), {"--model", "baseline"});
  const Result baseline = train_spring(dir, "baseline", as_baseline);
  ASSERT_EQ(baseline.code, 0) << baseline.err;
  const json m = read_json(dir / "hnn" / "metrics.json");
  // The fit's block, its time split and size; no steps and so no loss curve.
  const json& report = m.at("fit");
  EXPECT_EQ(report.at("method"), "sampled");
  EXPECT_EQ(report.at("sampler"), "uswim");
  EXPECT_FALSE(report.at("solver").get<std::string>().empty());
  for (const char* key : {"sample_seconds", "assemble_seconds", "solve_seconds"})
    EXPECT_GE(report.at(key).get<double>(), 0) << key;
  EXPECT_EQ(report.at("columns").get<int>(), 100);
  EXPECT_EQ(report.at("rows").get<int>(), 750 * 2);  // dH/dp and -dH/dq of each training state
  EXPECT_GT(report.at("matrix_bytes").get<double>(), 0);
  // The cutoff chosen on a held-out tenth, and the error of each cutoff tried.
  EXPECT_EQ(report.at("rcond"), "auto");
  EXPECT_GE(report.at("rcond_used").get<double>(), 1e-6);
  EXPECT_EQ(report.at("rcond_validation").size(), 14u);
  EXPECT_EQ(report.at("rcond_validation").front().at("rcond").get<double>(), 1e-14);
  EXPECT_GT(report.at("rcond_validation").front().at("error").get<double>(), 0);
  EXPECT_EQ(m.at("steps"), 0);
  EXPECT_EQ(m.at("task_settings").at("fit"), "sampled");
  EXPECT_GE(m.at("train_seconds").get<double>(),
            report.at("sample_seconds").get<double>() + report.at("solve_seconds").get<double>());
  EXPECT_FALSE(fs::exists(dir / "hnn" / "loss_curve.csv"));
  EXPECT_FALSE(fs::exists(dir / "hnn" / "checkpoint"));
  // The HNN's energy advantage over an equally sampled baseline.
  const double baseline_energy =
      read_json(dir / "baseline" / "metrics.json").at("energy_mse").get<double>();
  EXPECT_LT(m.at("energy_mse").get<double>(), baseline_energy / 10);
  // What the program says: a sampled fit, and how long each part took.
  const Result shown = train_spring(dir, "shown", {"--fit", "sampled", "--sampler", "elm"});
  ASSERT_EQ(shown.code, 0) << shown.err;
  EXPECT_NE(shown.out.find("spring hnn: seed 0, sampled fit (elm), hidden 100"), std::string::npos)
      << shown.out;
  EXPECT_NE(shown.out.find("  fit        sampling "), std::string::npos) << shown.out;
  EXPECT_NE(shown.out.find("  rcond      auto chose "), std::string::npos) << shown.out;
  // Evaluated again, rolled out and exported like any run.
  const Result evaluated = run_hnn({"evaluate", (dir / "hnn").string()}, dir.path());
  ASSERT_EQ(evaluated.code, 0) << evaluated.err;
  EXPECT_NE(evaluated.out.find("sampled fit (uswim)"), std::string::npos) << evaluated.out;
  ASSERT_EQ(run_hnn({"evaluate", (dir / "hnn").string(), "--json"}, dir.path()).code, 0);
  const Result rollout = run_hnn(
      {"rollout", (dir / "hnn").string(), "--out", (dir / "rollout.csv").string()}, dir.path());
  EXPECT_EQ(rollout.code, 0) << rollout.err;
  EXPECT_GT(lines(read_text(dir / "rollout.csv")).size(), 10u);
  const Result exported = run_hnn(
      {"export", (dir / "hnn").string(), "--format", "json", "--out", (dir / "h.json").string()},
      dir.path());
  EXPECT_EQ(exported.code, 0) << exported.err;
  EXPECT_TRUE(fs::exists(dir / "h.json"));
  // A fit that fails (too wide for the 750 training states) leaves the run it would replace.
  const Result too_wide = train_spring(
      dir, "hnn", {"--fit", "sampled", "--model", "baseline", "--hidden", "1000", "--force"});
  EXPECT_EQ(too_wide.code, 1);
  EXPECT_EQ(read_json(dir / "hnn" / "metrics.json"), m);
  // No steps to resume or continue.
  const Result resumed = run_hnn({"train", "--resume", (dir / "hnn").string()}, dir.path());
  EXPECT_EQ(resumed.code, 1);
  EXPECT_EQ(resumed.err, "hnn: error: '" + (dir / "hnn").string() +
                             "' holds a run fitted with --fit sampled: it took no training steps, "
                             "so there is nothing to resume or continue (train a new run with "
                             "--fit sampled+adam --steps N to fine-tune with Adam)\n");
}

TEST(SampledFitCli, SampledThenAdamRunsItsStepsFromTheSampledWeights) {
  const TempDir dir;
  const Result r = train_spring(
      dir, "run", {"--fit", "sampled+adam", "--steps", "20", "--lr", "1e-4", "--quiet"});
  ASSERT_EQ(r.code, 0) << r.err;
  const json m = read_json(dir / "run" / "metrics.json");
  EXPECT_EQ(m.at("fit").at("method"), "sampled+adam");
  EXPECT_EQ(m.at("fit").at("rcond"), "auto");
  EXPECT_EQ(m.at("steps"), 20);
  const std::vector<std::string> curve = lines(read_text(dir / "run" / "loss_curve.csv"));
  ASSERT_FALSE(curve.empty());
  EXPECT_TRUE(curve.back().starts_with("20,")) << curve.back();
  // From the sampled weights: the first recorded loss is already the sampled fit's, far below a
  // fresh Adam run's after as many steps.
  ASSERT_EQ(train_spring(dir, "adam", {"--steps", "20", "--lr", "1e-4", "--quiet"}).code, 0);
  EXPECT_LT(m.at("test_loss").get<double>(),
            read_json(dir / "adam" / "metrics.json").at("test_loss").get<double>() / 10);
  // Continued with Adam from its checkpoint, not sampled again: the run keeps its fit's report.
  const Result continued = run_hnn(
      {"train", "--resume", (dir / "run").string(), "--steps", "30", "--quiet"}, dir.path());
  ASSERT_EQ(continued.code, 0) << continued.err;
  const json more = read_json(dir / "run" / "metrics.json");
  EXPECT_EQ(more.at("steps"), 30);
  EXPECT_EQ(more.at("fit"), m.at("fit"));
  EXPECT_NE(continued.out.find("sampled fit (uswim), then Adam 30 steps"), std::string::npos)
      << continued.out;
}

TEST(SampledFitCli, AnInterruptedSampledThenAdamRunKeepsItsFitWhenResumed) {
  const TempDir dir;
  tasks::RunOptions o;
  o.task = "spring";
  o.hidden = std::vector<int>{100};
  o.steps = 20;
  o.learning_rate = 1e-4;
  o.task_settings = {{"rollouts", 3}, {"fit", "sampled+adam"}};
  o.quiet = true;
  o.out = dir / "run";
  tasks::StopSignal stop;
  stop.requested = true;  // stops after step 1, checkpointed, before metrics.json
  o.stop = &stop;
  EXPECT_THROW(tasks::run_training(o), tasks::TrainingInterrupted);
  ASSERT_FALSE(fs::exists(dir / "run" / "metrics.json"));
  const json report = tasks::recorded_fit(dir / "run");  // from the checkpoint
  ASSERT_TRUE(report.is_object()) << report.dump();
  EXPECT_EQ(report.at("method"), "sampled+adam");
  const Result resumed =
      run_hnn({"train", "--resume", (dir / "run").string(), "--quiet"}, dir.path());
  ASSERT_EQ(resumed.code, 0) << resumed.err;
  const json m = read_json(dir / "run" / "metrics.json");
  EXPECT_EQ(m.at("steps"), 20);
  EXPECT_EQ(m.at("fit"), report);
}

TEST(SampledFitCli, ASampledThenAdamFitThatFailsWritesNothing) {
  const TempDir dir;
  // Too wide for the 750 training states: the sampling fails before the folder is made.
  const std::vector<std::string> too_wide = {"--fit",    "sampled+adam", "--model", "baseline",
                                             "--hidden", "1000",         "--steps", "5"};
  const Result fresh = train_spring(dir, "new", too_wide);
  EXPECT_EQ(fresh.code, 1);
  EXPECT_FALSE(fs::exists(dir / "new"));
  // Nor is a run it would replace with --force removed.
  ASSERT_EQ(train_spring(dir, "old", {"--steps", "5", "--quiet"}).code, 0);
  const json before = read_json(dir / "old" / "metrics.json");
  std::vector<std::string> forced = too_wide;
  forced.push_back("--force");
  const Result replaced = train_spring(dir, "old", forced);
  EXPECT_EQ(replaced.code, 1);
  EXPECT_EQ(read_json(dir / "old" / "metrics.json"), before);
  EXPECT_TRUE(fs::exists(dir / "old" / "params.bin"));
}

TEST(SampledFitCli, ThePixelPendulumSaysWhyItTakesNoFit) {
  const TempDir dir;
  for (const std::vector<std::string>& option :
       {std::vector<std::string>{"--fit", "sampled"}, {"--solver-tolerance", "1e-10"}}) {
    std::vector<std::string> args = {"train", "pixel-pendulum", "--out", (dir / "run").string()};
    args.insert(args.end(), option.begin(), option.end());
    const Result r = run_hnn(args, dir.path());
    EXPECT_EQ(r.code, 1);
    EXPECT_EQ(r.err, "hnn: error: pixel-pendulum: " + option[0] +
                         " does not apply: its model is an autoencoder and an HNN of its latent "
                         "space trained together on frames, by Adam only (a sampled fit solves a "
                         "field model's last layer on dx/dt targets, which frames do not give)\n");
    EXPECT_FALSE(fs::exists(dir / "run"));
  }
}

TEST(SampledFitCli, TheDataTaskFitsItsTrainingSplit) {
  const TempDir dir;
  const std::string csv = simulated_pendulum_csv(dir.path());
  const Result r =
      run_hnn({"train", "data", "--data", csv, "--coords", "q", "--momenta", "p", "--fit",
               "sampled", "--hidden", "40", "--quiet", "--out", (dir / "run").string()},
              dir.path());
  ASSERT_EQ(r.code, 0) << r.err;
  const json m = read_json(dir / "run" / "metrics.json");
  EXPECT_EQ(m.at("fit").at("method"), "sampled");
  EXPECT_LT(m.at("test_loss").get<double>(), 1e-2);
}

// An explicit --rcond is used as given, with no validation; "auto" given is the default.
TEST(SampledFitCli, AnExplicitRcondIsUsedAsGiven) {
  const TempDir dir;
  for (const char* rcond : {"1e-3", "auto"}) {
    const Result r = train_spring(dir, rcond, {"--fit", "sampled", "--rcond", rcond});
    ASSERT_EQ(r.code, 0) << r.err;
    const json fit = read_json(dir / rcond / "metrics.json").at("fit");
    const bool given = std::string(rcond) != "auto";
    EXPECT_EQ(fit.at("rcond"), given ? json(1e-3) : json("auto"));
    EXPECT_EQ(fit.at("rcond_validation").empty(), given);
    if (given) {
      EXPECT_EQ(fit.at("rcond_used").get<double>(), 1e-3);
    }
    EXPECT_NE(r.out.find(given ? "(qr, rcond 0.001)" : "auto chose"), std::string::npos) << r.out;
  }
}

// A sweep takes --rcond's values as the command line does.
TEST(SampledFitCli, ASweepTakesAutoOrACutoff) {
  const TempDir dir;
  write_text(dir / "good.json",
             R"({"task": ["spring"], "fit": ["sampled"], "rcond": ["auto", 1e-3]})");
  const Result listed =
      run_hnn({"sweep", (dir / "good.json").string(), "--out", (dir / "good").string(), "--list"},
              dir.path());
  ASSERT_EQ(listed.code, 0) << listed.err;
  EXPECT_NE(listed.out.find("--rcond auto "), std::string::npos) << listed.out;
  EXPECT_NE(listed.out.find("--rcond 0.001 "), std::string::npos) << listed.out;
  write_text(dir / "bad.json", R"({"task": ["spring"], "fit": ["sampled"], "rcond": ["often"]})");
  const Result refused =
      run_hnn({"sweep", (dir / "bad.json").string(), "--out", (dir / "bad").string(), "--list"},
              dir.path());
  EXPECT_EQ(refused.code, 1);
  EXPECT_NE(refused.err.find(R"(key 'rcond': expected "auto" or a number in (0, 1), got "often")"),
            std::string::npos)
      << refused.err;
}

TEST(SampledFitCli, HelpShowsTheFitOptions) {
  const TempDir dir;
  const Result r = run_hnn({"train", "--help"}, dir.path());
  ASSERT_EQ(r.code, 0);
  EXPECT_NE(r.out.find("Training without backpropagation"), std::string::npos) << r.out;
  for (const char* option : {"--fit", "--sampler", "--rcond", "--solver", "--regularization",
                             "--solver-tolerance", "--solver-iterations"})
    EXPECT_NE(r.out.find(std::string("  ") + option + " "), std::string::npos) << option;
  // The defaults shown are the sampled fit's own (nn/sampled/sampled_fit.h).
  const nn::SampledFitConfig defaults;
  for (const auto& [option, value] : std::vector<std::pair<std::string, std::string>>{
           {"--sampler", std::string(nn::name_of(nn::kHiddenSamplerNames, defaults.sampler))},
           {"--solver", std::string(nn::name_of(nn::kLeastSquaresSolverNames, defaults.solver))},
           {"--rcond", defaults.rcond ? fmt::format("{:g}", *defaults.rcond) : "auto"},
           {"--regularization", fmt::format("{:g}", defaults.regularization)},
           {"--solver-tolerance", fmt::format("{:g}", defaults.tolerance)},
           {"--solver-iterations", fmt::format("{}", defaults.max_iterations)}}) {
    const std::size_t at = r.out.find("  " + option + " ");
    ASSERT_NE(at, std::string::npos) << option;
    const std::string line = r.out.substr(at, r.out.find('\n', at) - at);
    EXPECT_NE(line.find("(default " + value + ")"), std::string::npos) << line;
  }
}

}  // namespace
}  // namespace hnn::reliability
