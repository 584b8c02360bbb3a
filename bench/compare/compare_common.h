#pragma once
// What hnn_train_step.cpp and libtorch_step.cpp share (torch_step.py mirrors it): options, the
// raw float64 data files, the batch index stream, and the step timer. Standard library and
// nlohmann/json only, so that the LibTorch program builds without hnn.
//
// Note [Same computation]: the three programs start from hnn's initial parameters (written by
// --save-init, read by --init), train on the same data file, and draw minibatch rows from the
// same splitmix64 stream (BatchIndices), so their final losses agree up to rounding.
//
// Note [Rollout windows]: the rollout loss (--loss rollout, spring and chain2) trains on
// windows of horizon + 1 consecutive states of one trajectory: the data file's splits hold
// trajectories one after the other (the spring's 30 points over t in [0, 3]; chain2's chunks of
// 5 points 0.03 apart, Finzi et al.'s), and a window's rows are its start, the horizon states
// after it and each step's length. Both sides build the windows in the same order and draw
// window indices from BatchIndices.

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <vector>

namespace hnn::compare {

/// Command-line options of hnn_train_step and libtorch_step (torch_step.py has the same).
struct Options {
  std::string task =
      "spring";               // spring | twobody | threebody | pixel | realpend | dblpend | chain2
  std::string model = "hnn";  // hnn | baseline | dhnn | lnn | chnn
  std::string dtype = "float32";
  std::vector<long> hidden;             // hidden widths; empty: 200-200 (the HNN paper's)
  std::string activation = "tanh";      // nn::Activation's names (tanh, softplus, ...)
  std::string loss = "field";           // field: MSE of dx/dt; rollout: Note [Rollout windows]
  int horizon = 4;                      // rollout: steps per window
  std::string integrator = "leapfrog";  // rollout: the step, leapfrog or rk4
  std::string norm = "l2";              // rollout: l2 (mean squared) or l1 (mean absolute error)
  std::string optimizer = "adam";       // adam (L2 in the gradient) or adamw (decoupled)
  int threads = 1;
  int steps = -1;   // default per task (task_defaults)
  int warmup = -1;  // untimed steps; default steps / 10
  int window = -1;  // steps per timed window; default (steps - warmup) / 20
  int batch = -1;   // rows per step; 0: full batch
  std::uint64_t seed = 0;
  double lr = -1;                    // default 1e-3 (realpend: 5e-3)
  double weight_decay = -1;          // default 1e-4 (pixel: 1e-5 on the autoencoder)
  double dynamics_weight_decay = 0;  // pixel only: the latent model's L2 (PixelConfig's)
  std::string data, save_data, init, save_init;
  long n_train = -1, n_test = -1;  // rows of the data file's splits (spring: 750, 750)
  int pixel_trials = 20;           // frames of the pixel data: trials x 103
  std::string fma_peak;            // hnn_train_step: float32|float64: print the FMA peak, exit
};

/// The state size of a task's model input.
inline long task_dim(const std::string& task) {
  if (task == "spring") return 2;
  if (task == "twobody") return 8;
  if (task == "threebody") return 12;
  if (task == "pixel") return 2 * 28 * 28;
  if (task == "realpend") return 2;
  if (task == "dblpend") return 4;
  if (task == "chain2") return 8;  // two points in the plane: positions, then velocities
  throw std::invalid_argument("unknown task '" + task +
                              "' (spring, twobody, threebody, pixel, realpend, dblpend, chain2)");
}

/// hnn's name of a task (tasks::make_task).
inline std::string task_name(const std::string& task) {
  if (task == "twobody") return "two-body";
  if (task == "threebody") return "three-body";
  if (task == "pixel") return "pixel-pendulum";
  if (task == "realpend") return "real-pendulum";
  if (task == "dblpend") return "double-pendulum";
  if (task == "chain2") return "chain-pendulum-2";
  return task;
}

/// The trajectories of a rollout task's data file (Note [Rollout windows]): points each, over
/// [0, t_end].
struct Stretches {
  long points;
  double t_end;
};
inline Stretches rollout_stretches(const std::string& task) {
  if (task == "chain2") return {5, 4 * 0.03};  // the peer's chunks: 4 steps of ChainPendulum's dt
  return {30, 3.0};                            // the spring task's trajectories
}

/// "256,256" -> {256, 256}.
inline std::vector<long> parse_widths(const std::string& text) {
  std::vector<long> widths;
  for (std::size_t start = 0; start <= text.size();) {
    const std::size_t end = std::min(text.find(',', start), text.size());
    widths.push_back(std::stol(text.substr(start, end - start)));
    if (widths.back() < 1) throw std::invalid_argument("--hidden widths must be >= 1: " + text);
    start = end + 1;
  }
  return widths;
}

/// The checks of task_defaults that concern the model and the loss.
inline void check_model(const Options& o) {
  if (o.model != "hnn" && o.model != "baseline" && o.model != "dhnn" && o.model != "lnn" &&
      o.model != "chnn")
    throw std::invalid_argument("--model must be hnn, baseline, dhnn, lnn or chnn");
  if ((o.model == "chnn") != (o.task == "chain2"))
    throw std::invalid_argument("--model chnn is chain2's model, and chain2 trains only it");
  if (o.dtype != "float32" && o.dtype != "float64")
    throw std::invalid_argument("--dtype must be float32 or float64");
  if (o.loss != "field" && o.loss != "rollout")
    throw std::invalid_argument("--loss must be field or rollout");
  const bool rollout_task = o.task == "spring" || o.task == "chain2";
  if (o.loss == "rollout" &&
      (!rollout_task || o.horizon < 1 || o.horizon >= rollout_stretches(o.task).points))
    throw std::invalid_argument(
        "--loss rollout runs on spring (horizon 1..29) and chain2 (horizon 1..4)");
  if (o.task == "chain2" && o.loss != "rollout")
    throw std::invalid_argument("chain2 trains with --loss rollout (Finzi et al.'s chunks)");
  if (o.integrator != "leapfrog" && o.integrator != "rk4")
    throw std::invalid_argument("--integrator must be leapfrog or rk4");
  if (o.norm != "l2" && o.norm != "l1") throw std::invalid_argument("--norm must be l2 or l1");
  if (o.optimizer != "adam" && o.optimizer != "adamw")
    throw std::invalid_argument("--optimizer must be adam or adamw");
  if ((o.model == "lnn" || o.model == "dhnn") && o.task == "pixel")
    throw std::invalid_argument("the pixel task trains an hnn or a baseline");
}

/// Fills the per-task defaults: the batches of the paper's tasks, steps short enough for a
/// comparison run (spring: the full 2000, so the losses match the reference's).
inline void task_defaults(Options& o) {
  task_dim(o.task);
  check_model(o);
  const bool spring = o.task == "spring", pixel = o.task == "pixel";
  // The peers' protocols: D-HNN (realpend) batch 128 at 5e-3, LNN (dblpend) batch 512, neither
  // with weight decay; the rollout loss batch 128.
  const bool peer = o.task == "realpend" || o.task == "dblpend";
  if (o.batch < 0) {
    o.batch = o.task == "realpend" || o.loss == "rollout" ? 128
              : o.task == "dblpend"                       ? 512
              : spring                                    ? 0
              : o.task == "threebody"                     ? 600
                                                          : 200;
  }
  if (o.steps < 0) o.steps = spring ? 2000 : o.task == "twobody" ? 2000 : pixel ? 300 : 1000;
  if (o.lr < 0) o.lr = o.task == "realpend" ? 5e-3 : 1e-3;
  if (o.weight_decay < 0) o.weight_decay = peer ? 0 : pixel ? 1e-5 : 1e-4;
  if (o.warmup < 0) o.warmup = std::max(1, o.steps / 10);
  if (o.window < 0) o.window = std::max(1, (o.steps - o.warmup) / 20);
  if (spring && o.n_train < 0) o.n_train = o.n_test = 750;
  if (o.steps < 1 || o.warmup >= o.steps) throw std::invalid_argument("need steps > warmup >= 0");
  if (o.threads < 1) throw std::invalid_argument("--threads must be >= 1");
}

inline Options parse_options(int argc, char** argv, const char* program) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string key = argv[i];
    if (key == "--help" || key == "-h") {
      std::printf(
          "%s --task spring|twobody|threebody|pixel|realpend|dblpend|chain2\n"
          "  --model hnn|baseline|dhnn|lnn|chnn --dtype float32|float64 [--hidden W,W,...]\n"
          "  [--activation tanh|softplus|...] [--loss field|rollout --horizon K\n"
          "  --integrator leapfrog|rk4 --norm l2|l1] [--threads N] [--steps N] [--warmup N]\n"
          "  [--window N] [--batch N] [--seed N] [--optimizer adam|adamw]\n"
          "  [--lr X] [--weight-decay X] [--dynamics-weight-decay X] [--pixel-trials N]\n"
          "  [--data FILE --n-train N --n-test N] [--save-data FILE] [--init FILE]\n"
          "  [--save-init FILE] [--fma-peak float32|float64]\nPrints one JSON line: ms_per_step "
          "(median over windows), train_loss, test_loss (--fma-peak: the machine's FMA peak on\n"
          "--threads threads instead).\n",
          program);
      std::exit(0);
    }
    if (i + 1 >= argc) throw std::invalid_argument("missing value for " + key);
    const std::string v = argv[++i];
    if (key == "--task")
      o.task = v;
    else if (key == "--model")
      o.model = v;
    else if (key == "--dtype")
      o.dtype = v;
    else if (key == "--hidden")
      o.hidden = parse_widths(v);
    else if (key == "--activation")
      o.activation = v;
    else if (key == "--loss")
      o.loss = v;
    else if (key == "--horizon")
      o.horizon = std::stoi(v);
    else if (key == "--integrator")
      o.integrator = v;
    else if (key == "--norm")
      o.norm = v;
    else if (key == "--optimizer")
      o.optimizer = v;
    else if (key == "--threads")
      o.threads = std::stoi(v);
    else if (key == "--steps")
      o.steps = std::stoi(v);
    else if (key == "--warmup")
      o.warmup = std::stoi(v);
    else if (key == "--window")
      o.window = std::stoi(v);
    else if (key == "--batch")
      o.batch = std::stoi(v);
    else if (key == "--seed")
      o.seed = std::stoull(v);
    else if (key == "--lr")
      o.lr = std::stod(v);
    else if (key == "--weight-decay")
      o.weight_decay = std::stod(v);
    else if (key == "--dynamics-weight-decay")
      o.dynamics_weight_decay = std::stod(v);
    else if (key == "--data")
      o.data = v;
    else if (key == "--save-data")
      o.save_data = v;
    else if (key == "--init")
      o.init = v;
    else if (key == "--save-init")
      o.save_init = v;
    else if (key == "--n-train")
      o.n_train = std::stol(v);
    else if (key == "--n-test")
      o.n_test = std::stol(v);
    else if (key == "--pixel-trials")
      o.pixel_trials = std::stoi(v);
    else if (key == "--fma-peak")
      o.fma_peak = v;
    else
      throw std::invalid_argument("unknown option " + key + " (see --help)");
  }
  task_defaults(o);
  return o;
}

