#include "tasks/studies/reproduce.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <map>
#include <mutex>
#include <thread>

#include "nn/atomic_file.h"
#include "tasks/experiments/registry.h"
#include "tasks/report/reversibility_table.h"
#include "tasks/report/table1.h"
#include "tasks/run.h"
#include "tasks/studies/published.h"

namespace hnn::tasks {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr nn::ModelKind kModels[] = {nn::ModelKind::kBaseline, nn::ModelKind::kHnn};
const char* const kAveraged[] = {"train_loss", "train_loss_se", "test_loss",     "test_loss_se",
                                 "energy_mse", "energy_mse_se", "train_seconds", "eval_seconds"};

fs::path run_dir(const ReproduceOptions& o, const std::string& task, nn::ModelKind model,
                 int seed) {
  const fs::path dir = o.out / task / std::string(nn::to_string(model));
  return o.seeds == 1 ? dir : dir / fmt::format("seed-{}", seed);
}

// Runs every (task, model, seed) on `jobs` threads; the tape is per thread, so runs are
// independent. Results keep the order of `runs`.
std::vector<json> run_all(const std::vector<RunOptions>& runs, int jobs) {
  std::vector<json> results(runs.size());
  std::vector<std::exception_ptr> errors(runs.size());
  std::atomic<std::size_t> next{0};
  std::mutex print;
  const auto worker = [&] {
    for (std::size_t i; (i = next++) < runs.size();) {
      try {
        results[i] = run_training(runs[i]);
        const std::lock_guard lock(print);
        fmt::print(
            stderr, "  {:<14} {:<9} seed {}  test loss {:.4e}  energy MSE {}  ({:.1f} s)\n",
            runs[i].task, nn::to_string(runs[i].model), runs[i].seed,
            results[i]["test_loss"].is_number() ? results[i]["test_loss"].get<double>() : NAN,
            results[i]["energy_mse"].is_number()
                ? fmt::format("{:.4e}", results[i]["energy_mse"].get<double>())
                : "n/a",
            results[i]["train_seconds"].get<double>());
      } catch (...) {
        errors[i] = std::current_exception();
      }
    }
  };
  std::vector<std::thread> pool;
  for (int j = 1; j < jobs; ++j) pool.emplace_back(worker);
  worker();
  for (std::thread& t : pool) t.join();
  for (const std::exception_ptr& e : errors)
    if (e) std::rethrow_exception(e);
  return results;
}

// One row of table1.json: the mean over seeds of each metric, with the paper's values.
json table_row(const PaperRow& paper, const std::vector<json>& seeds) {
  json row = seeds.front();
  for (const char* key : kAveraged) {
    double sum = 0;
    int count = 0;
    for (const json& s : seeds) {
      if (s[key].is_number()) {
        sum += s[key].get<double>();
        ++count;
      }
    }
    row[key] = count == int(seeds.size()) ? json(sum / count) : json(nullptr);
  }
  row["seeds"] = seeds.size();
  row.erase("seed");
  row["seed"] = seeds.front()["seed"];
  row["paper_train_loss"] = paper.train_loss.mean;
  row["paper_train_loss_se"] = paper.train_loss.se;
  row["paper_test_loss"] = paper.test_loss.mean;
  row["paper_test_loss_se"] = paper.test_loss.se;
  row["paper_energy_mse"] = paper.energy_mse.mean;
  row["paper_energy_mse_se"] = paper.energy_mse.se;
  return row;
}

std::vector<std::string> table_notes(const std::vector<std::string>& tasks) {
  std::vector<std::string> notes;
  for (const std::string& task : tasks) {
    const std::string note = make_task(task)->table_note();
    if (!note.empty()) notes.push_back(note);
  }
  return notes;
}

}  // namespace

