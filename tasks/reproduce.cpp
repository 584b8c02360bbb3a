#include "tasks/reproduce.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <map>
#include <mutex>
#include <thread>

#include "tasks/files.h"
#include "tasks/pixel_pendulum.h"
#include "tasks/reversibility.h"
#include "tasks/run.h"
#include "tasks/task.h"
#include "tasks/task_library.h"

namespace hnn::tasks {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

const char* const kModels[] = {"baseline", "hnn"};
const char* const kAveraged[] = {"train_loss", "train_loss_se", "test_loss",     "test_loss_se",
                                 "energy_mse", "energy_mse_se", "train_seconds", "eval_seconds"};

fs::path run_dir(const ReproduceOptions& o, const std::string& task, const std::string& model,
                 int seed) {
  const fs::path dir = o.out / task / model;
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
            runs[i].task, runs[i].model, runs[i].seed,
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
json table_row(const Task& task, const std::string& model, const std::vector<json>& seeds) {
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
  const PaperRow paper = task.paper(model);
  row["paper_train_loss"] = paper.train_loss.mean;
  row["paper_train_loss_se"] = paper.train_loss.se;
  row["paper_test_loss"] = paper.test_loss.mean;
  row["paper_test_loss_se"] = paper.test_loss.se;
  row["paper_energy_mse"] = paper.energy_mse.mean;
  row["paper_energy_mse_se"] = paper.energy_mse.se;
  return row;
}

std::string value_se(const json& row, const std::string& key) {
  const json& v = row[key];
  const json& se = row[key + "_se"];
  if (!v.is_number()) return "n/a";
  if (!se.is_number()) return fmt::format("{:.4e}", v.get<double>());
  return fmt::format("{:.4e} ± {:.1e}", v.get<double>(), se.get<double>());
}

// ", lean 32-32" after a lean run's dtype; nothing for the paper's widths.
std::string widths_note(const json& row) {
  if (row.value("preset", "paper") == "paper") return "";
  return fmt::format(", {} {}", row["preset"].get<std::string>(), row.value("hidden", "?"));
}

}  // namespace

std::string table1_markdown(const json& rows, double wall_seconds) {
  std::map<std::string, std::map<std::string, json>> by_task;
  std::vector<std::string> order;
  for (const json& r : rows) {
    const std::string task = r["task"];
    if (!by_task.count(task)) order.push_back(task);
    by_task[task][r["model"].get<std::string>()] = r;
  }
  std::string md = fmt::format(
      "# Table 1, reproduced\n\n"
      "Mean ± standard error, baseline / HNN, in the paper's units (not rescaled); for each "
      "task, our row and then the paper's (*paper*). Losses: mean squared error of dx/dt "
      "over the whole split; energy: MSE between the true energy along true and learned rollouts "
      "(adaptive RK45, rtol 1e-9).\n\n"
      "| task | source | train loss (baseline / HNN) | test loss (baseline / HNN) | energy MSE "
      "(baseline / HNN) | train time (baseline / HNN) |\n"
      "| --- | --- | --- | --- | --- | --- |\n");
  for (const std::string& task : order) {
    const json& b = by_task[task]["baseline"];
    const json& h = by_task[task]["hnn"];
    if (b.is_null() || h.is_null()) continue;
    const auto both = [&](const std::string& key) {
      return value_se(b, key) + " / " + value_se(h, key);
    };
    md += fmt::format("| {} | ours ({} steps, {}{}) | {} | {} | {} | {:.1f} s / {:.1f} s |\n", task,
                      h["steps"].get<int>(), h["dtype"].get<std::string>(), widths_note(h),
                      both("train_loss"), both("test_loss"), both("energy_mse"),
                      b["train_seconds"].get<double>(), h["train_seconds"].get<double>());
    md += fmt::format("| | *paper* | {} | {} | {} | |\n", both("paper_train_loss"),
                      both("paper_test_loss"), both("paper_energy_mse"));
  }
  if (by_task.count(pixel::kTaskName)) {
    md +=
        "\nPixel pendulum: losses are the combined ae + cc + 0.1 hnn per frame pair; energy MSE "
        "is between the true Gym state's energy and the energy of the angle and velocity "
        "recovered from the decoded frames of 200-frame latent rollouts (dopri5) from the test "
        "trials (see energy_mse_frames_floor in its metrics.json for the recovery's own error).\n";
  }
  md += fmt::format("\nWall time of the whole reproduction: {:.1f} s.\n", wall_seconds);
  return md;
}

json reproduce(const ReproduceOptions& o) {
  HNN_TASKS_CHECK(o.seeds >= 1, "--seeds must be at least 1, got {}", o.seeds);
  HNN_TASKS_CHECK(o.jobs >= 1, "--jobs must be at least 1, got {}", o.jobs);
  const std::vector<std::string> tasks = o.tasks.empty() ? task_names() : o.tasks;
  std::vector<RunOptions> runs;
  for (const std::string& task : tasks) {
    make_task(task);  // fail on a bad name before any work
    for (const char* model : kModels) {
      for (int seed = 0; seed < o.seeds; ++seed) {
        RunOptions r;
        r.task = task;
        r.model = model;
        r.seed = std::uint64_t(seed);
        r.dtype = o.dtype;
        r.preset = o.preset;
        r.steps = o.steps;
        r.threads = std::max(1, int(std::thread::hardware_concurrency()) / o.jobs);
        r.out = run_dir(o, task, model, seed);
        r.quiet = true;
        runs.push_back(r);
      }
    }
  }
  fs::create_directories(o.out);
  fmt::print(stderr, "reproduce: {} runs on {} thread(s) into {}\n", runs.size(), o.jobs,
             o.out.string());
  const auto start = std::chrono::steady_clock::now();
  const std::vector<json> results = run_all(runs, o.jobs);
  const double wall =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  json table = json::array();
  for (std::size_t i = 0; i < runs.size(); i += std::size_t(o.seeds)) {
    const std::vector<json> seeds(results.begin() + long(i), results.begin() + long(i) + o.seeds);
    table.push_back(table_row(*make_task(runs[i].task), runs[i].model, seeds));
  }
  write_file_atomic(o.out / "table1.json", table.dump(2) + "\n");
  write_file_atomic(o.out / "table1.md", table1_markdown(table, wall));
  // What the HNN makes possible: Figure 4's animation, and reversibility on every run.
  if (std::find(tasks.begin(), tasks.end(), pixel::kTaskName) != tasks.end()) {
    pixel::write_comparison(run_dir(o, pixel::kTaskName, "baseline", 0),
                            run_dir(o, pixel::kTaskName, "hnn", 0), o.out / pixel::kTaskName);
  }
  if (o.reversibility) reversibility_report(o.out);
  return table;
}

}  // namespace hnn::tasks