/// A row-major table of doubles.
struct Rows {
  long rows = 0, cols = 0;
  std::vector<double> values;
  const double* row(long i) const { return values.data() + i * cols; }
};

/// A task's splits: x and its target (dx/dt; for the pixel task, the next pair of frames).
struct Data {
  Rows train_x, train_dx, test_x, test_dx;
};

inline void write_rows(std::ofstream& out, const Rows& r) {
  out.write(reinterpret_cast<const char*>(r.values.data()),
            std::streamsize(r.values.size() * sizeof(double)));
}

/// The reference's raw format: little-endian float64, train_x, train_dx, test_x, test_dx, each
/// rows x dim, no header (sizes from --n-train, --n-test and the task's dim).
inline void save_data(const Data& d, const std::string& path) {
  std::ofstream out(path, std::ios::binary);
  for (const Rows* r : {&d.train_x, &d.train_dx, &d.test_x, &d.test_dx}) write_rows(out, *r);
  if (!out) throw std::runtime_error("cannot write " + path);
}

inline Data load_data(const Options& o) {
  if (o.n_train < 1 || o.n_test < 1)
    throw std::invalid_argument("--data needs --n-train and --n-test for task " + o.task);
  std::ifstream in(o.data, std::ios::binary | std::ios::ate);
  if (!in) throw std::runtime_error("cannot open " + o.data);
  const long dim = task_dim(o.task);
  const auto expected = std::streamoff(2 * (o.n_train + o.n_test) * dim * 8);
  if (in.tellg() != expected) {
    throw std::runtime_error(o.data + " has " + std::to_string(in.tellg()) + " bytes, expected " +
                             std::to_string(expected) + " for these --n-train/--n-test");
  }
  in.seekg(0);
  const auto read = [&](long n) {
    Rows r{n, dim, std::vector<double>(std::size_t(n * dim))};
    in.read(reinterpret_cast<char*>(r.values.data()), std::streamsize(n * dim * 8));
    return r;
  };
  Data d;
  d.train_x = read(o.n_train);
  d.train_dx = read(o.n_train);
  d.test_x = read(o.n_test);
  d.test_dx = read(o.n_test);
  if (!in) throw std::runtime_error("short read from " + o.data);
  return d;
}