namespace {

// Every (task, model, seed) run, each checked before any work.
std::vector<RunOptions> plan_runs(const ReproduceOptions& o,
                                  const std::vector<std::string>& tasks) {
  std::vector<RunOptions> runs;
  const std::vector<std::string> paper = paper_task_names();
  for (const std::string& task : tasks) {
    make_task(task);  // an unknown name: the known ones
    HNN_TASKS_CHECK(std::find(paper.begin(), paper.end(), task) != paper.end(),
                    "reproduce runs the paper's tasks ({}); '{}' is not one of them: train it "
                    "with hnn train {}",
                    fmt::join(paper, ", "), task, task);
    for (const nn::ModelKind model : kModels) {
      for (int seed = 0; seed < o.seeds; ++seed) {
        RunOptions r{.task = task,
                     .model = model,
                     .seed = std::uint64_t(seed),
                     .dtype = o.dtype,
                     .preset = o.preset,
                     .threads = std::max(1, int(std::thread::hardware_concurrency()) / o.jobs),
                     .steps = o.steps,
                     .out = run_dir(o, task, model, seed),
                     .force = true,  // OUT's runs are reproduce's own: run again, replaced
                     .quiet = true};
        validate(r);
        runs.push_back(r);
      }
    }
  }
  return runs;
}

// The paper's row of each (task, model) of `runs` (seeds runs each), from the peers file.
std::vector<PaperRow> paper_rows(const std::vector<RunOptions>& runs, int seeds) {
  const json published = read_published(published_path());
  std::vector<PaperRow> rows;
  for (std::size_t i = 0; i < runs.size(); i += std::size_t(seeds))
    rows.push_back(paper_row(published, runs[i].task, runs[i].model));
  return rows;
}

// table1.json: one row per task and model, the seeds' results averaged.
json table_of(const std::vector<PaperRow>& papers, const std::vector<json>& results, int seeds) {
  json table = json::array();
  for (std::size_t i = 0; i < papers.size(); ++i) {
    const auto first = results.begin() + long(i) * seeds;
    table.push_back(table_row(papers[i], std::vector<json>(first, first + seeds)));
  }
  return table;
}

}  // namespace

json reproduce(const ReproduceOptions& o) {
  HNN_TASKS_CHECK(o.seeds >= 1, "--seeds must be at least 1, got {}", o.seeds);
  HNN_TASKS_CHECK(o.jobs >= 1, "--jobs must be at least 1, got {}", o.jobs);
  const std::vector<std::string> tasks = o.tasks.empty() ? paper_task_names() : o.tasks;
  const std::vector<RunOptions> runs = plan_runs(o, tasks);
  const std::vector<PaperRow> papers = paper_rows(runs, o.seeds);  // a bad peers file: no run
  fs::create_directories(o.out);
  fmt::print(stderr, "reproduce: {} runs on {} thread(s) into {}\n", runs.size(), o.jobs,
             o.out.string());
  const auto start = std::chrono::steady_clock::now();
  const std::vector<json> results = run_all(runs, o.jobs);
  const double wall =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const json table = table_of(papers, results, o.seeds);
  nn::write_file_atomic(o.out / "table1.json", table.dump(2) + "\n");
  nn::write_file_atomic(o.out / "table1.md", table1_markdown(table, wall, table_notes(tasks)));
  // What the HNN makes possible: the tasks' comparison figures, and reversibility on every run.
  for (const std::string& task : tasks) {
    if (!make_task(task)->has_comparison()) continue;
    const LoadedRun baseline = load_run(run_dir(o, task, nn::ModelKind::kBaseline, 0));
    const LoadedRun hnn = load_run(run_dir(o, task, nn::ModelKind::kHnn, 0));
    baseline.task->write_comparison(*baseline.run, *hnn.run, o.out / task);
  }
  if (o.reversibility) reversibility_report(o.out);
  return table;
}

json reversibility_report(const fs::path& results, const ReversibilityOptions& options) {
  json rows = json::array();
  for (const std::string& task : paper_task_names()) {
    for (const nn::ModelKind model : kModels) {
      fs::path dir = results / task / std::string(nn::to_string(model));
      if (!fs::exists(dir / "metrics.json")) dir /= "seed-0";
      if (fs::exists(dir / "metrics.json")) rows.push_back(reversibility(dir, options));
    }
  }
  nn::write_file_atomic(results / "reversibility.json", rows.dump(2) + "\n");
  nn::write_file_atomic(results / "reversibility.md", reversibility_markdown(rows));
  return rows;
}

}  // namespace hnn::tasks