/// Row indices in [0, n): splitmix64 from `seed`, index = z mod n. torch_step.py computes the
/// same stream with numpy (k-th draw from state seed + k * golden).
class BatchIndices {
 public:
  BatchIndices(std::uint64_t seed, long n) : state_(seed), n_(std::uint64_t(n)) {}
  long next() {
    state_ += 0x9E3779B97F4A7C15ULL;
    std::uint64_t z = state_;
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return long((z ^ (z >> 31)) % n_);
  }

 private:
  std::uint64_t state_, n_;
};

/// Times a training loop: `warmup` steps untimed, then windows of `window` steps; the figure is
/// the median of the windows' ms/step (robust to another process taking a core for a while).
class StepTimer {
 public:
  StepTimer(int steps, int warmup, int window)
      : steps_(steps), warmup_(warmup), window_(window), start_(Clock::now()), mark_(start_) {}

  /// Call after each step with the number of steps done.
  void tick(int done) {
    if (done < warmup_) return;
    const Clock::time_point now = Clock::now();
    if (done == warmup_) {
      timed_start_ = mark_ = now;
    } else if ((done - warmup_) % window_ == 0) {
      windows_.push_back(ms(now - mark_) / window_);
      mark_ = now;
    }
    if (done == steps_) end_ = now;
  }

  nlohmann::json to_json() const {
    std::vector<double> w = windows_;
    std::sort(w.begin(), w.end());
    const double median =
        w.empty()
            ? 0
            : (w.size() % 2 ? w[w.size() / 2] : 0.5 * (w[w.size() / 2 - 1] + w[w.size() / 2]));
    return {{"ms_per_step", median},
            {"ms_mean", ms(end_ - timed_start_) / (steps_ - warmup_)},
            {"ms_min", w.empty() ? 0 : w.front()},
            {"windows", w.size()},
            {"wall_s", ms(end_ - start_) / 1e3}};
  }

 private:
  using Clock = std::chrono::steady_clock;
  static double ms(Clock::duration d) {
    return std::chrono::duration<double, std::milli>(d).count();
  }

  int steps_, warmup_, window_;
  Clock::time_point start_, mark_, timed_start_, end_;
  std::vector<double> windows_;
};

/// The fields every program reports besides the timings and losses.
inline void add_run_fields(nlohmann::json& j, const Options& o, const std::string& impl,
                           const Data& d) {
  j["impl"] = impl;
  j["task"] = o.task;
  j["model"] = o.model;
  j["dtype"] = o.dtype;
  j["hidden"] = o.hidden.empty() ? std::vector<long>{200, 200} : o.hidden;
  j["activation"] = o.activation;
  j["loss"] = o.loss;
  if (o.loss == "rollout") {
    j["horizon"] = o.horizon;
    j["integrator"] = o.integrator;
    j["norm"] = o.norm;
  }
  j["optimizer"] = o.optimizer;
  j["threads"] = o.threads;
  j["steps"] = o.steps;
  j["warmup"] = o.warmup;
  j["window"] = o.window;
  j["batch"] = o.batch == 0 ? d.train_x.rows : o.batch;
  j["n_train"] = d.train_x.rows;
  j["n_test"] = d.test_x.rows;
  j["init"] = o.init.empty() ? (impl == "hnn" ? "own" : "own (torch orthogonal_)") : o.init;
}

}  // namespace hnn::compare
